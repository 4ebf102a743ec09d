//! The bake plan (docs/design.md §5.4): before any work, decide what the scene needs and say what
//! is left out. The plan is printed, stored in the cache, and drives the bake.

use crate::bsdf::Bsdf;
use crate::scene::{LightKind, Scene};
use crate::spectrum::Rgb;
use crate::surfels::radiance::map_levels;
use glam::Vec2;
use serde_json::{json, Value};

fn model(bsdf: &Bsdf) -> &'static str {
    match bsdf {
        Bsdf::Diffuse(_) => "diffuse",
        Bsdf::Conductor(_) => "roughconductor",
        Bsdf::Dielectric(_) => "roughdielectric",
        Bsdf::ThinDielectric(_) => "thin dielectric",
    }
}

/// What the bake of a scene will compute.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// Resolution of the tree's directional maps: the finest any material needs, and 3 (8²,
    /// enough for the cosine lobes of diffuse surfels) at least.
    pub map_levels: u32,
    /// The plan as the cache records it and `wpbgi bake` prints it.
    pub json: Value,
}

/// How far two ratios of emitter radiance (two chromaticities, two factors of an edit) may
/// differ, relatively, and count as one: float rounding of the products that made them.
pub(crate) const SAME_RATIO: f32 = 1e-6;

/// Whether a bake of `scene` makes the same choices when every emitter's radiance is
/// multiplied by one colour (not only a grey factor): every emitter untextured and of one
/// colour, and no light tree (`lightcuts`). The bake picks emitters by luminous power and cuts
/// light trees on bounds of it; a shared colour factor scales every emitter's power alike only
/// then. What `wpbgi relight` may rescale (`super::relight`).
pub(crate) fn recolourable(scene: &Scene, lightcuts: bool) -> bool {
    let mut colours = Vec::new();
    for m in &scene.materials {
        if let Some(e) = &m.emission {
            if e.texture.is_some() {
                return false;
            }
            colours.push(e.radiance);
        }
    }
    colours.extend(scene.lights.iter().map(|l| l.intensity));
    if let Some(env) = &scene.environment {
        if env.map.is_some() {
            return false;
        }
        colours.push(env.scale);
    }
    let chroma: Vec<Rgb> = colours
        .into_iter()
        .filter(|c| c.element_sum() > 0.0)
        .map(|c| c / c.element_sum())
        .collect();
    !lightcuts
        && chroma
            .windows(2)
            .all(|w| (w[0] - w[1]).abs().max_element() <= SAME_RATIO)
}

impl Plan {
    /// Record what `wpbgi relight` can change in a cache of this bake without baking again
    /// (`lightcuts`: whether the bake cuts a light tree).
    pub(crate) fn note_relight(&mut self, scene: &Scene, lightcuts: bool) {
        let scale = if recolourable(scene, lightcuts) {
            "every emitter's emission or intensity by one factor, grey or coloured"
        } else {
            "every emitter's emission or intensity by one grey factor (its emitters differ in \
             colour or texture, or it cuts a light tree)"
        };
        self.json["relight"] = json!({
            "rescales": scale,
            "bakes_again": "any other edit: reflectance, tints, transmittance, roughness, one \
                            emitter alone",
        });
    }

    /// Record the bounce settings: `bounces` 0 leaves indirect light out.
    pub fn note_bounces(&mut self, bounces: &crate::bake::bounce::BounceSettings) {
        if bounces.max == 0 {
            if let Some(l) = self.json["left_out"].as_array_mut() {
                l.push("indirect bounces: this bake computes direct light only".into());
            }
        } else {
            self.json["bounces"] = if bounces.tolerance > 0.0 {
                format!(
                    "until a bounce adds less than {} of the light, at most {}",
                    bounces.tolerance, bounces.max
                )
            } else {
                format!("exactly {}", bounces.max)
            }
            .into();
        }
    }

    /// Analyse `scene` (the materials its meshes use). Materials are classified by their BSDF
    /// at texture coordinate (0, 0); each surfel then takes the resolution of its own BSDF, so
    /// textured roughness is honoured.
    pub fn new(scene: &Scene) -> Plan {
        let mut finest = 3;
        let mut transmission = false;
        let mut materials = Vec::new();
        let used = |i: usize| scene.meshes.iter().any(|m| m.material == i);
        for m in (0..scene.materials.len())
            .filter(|&i| used(i))
            .map(|i| &scene.materials[i])
        {
            let bsdf = m.bsdf_at(&scene.textures, Vec2::ZERO);
            let levels = map_levels(&bsdf);
            if let Some(l) = levels {
                finest = finest.max(l);
            }
            transmission |= bsdf.is_two_sided();
            let storage = match levels {
                None => "RGB".to_string(),
                Some(l) => format!("directional {0}x{0}", 1u32 << l),
            };
            materials.push(json!({
                "name": m.name,
                "model": model(&bsdf),
                "storage": storage,
                "emissive": m.emission.is_some(),
            }));
        }
        let count = |k: fn(&LightKind) -> bool| scene.lights.iter().filter(|l| k(&l.kind)).count();
        let emissive_triangles: usize = scene
            .meshes
            .iter()
            .filter(|m| scene.emits(m))
            .map(|m| m.triangles.len())
            .sum();
        let emitters = json!({
            "emissive_triangles": emissive_triangles,
            "point": count(|k| matches!(k, LightKind::Point)),
            "spot": count(|k| matches!(k, LightKind::Spot { .. })),
            "directional": count(|k| matches!(k, LightKind::Directional)),
            "environment": scene.environment.is_some(),
        });
        let mut left_out = Vec::new();
        if materials.iter().all(|m| m["storage"] == "RGB") {
            left_out.push("wavelet radiance per surfel: every material is diffuse (RGB only)");
        }
        if !transmission {
            left_out.push("two-hemisphere functions: nothing transmits");
        }
        if scene.lights.is_empty() {
            left_out.push("punctual and directional lights: the scene has none");
        }
        if scene.environment.is_none() {
            left_out.push("environment lighting: the scene has no environment");
        }
        if emissive_triangles == 0 {
            left_out.push("emitting surfels: no surface emits");
        }
        let json = json!({
            "map_resolution": 1u32 << finest,
            "transmission": transmission,
            "materials": materials,
            "emitters": emitters,
            "left_out": left_out,
        });
        Plan {
            map_levels: finest,
            json,
        }
    }
}

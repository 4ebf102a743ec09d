//! Sampling of every emitter in a scene for next-event estimation: emissive triangles (uniform
//! by area within a triangle), punctual lights and the environment (by its radiance, see
//! [`crate::scene::environment`]), chosen with probability proportional to their power. Kinds
//! the scene does not have cost nothing. Estimators of many samples at one point take the
//! delta lights apart, each once and exactly ([`Draw::WithoutDelta`]). Where the emitters are
//! a few triangles of constant radiance, their unshadowed irradiance also in closed form
//! ([`ClosedFormLight`]).

use crate::accel::{Accel, Segment, TriangleId};
use crate::geometry::offset::{interpolate_with_error, offset_origin, SHADOW_EPSILON};
use crate::geometry::polygon_irradiance::projected_solid_angle;
use crate::geometry::spherical_triangle::SphericalTriangle;
use crate::geometry::warp::square_to_uniform_triangle;
use crate::scene::environment::EnvironmentSampler;
use crate::scene::{LightKind, Mesh, PunctualLight, Scene};
use crate::spectrum::{luminance, Rgb};
use glam::{Vec2, Vec3, Vec3A};

/// Where an emitter sample lies and what it delivers.
#[derive(Clone, Copy, Debug)]
pub struct EmitterSample {
    /// Unit direction from the shading point towards the emitter.
    pub wi: Vec3,
    /// Distance to the emitter point (infinite for directional lights and the environment).
    pub dist: f32,
    /// Emitted radiance (area) or intensity/irradiance terms, divided by the sampling density
    /// and multiplied by the geometry term: the value to multiply with the BSDF.
    pub value: Rgb,
    /// Solid-angle density of this sample, emitter selection included (0 for delta lights).
    pub pdf: f32,
    /// Whether the emitter is a delta light (point, spot, directional), which BSDF sampling
    /// cannot hit.
    pub delta: bool,
    /// For area emitters: the point and its rounding bound and geometric normal (for the
    /// shadow ray's far end).
    pub point: Vec3,
    /// See `point`.
    pub point_err: Vec3,
    /// See `point`.
    pub normal: Vec3,
}

impl EmitterSample {
    /// Whether nothing blocks the segment from `origin` (already offset off its surface,
    /// triangle `leaving` where the caller knows it) to the sampled point, whose own end is
    /// offset off the emitter the same way.
    pub(crate) fn visible_from(
        &self,
        accel: &Accel,
        leaving: Option<TriangleId>,
        origin: Vec3,
    ) -> bool {
        let s = self.shadow_segment(origin);
        !accel.occluded_leaving(leaving, s.origin, s.dir, s.tmin, s.tmax)
    }

    /// The segment [`EmitterSample::visible_from`] tests: to the sampled point, its end offset
    /// off the emitter, or along the direction without end for an environment.
    pub(crate) fn shadow_segment(&self, origin: Vec3) -> Segment {
        if !self.dist.is_finite() {
            return Segment {
                origin,
                dir: self.wi,
                tmin: 0.0,
                tmax: f32::INFINITY,
            };
        }
        let target = if self.delta {
            self.point
        } else {
            Vec3::from(offset_origin(
                Vec3A::from(self.point),
                Vec3A::from(self.point_err),
                Vec3A::from(self.normal),
                Vec3A::from(origin - self.point),
            ))
        };
        Segment {
            origin,
            dir: target - origin,
            tmin: 0.0,
            tmax: 1.0 - SHADOW_EPSILON,
        }
    }
}

/// The probability that entry `i` of the cumulative weights `cdf` is drawn.
fn selection_probability(cdf: &[f64], i: usize) -> f32 {
    let total = *cdf.last().unwrap_or(&1.0);
    let prev = if i == 0 { 0.0 } else { cdf[i - 1] };
    ((cdf[i] - prev) / total) as f32
}

/// An emitting triangle, with what sampling it needs kept at hand: its vertices, unit
/// geometric normal, selection probability and material are found once here rather than once
/// a sample (the render draws 16–32 samples at every hit: emitter sampling went from 5.1 % to
/// 3.9 % of a 512² cbox-diffuse render's perf samples).
struct EmissiveTriangle {
    mesh: u32,
    tri: u32,
    area: f32,
    vertices: [Vec3A; 3],
    normal: Vec3,
    /// The probability that this entry is drawn ([`selection_probability`]).
    selection: f32,
    /// The mesh's material, and whether its emission is textured (only then does a sample
    /// need its texture coordinates).
    material: usize,
    textured: bool,
}

/// The most delta lights that [`Draw::WithoutDelta`] hands over one by one
/// ([`EmitterSampler::delta_lights`]); with more, they are drawn with the other emitters, as
/// [`Draw::All`] draws them. Sixteen: the bake sends more point and spot lights than that
/// through a light tree, and a render's hit then casts at most this many more shadow rays.
pub const EXACT_DELTA_LIGHTS: usize = 16;

/// Which emitters a draw of [`EmitterSampler`] chooses among.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Draw {
    /// Every emitter, by power: the path tracer's next-event estimation, one draw a vertex,
    /// Mitsuba's.
    All,
    /// The emitters other than the delta lights (point, spot, directional), by power, where
    /// there are at most [`EXACT_DELTA_LIGHTS`] of those: [`EmitterSampler::delta_lights`]
    /// gives each of them once instead, exactly. For the estimators that draw many samples at
    /// one point and stratify the choice of emitter over them (the final render's direct
    /// light and the bake's): drawn with the rest, a delta light took either of the two
    /// whole numbers of samples nearest its share of them, each sample bringing the same
    /// light, and its light came out a few percent too bright or too dark from one pixel or
    /// surfel to the next (a speckle on every surface a point light lit beside an area
    /// light). With more delta lights than that, all are drawn ([`Draw::All`]).
    WithoutDelta,
}

/// Power-proportional emitter selection.
pub struct EmitterSampler {
    tris: Vec<EmissiveTriangle>,
    /// Index of the first emitter entry of each mesh (`u32::MAX` for non-emissive meshes).
    mesh_base: Vec<u32>,
    /// Cumulative selection weights over `tris`, then the scene's punctual lights, then the
    /// environment if any.
    cdf: Vec<f64>,
    environment: Option<EnvironmentSampler>,
    /// Bounding-sphere radius, for the power of directional lights.
    scene_radius: f32,
    /// The emitters' unshadowed light in closed form, where they allow it.
    closed_form: Option<ClosedFormLight>,
    /// The delta lights' summed selection weight (their entries in `cdf` follow `tris`'),
    /// and whether [`Draw::WithoutDelta`] leaves them out.
    delta_weight: f64,
    delta_apart: bool,
}

impl EmitterSampler {
    /// The sampler of every emitter of `scene`: emissive triangles, punctual lights and the
    /// environment.
    pub fn new(scene: &Scene) -> Self {
        Self::with_punctual(scene, true)
    }

    /// Like [`EmitterSampler::new`], leaving out point and spot lights when `point_and_spot`
    /// is false (when a light tree handles them).
    pub fn with_punctual(scene: &Scene, point_and_spot: bool) -> Self {
        let mut tris = Vec::new();
        let mut mesh_base = vec![u32::MAX; scene.meshes.len()];
        let mut weights = Vec::new();
        for (mi, m) in scene.meshes.iter().enumerate() {
            let Some(e) = &scene.materials[m.material].emission else {
                continue;
            };
            mesh_base[mi] = tris.len() as u32;
            let sides = if e.two_sided { 2.0 } else { 1.0 };
            for (ti, t) in m.triangles.iter().enumerate() {
                let p = |i: u32| m.positions[i as usize];
                let area = 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length();
                let vertices = m.corners(ti as u32);
                tris.push(EmissiveTriangle {
                    mesh: mi as u32,
                    tri: ti as u32,
                    area,
                    vertices,
                    normal: Mesh::geometric_normal(vertices),
                    // Set below, once every weight is known.
                    selection: 0.0,
                    material: m.material,
                    textured: e.texture.is_some(),
                });
                weights.push(
                    (area * luminance(e.radiance).max(1e-12) * sides * std::f32::consts::PI) as f64,
                );
            }
        }
        let (lo, hi) = scene.bounds();
        let scene_radius = if lo.is_finite() {
            0.5 * (hi - lo).length()
        } else {
            1.0
        };
        for l in &scene.lights {
            let w = match l.kind {
                LightKind::Directional => {
                    luminance(l.intensity) * std::f32::consts::PI * scene_radius * scene_radius
                }
                _ if !point_and_spot => 0.0,
                _ => luminance(l.intensity) * 4.0 * std::f32::consts::PI,
            };
            weights.push(w.max(0.0) as f64);
        }
        let environment = scene
            .environment
            .as_ref()
            .map(|e| e.sampler())
            .filter(|s| !s.is_black());
        if let Some(s) = &environment {
            // What crosses the scene's disc: π R² × ½ ∫ L dω, with ∫ L dω = 2π² ∫∫ L sin θ du dv.
            let pi = std::f64::consts::PI;
            weights.push(pi * (scene_radius as f64).powi(2) * pi * pi * s.integral());
        }
        let mut acc = 0.0;
        let cdf: Vec<f64> = weights
            .iter()
            .map(|w| {
                acc += w;
                acc
            })
            .collect();
        for (i, t) in tris.iter_mut().enumerate() {
            t.selection = selection_probability(&cdf, i);
        }
        let lights = &weights[tris.len()..tris.len() + scene.lights.len()];
        let delta_count = lights.iter().filter(|&&w| w > 0.0).count();
        EmitterSampler {
            tris,
            mesh_base,
            cdf,
            environment,
            scene_radius,
            closed_form: ClosedFormLight::of(scene),
            delta_weight: lights.iter().sum(),
            delta_apart: (1..=EXACT_DELTA_LIGHTS).contains(&delta_count),
        }
    }

    /// The factor by which `draw` raises the selection probability of an emitter it may draw
    /// (1 for [`Draw::All`]): the delta lights' weight left out of the total.
    fn selection_scale(&self, draw: Draw) -> f32 {
        if draw == Draw::All || !self.delta_apart {
            return 1.0;
        }
        let total = self.cdf.last().copied().unwrap_or(0.0);
        let rest = total - self.delta_weight;
        if rest > 0.0 {
            (total / rest) as f32
        } else {
            0.0
        }
    }

    /// The entry of `cdf` that `u_sel` draws under `draw`: for [`Draw::WithoutDelta`], over
    /// the weights with the delta lights' left out (`None` where nothing else emits).
    fn drawn(&self, u_sel: f32, draw: Draw) -> Option<usize> {
        let total = *self.cdf.last()?;
        let last = self.cdf.len() - 1;
        let pick = |target: f64| self.cdf.partition_point(|&c| c <= target).min(last);
        if draw == Draw::All || !self.delta_apart {
            return Some(pick(u_sel as f64 * total));
        }
        let rest = total - self.delta_weight;
        if !(rest > 0.0) {
            return None;
        }
        let (tris, lights) = (self.tris.len(), self.cdf.len() - self.tris.len());
        let below = if tris == 0 { 0.0 } else { self.cdf[tris - 1] };
        let mut target = u_sel as f64 * rest;
        if target >= below {
            target += self.delta_weight;
        }
        let i = pick(target);
        // Rounding may land on a delta light: the emitter beyond them (the environment), or
        // else the last triangle before them.
        let environment = usize::from(self.environment.is_some());
        Some(if i >= tris && i < tris + lights - environment {
            if environment == 1 {
                last
            } else {
                tris.checked_sub(1)?
            }
        } else {
            i
        })
    }

    /// Under [`Draw::WithoutDelta`], each delta light that it leaves out, as seen from `p`,
    /// exactly (its selection probability taken as 1); nothing under [`Draw::All`] or where
    /// the delta lights are drawn with the rest.
    pub fn delta_lights<'a>(
        &'a self,
        scene: &'a Scene,
        p: Vec3,
        draw: Draw,
    ) -> impl Iterator<Item = EmitterSample> + 'a {
        let apart = draw == Draw::WithoutDelta && self.delta_apart;
        let base = self.tris.len();
        scene
            .lights
            .iter()
            .enumerate()
            .filter(move |&(i, _)| apart && selection_probability(&self.cdf, base + i) > 0.0)
            .filter_map(move |(_, l)| self.light_sample(l, p, 1.0))
    }

    /// The emitters' unshadowed irradiance in closed form, where they are a few triangles of
    /// constant radiance and nothing else emits ([`ClosedFormLight`]).
    pub fn closed_form(&self) -> Option<&ClosedFormLight> {
        self.closed_form.as_ref()
    }

    /// Whether the scene emits nothing.
    pub fn is_empty(&self) -> bool {
        self.cdf.last().is_none_or(|&t| t <= 0.0)
    }

    /// Solid-angle density with which [`EmitterSampler::sample`] under `draw` would pick the
    /// point hit on `(mesh, tri)` at distance `dist` along unit direction `w`, from a surface
    /// with geometric normal `ng` there.
    pub fn pdf_hit(&self, mesh: u32, tri: u32, dist: f32, w: Vec3, ng: Vec3, draw: Draw) -> f32 {
        let base = self
            .mesh_base
            .get(mesh as usize)
            .copied()
            .unwrap_or(u32::MAX);
        if base == u32::MAX {
            return 0.0;
        }
        let i = (base + tri) as usize;
        let cos = w.dot(ng).abs();
        if cos <= 0.0 {
            return 0.0;
        }
        self.tris[i].selection * self.selection_scale(draw) / self.tris[i].area * dist * dist / cos
    }

    /// Solid-angle density with which [`EmitterSampler::sample`] would pick the environment
    /// along world direction `w` (0 without one).
    pub(crate) fn pdf_environment(&self, scene: &Scene, w: Vec3, draw: Draw) -> f32 {
        match (&self.environment, &scene.environment) {
            (Some(s), Some(env)) => {
                selection_probability(&self.cdf, self.cdf.len() - 1)
                    * self.selection_scale(draw)
                    * s.pdf(env, w)
            }
            _ => 0.0,
        }
    }

    /// Sample an emitter as seen from `p`: `u_sel` picks the emitter among those `draw`
    /// takes, `u` the point on it (uniform by area on a triangle, the density
    /// [`EmitterSampler::pdf_hit`] gives under the same `draw`).
    pub fn sample(
        &self,
        scene: &Scene,
        p: Vec3,
        (u_sel, u): (f32, Vec2),
        draw: Draw,
    ) -> Option<EmitterSample> {
        self.sample_with(scene, p, (u_sel, u), false, draw)
    }

    /// Like [`EmitterSampler::sample`], but a triangle that subtends enough solid angle is
    /// sampled uniformly over it ([`SphericalTriangle`]): a bounded estimator for light
    /// sampling on its own. Its densities are not [`EmitterSampler::pdf_hit`]'s, so it does
    /// not serve multiple importance sampling.
    pub(crate) fn sample_solid_angle(
        &self,
        scene: &Scene,
        p: Vec3,
        (u_sel, u): (f32, Vec2),
        draw: Draw,
    ) -> Option<EmitterSample> {
        self.sample_with(scene, p, (u_sel, u), true, draw)
    }

    fn sample_with(
        &self,
        scene: &Scene,
        p: Vec3,
        (u_sel, u): (f32, Vec2),
        by_solid_angle: bool,
        draw: Draw,
    ) -> Option<EmitterSample> {
        if self.is_empty() {
            return None;
        }
        let i = self.drawn(u_sel, draw)?;
        let scale = self.selection_scale(draw);
        if let Some(et) = self.tris.get(i) {
            let sel = et.selection * scale;
            if sel <= 0.0 {
                return None;
            }
            let v = et.vertices;
            let spherical = by_solid_angle
                .then(|| SphericalTriangle::new(p, v.map(Vec3::from)))
                .flatten();
            let b = match &spherical {
                Some(st) => st.sample(u).map(|x| x as f32),
                None => {
                    let bb = square_to_uniform_triangle(u);
                    [1.0 - bb.x - bb.y, bb.x, bb.y]
                }
            };
            let (q, err) = interpolate_with_error(v, b);
            let (q, err) = (Vec3::from(q), Vec3::from(err));
            let ng = et.normal;
            let d = q - p;
            let dist2 = d.length_squared();
            let dist = dist2.sqrt();
            if !(dist > 0.0) {
                return None;
            }
            let wi = d / dist;
            let cos_light = -wi.dot(ng);
            let uv = if et.textured {
                scene.meshes[et.mesh as usize].uv_at(et.tri, b)
            } else {
                Vec2::ZERO
            };
            let le = scene.materials[et.material].emission_at(&scene.textures, uv, cos_light > 0.0);
            if le == Rgb::ZERO || cos_light == 0.0 {
                return None;
            }
            let pdf = match &spherical {
                Some(st) => sel / st.solid_angle() as f32,
                None => sel / et.area * dist2 / cos_light.abs(),
            };
            return Some(EmitterSample {
                wi,
                dist,
                value: le / pdf,
                pdf,
                delta: false,
                point: q,
                point_err: err,
                normal: ng,
            });
        }
        let sel = selection_probability(&self.cdf, i) * scale;
        if sel <= 0.0 {
            return None;
        }
        let Some(l) = scene.lights.get(i - self.tris.len()) else {
            let (sampler, env) = (self.environment.as_ref()?, scene.environment.as_ref()?);
            let (wi, pdf) = sampler.sample(env, u)?;
            let pdf = sel * pdf;
            let le = env.radiance(wi);
            return (le != Rgb::ZERO).then_some(EmitterSample {
                wi,
                dist: f32::INFINITY,
                value: le / pdf,
                pdf,
                delta: false,
                point: p + wi * (4.0 * self.scene_radius),
                point_err: Vec3::ZERO,
                normal: -wi,
            });
        };
        self.light_sample(l, p, sel)
    }

    /// Punctual light `l` as seen from `p`, drawn with probability `sel`.
    fn light_sample(&self, l: &PunctualLight, p: Vec3, sel: f32) -> Option<EmitterSample> {
        match l.kind {
            LightKind::Directional => Some(EmitterSample {
                wi: -l.direction,
                dist: f32::INFINITY,
                value: l.intensity / sel,
                pdf: 0.0,
                delta: true,
                point: p - l.direction * (4.0 * self.scene_radius),
                point_err: Vec3::ZERO,
                normal: l.direction,
            }),
            _ => {
                let d = l.position - p;
                let dist = d.length();
                if !(dist > 0.0) {
                    return None;
                }
                let wi = d / dist;
                let value = l.intensity * l.falloff(-wi) / (dist * dist * sel);
                (value != Rgb::ZERO).then_some(EmitterSample {
                    wi,
                    dist,
                    value,
                    pdf: 0.0,
                    delta: true,
                    point: l.position,
                    point_err: Vec3::ZERO,
                    normal: -wi,
                })
            }
        }
    }
}

/// The most emissive triangles whose light [`ClosedFormLight`] sums in closed form: each costs
/// a clipping and Lambert's formula at every shading point that asks.
pub const CLOSED_FORM_TRIANGLES: usize = 16;

/// How near a point may lie to an emitting triangle's plane, relative to the coordinates'
/// magnitude, and still see it ([`ClosedFormLight::irradiance`]): 25 times the rounding bound
/// of a hit point (γ₇ ≈ 4.2e-7, `geometry::offset`), so that a point on the triangle's own
/// surface is never taken for one above it.
pub const COPLANAR: f32 = 1e-5;

/// The unshadowed irradiance of a scene's emitters in closed form (Lambert's formula), where
/// they are at most [`CLOSED_FORM_TRIANGLES`] triangles of constant radiance and nothing else
/// emits (no texture on the emission, no punctual light, no environment).
pub struct ClosedFormLight {
    tris: Vec<ClosedFormTriangle>,
}

struct ClosedFormTriangle {
    corners: [Vec3; 3],
    /// The front face's unit normal (counter-clockwise winding).
    normal: Vec3,
    /// The largest coordinate magnitude of its corners (for [`COPLANAR`]).
    extent: f32,
    /// Radiance from the front and from the back face.
    front: Rgb,
    back: Rgb,
}

impl ClosedFormLight {
    /// The closed form of `scene`'s emitters, or `None` where they do not allow it.
    pub fn of(scene: &Scene) -> Option<ClosedFormLight> {
        if !scene.lights.is_empty() || scene.environment.is_some() {
            return None;
        }
        let mut tris = Vec::new();
        for m in &scene.meshes {
            let Some(e) = &scene.materials.get(m.material)?.emission else {
                continue;
            };
            if e.texture.is_some() || tris.len() + m.triangles.len() > CLOSED_FORM_TRIANGLES {
                return None;
            }
            for t in &m.triangles {
                let corners = t.map(|i| m.positions[i as usize]);
                let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
                if !(normal.length() > 0.0) {
                    // No area: the emitter samples never pick it either.
                    continue;
                }
                tris.push(ClosedFormTriangle {
                    corners,
                    normal: normal.normalize(),
                    extent: corners
                        .iter()
                        .map(|c| c.abs().max_element())
                        .fold(0.0, f32::max),
                    front: e.radiance,
                    back: if e.two_sided { e.radiance } else { Rgb::ZERO },
                });
            }
        }
        (!tris.is_empty()).then_some(ClosedFormLight { tris })
    }

    /// The irradiance at `p` through the hemisphere around the unit normal `n`, as if nothing
    /// stood between it and the emitters: Σ L · (projected solid angle), each triangle's
    /// radiance that of the face `p` sees. A triangle whose plane passes through `p` (to
    /// within [`COPLANAR`]) sends nothing there, as the emitter samples find (their cosine at
    /// the light is zero): a point on an emitting surface, or beside a light set flush into
    /// a ceiling, where Lambert's formula is undefined (π inside the triangle, 0 outside,
    /// and rounding decides between them).
    pub fn irradiance(&self, p: Vec3, n: Vec3) -> Rgb {
        let at = p.abs().max_element();
        self.tris
            .iter()
            .map(|t| {
                let height = (p - t.corners[0]).dot(t.normal);
                if height.abs() <= COPLANAR * at.max(t.extent) {
                    return Rgb::ZERO;
                }
                let radiance = if height > 0.0 { t.front } else { t.back };
                if radiance == Rgb::ZERO {
                    Rgb::ZERO
                } else {
                    radiance * projected_solid_angle(p, n, t.corners)
                }
            })
            .fold(Rgb::ZERO, |a, b| a + b)
    }
}

/// `unshadowed` light, known in closed form, times the share of it that emitter samples found
/// unblocked: `visible / all`, per channel (zero where `all` is), the ratio estimator of Heitz,
/// Hill and McGuire ("Combining analytic direct illumination and stochastic shadows", 2018).
/// Where nothing blocks the light the result is exact, and where everything does it is zero,
/// whatever the samples; only penumbrae keep noise. The ratio of two estimates is biased by
/// O(1/k) for k samples: at 512 samples a pixel, cbox-diffuse's rendered direct light moved by
/// 2e-6 of the image's light on average against the plain estimate (docs/render.md).
pub fn shadowed(unshadowed: Rgb, visible: Rgb, all: Rgb) -> Rgb {
    let ratio = |v: f32, a: f32| if a > 0.0 { v / a } else { 0.0 };
    unshadowed
        * Rgb::new(
            ratio(visible.x, all.x),
            ratio(visible.y, all.y),
            ratio(visible.z, all.z),
        )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::{Bsdf, Diffuse};
    use crate::scene::{Emission, Material, Scattering};

    /// Two emitting triangles side by side (the right one twice the left's area), facing
    /// down from z = 1, and a point and a spot light.
    fn two_triangles_and_two_lights() -> Scene {
        let mesh = Mesh {
            name: "panels".into(),
            positions: vec![
                Vec3::new(-2.0, 0.0, 1.0),
                Vec3::new(-2.0, 1.0, 1.0),
                Vec3::new(-1.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(1.0, 2.0, 1.0),
                Vec3::new(2.0, 0.0, 1.0),
            ],
            normals: None,
            uvs: None,
            triangles: vec![[0, 1, 2], [3, 4, 5]],
            material: 0,
        };
        let light = |name: &str, kind| PunctualLight {
            name: name.into(),
            kind,
            position: Vec3::new(0.0, 0.0, 2.0),
            direction: -Vec3::Z,
            intensity: Rgb::splat(3.0),
        };
        Scene {
            meshes: vec![mesh],
            materials: vec![Material {
                name: "panel".into(),
                scattering: Scattering::Explicit(Bsdf::Diffuse(Diffuse {
                    reflectance: Rgb::ZERO,
                })),
                cutout: None,
                normal_map: None,
                emission: Some(Emission {
                    radiance: Rgb::splat(2.0),
                    texture: None,
                    two_sided: false,
                }),
            }],
            lights: vec![
                light("bulb", LightKind::Point),
                light(
                    "spot",
                    LightKind::Spot {
                        cos_inner: 0.9,
                        cos_outer: 0.8,
                    },
                ),
            ],
            ..Default::default()
        }
    }

    /// `Draw::WithoutDelta` draws the triangles alone, in proportion to their power (1 : 2),
    /// each sample's density the one `pdf_hit` gives under the same draw (as MIS needs), and
    /// hands the two lights over whole; `Draw::All` still draws the lights by their power.
    #[test]
    fn without_delta_draws_the_rest_by_power_and_hands_the_lights_over_whole() {
        let scene = two_triangles_and_two_lights();
        let emitters = EmitterSampler::new(&scene);
        let p = Vec3::new(0.1, 0.2, 0.0);
        let n = 4096;
        let mut right = 0;
        for k in 0..n {
            let u_sel = (k as f32 + 0.5) / n as f32;
            let u = Vec2::new(0.3, 0.6);
            let es = emitters
                .sample(&scene, p, (u_sel, u), Draw::WithoutDelta)
                .expect("a triangle");
            assert!(!es.delta, "u_sel {u_sel} drew a delta light");
            let tri = u32::from(es.point.x > 0.0);
            right += tri;
            let pdf = emitters.pdf_hit(0, tri, es.dist, es.wi, es.normal, Draw::WithoutDelta);
            assert!((es.pdf / pdf - 1.0).abs() < 1e-5, "{} vs {pdf}", es.pdf);
        }
        assert!(
            (right as f32 / n as f32 - 2.0 / 3.0).abs() < 1e-3,
            "{right} of {n}"
        );
        let last = 1.0 - f32::EPSILON;
        let es = emitters.sample(&scene, p, (last, Vec2::splat(0.5)), Draw::WithoutDelta);
        assert!(es.is_some_and(|s| !s.delta));

        let whole: Vec<EmitterSample> = emitters
            .delta_lights(&scene, p, Draw::WithoutDelta)
            .collect();
        assert_eq!(whole.len(), 2);
        let d2 = (Vec3::new(0.0, 0.0, 2.0) - p).length_squared();
        let cos = 2.0 / d2.sqrt();
        let falloff = ((cos - 0.8) / 0.1f32).clamp(0.0, 1.0).powi(2);
        for (es, expected) in whole.iter().zip([3.0 / d2, 3.0 * falloff / d2]) {
            assert!((es.value.x / expected - 1.0).abs() < 1e-5);
        }
        assert_eq!(emitters.delta_lights(&scene, p, Draw::All).count(), 0);
        let drawn_delta = (0..n)
            .filter_map(|k| {
                let u_sel = (k as f32 + 0.5) / n as f32;
                emitters.sample(&scene, p, (u_sel, Vec2::splat(0.5)), Draw::All)
            })
            .filter(|s| s.delta)
            .count();
        assert!(drawn_delta > 0);
    }
}

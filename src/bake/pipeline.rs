//! The bake, stage by stage (docs/design.md §5): plan, surfels, direct light, tree, coding.
//!
//! Per surfel, the direct-lit outgoing radiance is kept compactly: RGB for diffuse surfels, a
//! thresholded wavelet map (at the resolution its BSDF needs) for the others. The tree is then
//! coded post-order, each leaf's radiant-intensity map A |n·ω| L(ω) being built on the fly
//! from that compact form, so the uncompressed set never exists.

use super::baked::Baked;
use super::direct::{DirectLight, NEAR_SPECULAR_ALPHA};
use super::lightcuts::LightTree;
use super::plan::Plan;
use super::settings::BakeSettings;
use crate::accel::Accel;
use crate::bake::bounce::bsdf_operator::{quantised_alpha, Operators, SurfelOperator};
use crate::bake::bounce::kept::{KeptDirect, KeptIrradiance};
use crate::bake::bounce::{add_bounces, TransportHandoff};
use crate::bsdf::Bsdf;
use crate::cache::store::{emitters_hash, geometry_hash, material_hash};
use crate::emitters::EmitterSampler;
use crate::error::{Error, Result};
use crate::haar::{texel_directions, Haar2d, SparseHaar};
use crate::progress::Progress;
use crate::scene::{LightKind, Scene};
use crate::spectrum::Rgb;
use crate::surfels::coding::{encode, CodedTree};
use crate::surfels::radiance::{
    intensity_of, map_levels, mesh_flags, projected_area_map, SurfelRadiance, PROJECTED_AREA_LEVELS,
};
use crate::surfels::tree::SurfelTree;
use crate::surfels::{sample_surfels_with_density, Surfel};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

/// Scenes with more point and spot lights than this use a light tree (Lightcuts).
pub(crate) const LIGHT_TREE_FROM: usize = 16;

/// Each mesh's relative surfel density from the per-material factors of `densities`
/// (material name, factor, whose range [`BakeSettings::validate`] checked): a name that is
/// no material of the scene is refused, naming the materials there are.
fn mesh_densities(scene: &Scene, densities: &[(String, f32)]) -> Result<Vec<f32>> {
    let mut of_material = vec![1.0f32; scene.materials.len()];
    for (name, w) in densities {
        let matching: Vec<usize> = (0..scene.materials.len())
            .filter(|&m| scene.materials[m].name == *name)
            .collect();
        if matching.is_empty() {
            // The names of the materials some mesh uses (not the loader's unused fallback).
            let mut used: Vec<usize> = scene.meshes.iter().map(|m| m.material).collect();
            used.sort_unstable();
            used.dedup();
            let names: Vec<&str> = used
                .iter()
                .map(|&m| scene.materials[m].name.as_str())
                .collect();
            return Err(Error::InvalidSetting(format!(
                "no material is named \"{name}\" (the scene's meshes use: {})",
                names.join(", ")
            )));
        }
        for m in matching {
            of_material[m] = *w;
        }
    }
    Ok(scene
        .meshes
        .iter()
        .map(|m| of_material[m.material])
        .collect())
}

/// Refuse, before any work, a bake that cannot fit: bounces whose transport slots overflow
/// 32 bits, or a floor of what the bake must hold (surfels, their radiance, the tree and its
/// coding, the cache's records, and for bounces the tree as senders and the slots' bitmap,
/// with no transport kept: that part gives way, see
/// [`BounceSettings::transport_budget`](crate::bake::bounce::BounceSettings::transport_budget);
/// or the surfel sampling's, where larger) above the memory the machine has available. The
/// floor counts the structures only, not the maps' coefficients, so a bake it lets through
/// may still need more.
fn check_fits(settings: &BakeSettings, map_levels: u32) -> Result<()> {
    let points = settings.points as u64;
    let bounces = settings.bounces.max > 0;
    if bounces {
        super::bounce::settings::check_slots(points, map_levels)?;
    }
    let per_surfel = size_of::<Surfel>()
        + size_of::<SurfelRadiance>()
        + size_of::<Rgb>()
        + 2 * (size_of::<crate::surfels::tree::Node>()
            + size_of::<crate::surfels::coding::NodeCoding<Rgb>>()
            + size_of::<crate::surfels::coding::NodeCoding<f32>>()
            + size_of::<crate::cache::store::NodeRecord>())
        + size_of::<crate::cache::store::SurfelRecord>();
    let floor = points
        .saturating_mul(per_surfel as u64)
        .saturating_add(if bounces {
            super::bounce::settings::memory_floor(points, map_levels)
        } else {
            0
        })
        // Drawing the surfels holds more a surfel than the structures, for a while.
        .max(crate::surfels::sampling_memory(points));
    match crate::machine::available_memory() {
        Some(available) if floor > available => Err(Error::InvalidSetting(format!(
            "a bake of {points} surfels needs at least {} MB, and this machine has {} MB \
             available; bake fewer points (--points)",
            floor / 1_000_000,
            available / 1_000_000
        ))),
        _ => Ok(()),
    }
}

/// Bake `scene`: direct light, then the indirect bounces `settings` asks for.
pub fn bake(scene: &Scene, settings: &BakeSettings, progress: Progress) -> Result<Baked> {
    bake_cancellable(scene, settings, progress, &AtomicBool::new(false))
}

/// [`bake`], stopping with [`Error::Cancelled`] soon after `cancel` is set (by the progress
/// callback, another thread or a signal handler). The surfel loops look at the flag once per
/// surfel or receiver group; only the tree's coding (a few per cent of a bake) runs on.
pub fn bake_cancellable(
    scene: &Scene,
    settings: &BakeSettings,
    progress: Progress,
    cancel: &AtomicBool,
) -> Result<Baked> {
    bake_with_transport(
        scene,
        settings,
        progress,
        cancel,
        &mut TransportHandoff::default(),
    )
}

/// [`bake_cancellable`], its bounces replaying a transport kept from an earlier bake where
/// `handoff` hands in one whose key is this bake's, and handing theirs out where it asks
/// (see [`TransportHandoff`]; the cache is the same either way).
pub fn bake_with_transport(
    scene: &Scene,
    settings: &BakeSettings,
    progress: Progress,
    cancel: &AtomicBool,
    handoff: &mut TransportHandoff,
) -> Result<Baked> {
    let stop = || crate::error::check_cancel(cancel);
    settings.validate()?;
    scene.check_renderable()?;
    let density = mesh_densities(scene, &settings.surfel_density)?;
    let mut timings = Vec::new();
    let mut stage =
        |name: &'static str, start: Instant| timings.push((name, start.elapsed().as_secs_f64()));

    let t = Instant::now();
    let mut plan = Plan::new(scene);
    plan.note_bounces(&settings.bounces);
    check_fits(settings, plan.map_levels)?;
    let accel = Accel::build(scene);
    // Many point and spot lights go through a light tree; a few are sampled with the rest.
    let punctual = scene
        .lights
        .iter()
        .filter(|l| !matches!(l.kind, LightKind::Directional))
        .count();
    let light_tree = (punctual > LIGHT_TREE_FROM).then(|| LightTree::new(&scene.lights));
    let emitters = EmitterSampler::with_punctual(scene, light_tree.is_none());
    plan.json["lightcuts"] = light_tree.is_some().into();
    plan.note_relight(scene, light_tree.is_some());
    stage("plan", t);

    let t = Instant::now();
    progress("surfels", 0.0);
    // A bake handed the surfels and direct light of a bake of the same geometry and settings
    // (a relight's: see `KeptDirect`) takes the surfels, and where the emitters are the
    // same too, the direct light of every surfel whose material is.
    // What this bake's surfels and direct light come from, hashed only where a kept direct
    // light is handed in or asked for (the geometry's hash reads every vertex and texel).
    // A relight's kept BSDF operators, taken where this bake would build the same ones.
    let kept_operators = handoff
        .reuse
        .as_mut()
        .map(|t| std::mem::take(&mut t.operators))
        .unwrap_or_default();
    let geometry = (handoff.keep || handoff.reuse.is_some() || handoff.projected.is_some())
        .then(|| geometry_hash(scene, &settings.to_json()));
    let kept = handoff
        .reuse
        .as_ref()
        .and_then(|t| t.direct.as_ref())
        .filter(|d| {
            Some(d.geometry) == geometry
                && d.radiance.len() == d.surfels.len()
                && d.emitted.len() == d.surfels.len()
                && d.surfels.iter().all(|s| {
                    scene
                        .meshes
                        .get(s.mesh as usize)
                        .is_some_and(|m| (s.triangle as usize) < m.triangles.len())
                })
        });
    let kept_direct = kept
        .filter(|d| {
            d.emitters == emitters_hash(scene) && d.materials.len() == scene.materials.len()
        })
        .map(|d| {
            let holds: Vec<bool> = d
                .materials
                .iter()
                .zip(&scene.materials)
                .map(|(h, m)| *h == material_hash(m))
                .collect();
            (d, holds)
        });
    let surfels = match kept {
        Some(d) => d.surfels.clone(),
        None => sample_surfels_with_density(scene, settings.points, settings.seed, &density),
    };
    progress("surfels", 1.0);
    stage("surfels", t);
    stop()?;

    let t = Instant::now();
    let direct = DirectLight {
        scene,
        accel: &accel,
        emitters: &emitters,
        samples: settings.light_samples,
        seed: settings.seed,
        light_tree: light_tree.as_ref(),
        max_cut: settings.max_cut,
    };
    let bsdfs: Vec<Bsdf> = surfels.iter().map(|s| surfel_bsdf(scene, s)).collect();
    let shading_normals: Vec<Vec3> = surfels
        .iter()
        .map(|s| surfel_shading_normal(scene, s))
        .collect();
    let mut operators = Operators::with_kept(kept_operators);
    let near_specular = operators.of_each(&bsdfs, settings.bounces.operator_tau, |b| {
        b.alpha().is_some_and(|a| a < NEAR_SPECULAR_ALPHA)
    });
    let done = AtomicUsize::new(0);
    // The kept direct light, per surfel whose material is as it was in the bake that kept it.
    let kept_at = |i: usize, s: &Surfel| {
        kept_direct.as_ref().and_then(|(d, holds)| {
            holds[scene.meshes[s.mesh as usize].material].then(|| SurfelDirect {
                radiance: d.radiance[i].clone(),
                emitted: d.emitted[i],
                irradiance: d.irradiance[i],
            })
        })
    };
    // The kept irradiance of a diffuse surfel whose material is not (its reflectance edited),
    // shading about the same normal: reflected again as the direct pass reflects it.
    let reflected_at = |i: usize, s: &Surfel| {
        let (d, _) = kept_direct.as_ref()?;
        let kept = d.irradiance[i].filter(|k| same_bits(k.shading, shading_normals[i]))?;
        let Bsdf::Diffuse(diffuse) = &bsdfs[i] else {
            return None;
        };
        map_levels(&bsdfs[i]).is_none().then(|| {
            let emitted = surfel_emission(scene, s);
            SurfelDirect {
                radiance: diffuse_radiance(diffuse.reflectance, kept.irradiance, emitted),
                emitted,
                irradiance: Some(kept),
            }
        })
    };
    let (reused, reflected) = (AtomicUsize::new(0), AtomicUsize::new(0));
    let direct_light: Vec<SurfelDirect> = surfels
        .par_iter()
        .enumerate()
        .map(|(i, s)| {
            stop()?;
            if let Some(kept) = kept_at(i, s) {
                reused.fetch_add(1, Ordering::Relaxed);
                return Ok(kept);
            }
            if let Some(again) = reflected_at(i, s) {
                reflected.fetch_add(1, Ordering::Relaxed);
                return Ok(again);
            }
            let (bsdf, op) = (&bsdfs[i], near_specular[i].as_ref());
            let at = (s, shading_normals[i]);
            let r = surfel_radiance(scene, &direct, at, i as u64, (bsdf, op), settings.tau);
            let n = done.fetch_add(1, Ordering::Relaxed) + 1;
            if n.is_multiple_of(4096) {
                progress("direct light", n as f32 / surfels.len() as f32);
            }
            Ok(r)
        })
        .collect::<Result<_>>()?;
    let mut radiance = Vec::with_capacity(direct_light.len());
    let mut emitted = Vec::with_capacity(direct_light.len());
    let mut irradiance = Vec::with_capacity(direct_light.len());
    for d in direct_light {
        radiance.push(d.radiance);
        emitted.push(d.emitted);
        irradiance.push(d.irradiance);
    }
    progress("direct light", 1.0);
    stage("direct light", t);
    handoff.direct_reused = reused.into_inner();
    handoff.irradiance_reused = reflected.into_inner();
    if let Some(t) = handoff.reuse.as_mut() {
        t.direct = None; // taken where it held; the bounces need the links alone
    }
    let direct_kept = geometry
        .filter(|_| handoff.keep)
        .map(|geometry| KeptDirect {
            geometry,
            emitters: emitters_hash(scene),
            materials: scene.materials.iter().map(material_hash).collect(),
            surfels: surfels.clone(),
            radiance: radiance.clone(),
            emitted: emitted.clone(),
            irradiance,
        });

    let t = Instant::now();
    let tree = SurfelTree::build(&surfels);
    stage("tree", t);

    let t = Instant::now();
    let eps = settings
        .split_level
        .unwrap_or(tree.depth().saturating_sub(3))
        .min(tree.depth().saturating_sub(1));
    // Textured roughness can ask for more than the plan saw at (0, 0): the tree takes the finest.
    let levels = radiance
        .iter()
        .filter_map(|r| match r {
            SurfelRadiance::Map(m) => Some(m.levels()),
            SurfelRadiance::Rgb(_) => None,
        })
        .fold(plan.map_levels, u32::max);
    plan.map_levels = levels;
    plan.json["map_resolution"] = (1u32 << levels).into();
    let mesh_flags = mesh_flags(scene);
    progress("coding", 0.0);
    // The bounces read the tree's geometry alone and code it again for the total light at
    // the end: only a direct-only cache keeps the direct light's coding.
    let coded = if settings.bounces.max > 0 {
        CodedTree::uncoded(&tree, eps)
    } else {
        encode(
            &tree,
            &intensity_of(&surfels, &mesh_flags, &radiance),
            levels,
            eps,
            settings.tau,
        )
    };
    // A relight's cache holds the coding of this geometry's projected area already.
    let kept_projected = handoff
        .projected
        .take()
        .filter(|p| Some(p.geometry) == geometry && p.nodes.len() == tree.nodes.len());
    let projected = match kept_projected {
        Some(p) => CodedTree {
            split_level: eps,
            nodes: p.nodes,
        },
        None => {
            let area_leaf =
                |i: u32| SparseHaar::compress_below(&projected_area_map(&surfels[i as usize]), 0.0);
            encode(&tree, &area_leaf, PROJECTED_AREA_LEVELS, eps, settings.tau)
        }
    };
    progress("coding", 1.0);
    stage("coding", t);
    stop()?;

    let mut baked = Baked {
        plan,
        settings: settings.clone(),
        surfels,
        radiance,
        emitted,
        mesh_flags,
        bsdfs,
        shading_normals,
        operators,
        tree,
        coded,
        projected,
        timings,
        bounces: None,
    };
    if settings.bounces.max > 0 {
        let t = Instant::now();
        baked.bounces = Some(add_bounces(
            scene,
            &mut baked,
            &settings.bounces,
            progress,
            cancel,
            handoff,
        )?);
        baked.timings.push(("bounces", t.elapsed().as_secs_f64()));
        if let Some(kept) = handoff.kept.as_mut() {
            kept.direct = direct_kept;
        }
    }
    Ok(baked)
}

/// The material of surfel `s` and its texture coordinates there.
fn surfel_material<'a>(scene: &'a Scene, s: &Surfel) -> (&'a crate::scene::Material, glam::Vec2) {
    let mesh = &scene.meshes[s.mesh as usize];
    let uv = mesh.uv_at(s.triangle, [1.0 - s.b.x - s.b.y, s.b.x, s.b.y]);
    (&scene.materials[mesh.material], uv)
}

/// The BSDF at surfel `s` (textures looked up), its roughness snapped to the operators'
/// levels ([`quantised_alpha`]) where a texture varies it: the bake then builds one operator
/// per level, not one per surfel.
pub fn surfel_bsdf(scene: &Scene, s: &Surfel) -> Bsdf {
    let (material, uv) = surfel_material(scene, s);
    let bsdf = material.bsdf_at(&scene.textures, uv);
    match bsdf.alpha() {
        Some(alpha) if material.has_textured_roughness() => bsdf.with_alpha(quantised_alpha(alpha)),
        _ => bsdf,
    }
}

/// The normal surfel `s` shades with: its geometric normal `s.n`, or where its material has a
/// normal map, the interpolated normal tilted by the map (as at a ray hit, docs/scene.md).
/// The surfel's disc, its emission and its projected area keep `s.n`.
pub fn surfel_shading_normal(scene: &Scene, s: &Surfel) -> Vec3 {
    let mesh = &scene.meshes[s.mesh as usize];
    let Some(map) = &scene.materials[mesh.material].normal_map else {
        return s.n;
    };
    let b = [1.0 - s.b.x - s.b.y, s.b.x, s.b.y];
    let interpolated = mesh
        .normal_at(s.triangle, b)
        .filter(|n| n.dot(s.n) > 0.0)
        .unwrap_or(s.n);
    map.shading_normal(
        &scene.textures,
        mesh,
        s.triangle,
        mesh.uv_at(s.triangle, b),
        interpolated,
    )
}

/// What the direct pass leaves a surfel.
struct SurfelDirect {
    /// Direct light plus emission leaving it.
    radiance: SurfelRadiance,
    /// The emission alone.
    emitted: Rgb,
    /// For a diffuse surfel, the irradiance it reflects.
    irradiance: Option<KeptIrradiance>,
}

/// Whether two vectors are the same bit for bit.
fn same_bits(a: Vec3, b: Vec3) -> bool {
    a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
}

/// The emission leaving surfel `s`'s front face (both faces of a two-sided emitter are not
/// separate surfels: the front is what a surfel stands for).
fn surfel_emission(scene: &Scene, s: &Surfel) -> Rgb {
    let (material, uv) = surfel_material(scene, s);
    material.emission_at(&scene.textures, uv, true)
}

/// A diffuse surfel's outgoing radiance from its reflectance, the irradiance on its front
/// face and its emission.
fn diffuse_radiance(reflectance: Rgb, irradiance: Rgb, emitted: Rgb) -> SurfelRadiance {
    SurfelRadiance::Rgb(reflectance * irradiance * std::f32::consts::FRAC_1_PI + emitted)
}

/// The direct pass at surfel `s` with its BSDF (and that BSDF's operator where its direct
/// light goes through it, see [`NEAR_SPECULAR_ALPHA`]).
fn surfel_radiance(
    scene: &Scene,
    direct: &DirectLight,
    (s, shading): (&Surfel, Vec3),
    id: u64,
    (bsdf, op): (&Bsdf, Option<&SurfelOperator>),
    tau: f32,
) -> SurfelDirect {
    let emitted = surfel_emission(scene, s);
    let mut irradiance = None;
    let radiance = match (map_levels(bsdf), bsdf) {
        (None, Bsdf::Diffuse(d)) => {
            let e = direct.irradiance(s, shading, id);
            irradiance = Some(KeptIrradiance {
                irradiance: e,
                shading,
            });
            diffuse_radiance(d.reflectance, e, emitted)
        }
        (levels, _) => {
            let levels = levels.unwrap_or(3);
            let mut texels = match op {
                Some(op) => direct.radiance_map_through((s, shading), id, op, levels),
                None => direct.radiance_map((s, shading), id, bsdf, levels),
            };
            if emitted != Rgb::ZERO {
                for (v, w) in texels.iter_mut().zip(texel_directions(levels)) {
                    if w.dot(s.n) > 0.0 {
                        *v += emitted;
                    }
                }
            }
            SurfelRadiance::Map(SparseHaar::compress(
                &Haar2d::forward(&texels, 1 << levels),
                tau,
            ))
        }
    };
    SurfelDirect {
        radiance,
        emitted,
        irradiance,
    }
}

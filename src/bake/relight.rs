//! Relighting a cache for an edited scene (`wpbgi relight`): the scene's materials and lights
//! changed after the bake ([`crate::scene::edit`]), the cache made the edited scene's bake.
//!
//! Light transport is linear in the emission, channel by channel. When the edits multiply
//! every emitter's radiance by one factor k per colour channel and change nothing else, the
//! edited scene's bake is the cache's with every radiance multiplied by k: the surfels'
//! radiance and emission and the tree's intensity maps, Haar coefficient by coefficient (the
//! transform is linear); projected areas stay. That takes the time of reading and writing
//! the cache. It holds only where k leaves every choice of the bake as it was: the bake
//! picks emitters in proportion to their luminous power, stops its bounces on luminance
//! ratios and cuts its light tree on relative bounds, so k must be grey, or every emitter
//! one untextured colour (then k changes no emitter's share) with no light tree
//! (`plan::recolourable`, which the bake's plan records under "relight").
//!
//! Every other edit (a reflectance, a tint, a roughness, one light of several recoloured, an
//! emitter added or removed) changes how light bounces, and the cache is baked again for the
//! edited scene with the settings it was baked with. Where the cache was baked with its
//! transport kept beside it ([`super::bounce::kept`]), that bake replays the transport
//! instead of recording it, and keeps the direct light of every surfel whose material (and
//! the scene's emitters) are as they were in the bake that kept it: the same cache, byte for
//! byte, in about half the time (the report says which way was taken and why).
//!
//! Either way the new cache carries the hash of the edited scene's bake, so `render` accepts
//! it for the edited scene and refuses it for the original.

use super::baked::Baked;
use super::bounce::kept::beside;
use super::bounce::{BounceReport, KeptProjected, KeptTransport, TransportHandoff};
use super::pipeline::bake_with_transport;
use super::plan::{recolourable, SAME_RATIO};
use super::settings::BakeSettings;
use super::store::{save, write_scaled};
use crate::cache::store::{bake_hash, geometry_hash, BakedCache, NO_MAP};
use crate::cache::CacheError;
use crate::error::Result;
use crate::progress::Progress;
use crate::scene::edit::Edit;
use crate::scene::Scene;
use crate::spectrum::Rgb;
use crate::surfels::coding::NodeCoding;
use crate::surfels::radiance::map_levels;
use glam::Vec2;
use rayon::prelude::*;
use serde_json::json;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// How a relit cache was made.
#[derive(Clone, Debug, PartialEq)]
pub enum Relighting {
    /// Every radiance the cache holds multiplied by `factor` per channel.
    Rescaled {
        /// The emitters' common factor.
        factor: Rgb,
    },
    /// The edited scene's bounces re-solved from the transport kept beside the cache
    /// (`wpbgi bake --keep-transport`): its transport replayed, the direct light made again
    /// for the edited materials' surfels only.
    Resolved {
        /// Why the cache could not be rescaled, in words.
        why: String,
        /// Surfels whose direct light was kept (their material and every emitter unedited),
        /// of all.
        kept_direct: (usize, usize),
        /// Diffuse surfels of edited materials whose kept irradiance was reflected again
        /// (their reflectance edited, their normal and every emitter as they were): no light
        /// sampled for them either.
        kept_irradiance: usize,
        /// BSDF operators taken from the transport file (their untinted BSDFs unedited), of
        /// all the bake used.
        kept_operators: (usize, usize),
    },
    /// The edited scene baked again with the cache's settings.
    Rebaked {
        /// Why the cache could not be rescaled, in words.
        why: String,
    },
}

impl std::fmt::Display for Relighting {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Relighting::Rescaled { factor } => write!(
                f,
                "every emitter ×({:.4}, {:.4}, {:.4}), the cache rescaled",
                factor.x, factor.y, factor.z
            ),
            Relighting::Resolved {
                why,
                kept_direct,
                kept_irradiance,
                kept_operators,
            } => write!(
                f,
                "re-solved from the kept transport, the direct light of {} of {} surfels (and \
                 the irradiance of {kept_irradiance} more) and {} of {} BSDF operators kept: \
                 {why}",
                kept_direct.0, kept_direct.1, kept_operators.0, kept_operators.1
            ),
            Relighting::Rebaked { why } => write!(f, "baked again: {why}"),
        }
    }
}

/// What [`relight`] did.
#[derive(Clone, Debug)]
pub struct Relit {
    /// How the new cache was made.
    pub how: Relighting,
    /// The edited scene (what the new cache is fresh for).
    pub scene: Scene,
    /// Wall seconds.
    pub seconds: f64,
    /// Wall seconds by stage, in order: reading the kept transport and the bake's own stages
    /// where the cache was re-solved or baked again, then writing the new cache.
    pub timings: Vec<(&'static str, f64)>,
    /// Where the cache was re-solved or baked again, what its bounces did (each one's
    /// seconds, and the final maps': the "bounces" stage of `timings`).
    pub bounces: Option<BounceReport>,
}

/// Relight `cache`, a fresh bake of `original`, for `original` with `edits` applied, and
/// write the result to `output` (atomically). `progress` and `cancel` serve a re-bake.
pub fn relight(
    original: &Scene,
    cache: &BakedCache,
    edits: &[Edit],
    output: &Path,
    progress: Progress,
    cancel: &AtomicBool,
) -> Result<Relit> {
    let start = Instant::now();
    cache.check_scene(original)?;
    let scene = original.edited(edits)?;
    let lightcuts = cache.plan["plan"]["lightcuts"].as_bool().unwrap_or(true);
    let mut timings = Vec::new();
    let mut bounces = None;
    let how = match emission_factor(original, &scene, lightcuts) {
        Ok(factor) => {
            let hash = bake_hash(&scene, cache.settings());
            let mut plan = cache.plan.clone();
            plan["relit"] = json!({
                "from": crate::cache::hash_hex(cache.cache.hash),
                "edits": edits.iter().map(|e| e.to_string()).collect::<Vec<_>>(),
                "factor": factor.to_array(),
            });
            let writing = Instant::now();
            write_scaled(output, hash, cache, factor, &plan)?;
            timings.push(("rescale and write", writing.elapsed().as_secs_f64()));
            Relighting::Rescaled { factor }
        }
        Err(why) => {
            let why = why + &finer_maps(original, &scene, cache.map_resolution());
            let settings = BakeSettings::from_json(cache.settings()).map_err(|what| {
                CacheError::Malformed {
                    path: cache.cache.path.clone(),
                    what: format!("its settings cannot be read back: {what}"),
                }
            })?;
            let transport = beside(&cache.cache.path);
            let mut handoff = TransportHandoff::default();
            let reading = Instant::now();
            handoff.projected = Some(projected_of(cache, original, &settings)?);
            timings.push(("read projected area", reading.elapsed().as_secs_f64()));
            let mut unused = None;
            let present = transport.exists();
            if present {
                let reading = Instant::now();
                match KeptTransport::read(&transport) {
                    Ok(t) => handoff.reuse = Some(t),
                    Err(reason) => unused = Some(reason),
                }
                timings.push(("read transport", reading.elapsed().as_secs_f64()));
            }
            let mut baked: Baked =
                bake_with_transport(&scene, &settings, progress, cancel, &mut handoff)?;
            timings.extend(&baked.timings);
            // The cache records none of it (no times: it is byte-identical from run to run).
            bounces = baked.bounces.take();
            let writing = Instant::now();
            save(output, &scene, &baked)?;
            timings.push(("write", writing.elapsed().as_secs_f64()));
            let unused = unused.or(handoff.refused);
            if handoff.replayed {
                keep_beside(&transport, &beside(output));
                Relighting::Resolved {
                    why,
                    kept_direct: (handoff.direct_reused, baked.surfels.len()),
                    kept_irradiance: handoff.irradiance_reused,
                    kept_operators: (baked.operators.reused(), baked.operators.len()),
                }
            } else {
                let note = match unused {
                    Some(reason) => format!(
                        "; the transport {} was not used: {reason}",
                        transport.display()
                    ),
                    None if !present && settings.bounces.max > 0 => {
                        " (a cache baked with --keep-transport re-solves such edits without \
                         gathering again)"
                            .to_string()
                    }
                    None => String::new(),
                };
                Relighting::Rebaked { why: why + &note }
            }
        }
    };
    Ok(Relit {
        how,
        scene,
        seconds: start.elapsed().as_secs_f64(),
        timings,
        bounces,
    })
}

/// The cache's coding of the projected area, for the bake of the edited scene to take where
/// its geometry is the cache's: keyed by the geometry of `original`, the scene the cache was
/// checked against.
fn projected_of(
    cache: &BakedCache,
    original: &Scene,
    settings: &BakeSettings,
) -> Result<KeptProjected, CacheError> {
    let map = |i: u32| (i != NO_MAP).then(|| cache.map::<f32>(i)).transpose();
    let nodes = cache
        .nodes
        .par_iter()
        .map(|n| {
            Ok(NodeCoding {
                g: map(n.area_g)?,
                h: map(n.area_h)?,
            })
        })
        .collect::<Result<_, CacheError>>()?;
    Ok(KeptProjected {
        geometry: geometry_hash(original, &settings.to_json()),
        nodes,
    })
}

/// Keep the transport file `from` beside the relit cache too, as `to` (the edits changed no
/// link of it), so that edits chain: a hard link, which costs no space. Where none can be
/// made (another file system) the relit cache goes without: a copy would cost seconds and
/// several times the cache's size on disk, unasked.
fn keep_beside(from: &Path, to: &Path) {
    if std::fs::canonicalize(from).ok() == std::fs::canonicalize(to).ok() {
        return;
    }
    // A stale transport of an earlier cache at `to` goes first (the link needs the name
    // free), and must go either way: it is not this cache's.
    let _ = std::fs::remove_file(to);
    let _ = std::fs::hard_link(from, to);
}

/// Where an edit makes a material smoother than the cache's directional maps resolve (`side`
/// texels a side; see [`map_levels`]): a note saying so, else nothing. Only a bake can give it
/// finer maps; the note says why the new cache's plan differs.
fn finer_maps(original: &Scene, edited: &Scene, side: Option<u32>) -> String {
    let side = side.unwrap_or(0);
    let needs = |scene: &Scene, m: &crate::scene::Material| {
        map_levels(&m.bsdf_at(&scene.textures, Vec2::ZERO)).map_or(0, |l| 1u32 << l)
    };
    let notes: Vec<String> = original
        .materials
        .iter()
        .zip(&edited.materials)
        .filter_map(|(o, e)| {
            let n = needs(edited, e);
            (n > side && n > needs(original, o)).then(|| {
                format!(
                    "; material \"{}\" now needs {n}² directional maps where the cache has {side}²",
                    e.name
                )
            })
        })
        .collect();
    notes.concat()
}

/// The factor k per channel by which every emission of `edited` is `original`'s, when the
/// edits changed nothing else and k leaves the bake's choices as they were (see the module
/// docs); otherwise why not. `lightcuts`: whether the bake cut a light tree.
fn emission_factor(original: &Scene, edited: &Scene, lightcuts: bool) -> Result<Rgb, String> {
    // (original, edited) radiance of every emitter.
    let mut pairs: Vec<(Rgb, Rgb)> = Vec::new();
    for (o, e) in original.materials.iter().zip(&edited.materials) {
        let rest =
            |m: &crate::scene::Material| format!("{:?}", (&m.scattering, &m.cutout, &m.normal_map));
        if rest(o) != rest(e) {
            return Err(format!(
                "the edits change how material \"{}\" scatters light",
                o.name
            ));
        }
        match (&o.emission, &e.emission) {
            (None, None) => {}
            (Some(a), Some(b)) if a.two_sided == b.two_sided => {
                pairs.push((a.radiance, b.radiance))
            }
            _ => return Err(format!("the edits make material \"{}\" an emitter", o.name)),
        }
    }
    for (o, e) in original.lights.iter().zip(&edited.lights) {
        pairs.push((o.intensity, e.intensity));
    }
    if let (Some(o), Some(e)) = (&original.environment, &edited.environment) {
        pairs.push((o.scale, e.scale));
    }
    let mut factor = [None::<f32>; 3];
    for &(o, e) in &pairs {
        for c in 0..3 {
            if o[c] > 0.0 {
                let k = e[c] / o[c];
                match factor[c] {
                    None => factor[c] = Some(k),
                    Some(f) if (k - f).abs() <= SAME_RATIO * f.abs().max(k.abs()) => {}
                    Some(_) => {
                        return Err("the edits change the emitters by different factors".into())
                    }
                }
            } else if e[c] != 0.0 {
                return Err("the edits give an emitter a colour it did not emit".into());
            }
        }
    }
    let k = Rgb::from_array(factor.map(|f| f.unwrap_or(1.0)));
    if !(k.min_element() > 0.0 && k.is_finite()) {
        return Err("the edits turn an emitter's light off".into());
    }
    let grey = k.max_element() - k.min_element() <= SAME_RATIO * k.max_element();
    if !grey && !recolourable(original, lightcuts) {
        return Err(
            "the edits recolour emitters of different colours or textures, or lights \
                    that the bake cut as a light tree"
                .into(),
        );
    }
    Ok(k)
}

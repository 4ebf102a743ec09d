//! The path-traced gather (`--gather paths`): a receiver's indirect light from rays drawn
//! from its BSDF that end in the cache.
//!
//! A receiver is a rough hit of a camera sample, whose direct light the primary pass took by
//! next-event estimation. From it, `spp` directions are drawn from its BSDF (the points of a
//! scrambled (0, 2)-sequence, so that every strip of the square holds its share of them) and
//! traced to the first surface they hit. The cache's reflected radiance there, towards the
//! receiver, stands for all the light further along the path: the nearest surfel of the hit
//! mesh, read as a gather reads a leaf ([`Senders::lookup_at`]). This is how production
//! renderers use a light cache (V-Ray's light cache, Corona's UHD cache): the first bounce is
//! traced exactly, through contacts and narrow lobes, and what lies beyond it comes from the
//! cache without noise. Its cost is `spp` rays and nearest-surfel searches per receiver,
//! whatever its lobe; its error is the first bounce's noise, smallest where the lobe is narrow
//! (a glossy receiver's rays all land where its buffer would have had to be refined).
//!
//! **Through glossy hits.** A cache stores a glossy surface's outgoing light in directional
//! maps as fine as its plan chose, which blur a narrow lobe (a rough glass sphere's inside,
//! seen from the floor through it, is the cache's bias that stopped this mode short of
//! Mitsuba + OIDN's error on cbox-rough). So where a ray lands on a surface smoother than the
//! render's glossy threshold, the path goes on as a path tracer's does (one emitter sample
//! there, combined with the BSDF samples that find emitters by the power heuristic, then a
//! BSDF sample onwards), up to the render's chain depth, and the cache is read at the first
//! rougher hit. The light that hit reflects is the same quantity the cache holds at the
//! glossy one, so this only moves where the cache is read. It trades the maps' blur for
//! path-traced noise (caustics found by BSDF samples through the glass), so it is for a
//! denoised render (`render --denoise` asks for it:
//! [`FinalSettings::paths_through_glossy`](super::FinalSettings::paths_through_glossy)).
//! Measured at 256² on the default caches, 16 / 64 rays, denoised, relMSE against Mitsuba's
//! max_depth 8: cbox-rough 1.65e-3 → 9.1e-4 / 1.42e-3 → 7.9e-4, cbox-glossy 1.61e-3 →
//! 1.43e-3 / 1.38e-3 → 1.28e-3, cbox-mirror 2.27e-3 → 1.92e-3 / 2.22e-3 → 1.49e-3, caustic
//! 5.54e-3 → 5.64e-3 / 5.27e-3 → 5.49e-3, cbox-diffuse the same (nothing glossy), for 0–35 %
//! more time; raw, cbox-rough's relMSE at 16 rays went 7.9e-3 → 1.29e-2. It is done only
//! where the cache's light is the whole of what lies beyond: with a limited `--max-depth`, or
//! a direct-only cache, the path stops at the first hit.

use super::primary::Receiver;
use crate::bsdf::TransportMode;
use crate::gather::Senders;
use crate::sampler::{sobol02, Sampler};
use crate::spectrum::{max_component, Rgb};
use crate::trace::{intersect, Tracer};
use glam::Vec3;

/// Where a path-traced gather's rays read the cache.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Continuation {
    /// Go on through hits smoother than `glossy_below` (see the module docs); else read the
    /// cache at the first hit.
    pub through_glossy: bool,
    /// The roughness below which a hit is glossy (the render's `glossy_below`).
    pub glossy_below: f32,
    /// The most glossy hits a path goes through (the render's `chain_depth`).
    pub most: u32,
}

/// Sample indices of the path-traced gather's streams start here, above any camera sample's
/// (each pixel's stream numbers its camera samples from 0).
const GATHER_STREAMS: u64 = 1 << 40;

/// The indirect light receiver `r` sends towards its viewer (times its weight), from `spp`
/// rays into the cache. `index` tells the receiver apart from the others of its pixel (its
/// place in its tile), which keys its random numbers.
pub(crate) fn path_gather(
    ctx: &Tracer,
    senders: &Senders,
    r: &Receiver,
    spp: u32,
    continuation: Continuation,
    (seed, index): (u64, u64),
) -> Rgb {
    let mut sampler = Sampler::new(seed, u64::from(r.pixel), GATHER_STREAMS + index);
    let scramble = sampler.next_scramble();
    let mut sum = Rgb::ZERO;
    for s in 0..spp {
        let u0 = sampler.next_1d();
        let Some(sample) = r
            .bsdf
            .sample(r.view, u0, sobol02(s, scramble), TransportMode::Radiance)
        else {
            continue;
        };
        let w = r.frame.to_world(sample.wo).normalize();
        sum += sample.weight
            * into_cache(
                ctx,
                senders,
                (r.spawn(w), w),
                r.mesh,
                continuation,
                &mut sampler,
            )
            .light;
    }
    let l = r.weight * sum / spp as f32;
    if l.is_finite() {
        l
    } else {
        Rgb::ZERO
    }
}

/// What a ray into the cache brought back ([`into_cache`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct CacheRay {
    /// All the light it brought.
    pub light: Rgb,
    /// The part of `light` that emitters sent through its glossy hits (found by next-event
    /// estimation or by a BSDF sample): the path-traced part, whose noise is a glint's
    /// (`super::bright` caps it).
    pub emitted: Rgb,
    /// Whether the ray hit the scene at all.
    pub hit: bool,
}

/// The light arriving along the ray `(o, w)` leaving a receiver on mesh `receiver_mesh`, less
/// what its own next-event estimation took (the emitters it hits first): the cache's at the
/// first hit, or, through glossy hits ([`Continuation`]), a path traced on to the first rough
/// one, its emitters found by next-event estimation and by its BSDF samples, combined by the
/// power heuristic as the reference path tracer combines them.
pub(crate) fn into_cache(
    ctx: &Tracer,
    senders: &Senders,
    (mut o, mut w): (Vec3, Vec3),
    receiver_mesh: u32,
    continuation: Continuation,
    sampler: &mut Sampler,
) -> CacheRay {
    let scene = ctx.scene;
    let mut cached = Rgb::ZERO;
    let mut emitted = Rgb::ZERO;
    let mut hit_any = false;
    let mut throughput = Rgb::ONE;
    // The BSDF density of the direction that led here from a glossy hit (none yet: the
    // receiver's own emitters are its next-event estimation's).
    let mut from_glossy: Option<f32> = None;
    let mut reader = receiver_mesh;
    for through in 0..=continuation.most {
        let Some(hit) = intersect(ctx, o, w) else {
            if from_glossy.is_some() {
                emitted += ctx.environment_hit(w, from_glossy, throughput);
            }
            break;
        };
        hit_any = true;
        let material = &scene.materials[scene.meshes[hit.mesh as usize].material];
        let view = hit.frame.to_local(-w);
        if from_glossy.is_some() {
            emitted += ctx.emission_hit(&hit, w, from_glossy, throughput);
        }
        let bsdf = material.bsdf_at(&scene.textures, hit.uv);
        let glossy = bsdf.alpha().is_some_and(|a| a < continuation.glossy_below);
        if !(continuation.through_glossy && glossy && through < continuation.most) {
            if let Some(lookup) = senders.lookup_at(hit.p, hit.mesh, hit.ng, -w, reader) {
                cached += throughput * senders.radiance_of(lookup);
            }
            break;
        }
        // A glossy hit: one emitter sample, then a BSDF sample onwards.
        let u = (sampler.next_1d(), sampler.next_2d());
        emitted += ctx.next_event(&hit, &bsdf, view, u, throughput);
        let (u0, u) = (sampler.next_1d(), sampler.next_2d());
        let Some(bs) = bsdf.sample(view, u0, u, TransportMode::Radiance) else {
            break;
        };
        throughput *= bs.weight;
        if !(max_component(throughput) > 0.0) || !throughput.is_finite() {
            break;
        }
        let dir = hit.frame.to_world(bs.wo).normalize();
        from_glossy = Some(bs.pdf);
        reader = hit.mesh;
        o = hit.spawn(dir);
        w = dir;
    }
    CacheRay {
        light: cached + emitted,
        emitted,
        hit: hit_any,
    }
}

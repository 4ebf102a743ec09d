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

use super::primary::Receiver;
use crate::bsdf::TransportMode;
use crate::gather::Senders;
use crate::geometry::offset::offset_origin;
use crate::sampler::{sobol02, Sampler};
use crate::spectrum::Rgb;
use crate::trace::{intersect, Tracer};
use glam::{Vec3, Vec3A};

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
        let origin = offset_origin(
            Vec3A::from(r.p),
            Vec3A::from(r.err),
            Vec3A::from(r.ng),
            Vec3A::from(w),
        );
        let Some(hit) = intersect(ctx, Vec3::from(origin), w) else {
            continue;
        };
        let towards = -w;
        if let Some(lookup) = senders.lookup_at(hit.p, hit.mesh, hit.ng, towards, r.mesh) {
            sum += sample.weight * senders.radiance_of(lookup);
        }
    }
    let l = r.weight * sum / spp as f32;
    if l.is_finite() {
        l
    } else {
        Rgb::ZERO
    }
}

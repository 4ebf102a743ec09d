//! A render receiver's brightest buffer pixels, traced: where one pixel holds much of the
//! light a receiver gathers, rays through equal parts of it find what the receiver sees there.
//!
//! A microbuffer resolves what it sees to its pixels (16 × 16 per hemisphere by default):
//! within a pixel, senders at different depths composite by coverage, so a layer behind a
//! partial occluder is dimmed by the pixel's open fraction as a whole. That is right when the
//! light behind is even over the pixel, and wrong when the occluder hides the brightest part
//! of it. The case that showed it is the one a light cache exists for: a small lamp turned to
//! face the ceiling, 10 cm below it, whose bright spot on the ceiling is hidden from the floor
//! below by the lamp itself. The spot lies in one or two pixels of a floor receiver's buffer
//! and the lamp covers a ninth of one, right in front of the spot's peak: the buffer counted
//! the spot as if the lamp hid an average ninth, and the floor's gathered light came out 10 to
//! 22 % too bright (rays into the same cache: within 2 % of the surfels' own sum with
//! visibility), the whole image 4–23 % by region.
//!
//! So after the cut (and the near field, and the cluster's shared buffer) is resolved, every
//! pixel holding more than a small share of the receiver's reflected or transmitted light is
//! traced instead, with as many rays as its share of the light calls for ([`TIERS`]: 64 rays
//! for a pixel holding more than 1/32 of it, down to 4 for one holding more than 1/512; a
//! glass receiver's transmitted pixels down to 1/4096 with one, [`TRANSMITTED_TIER`])
//! through the centres of equal-area parts of it (a fixed grid, the same for
//! every frame), each reading the cache where it hits as the near field's rays do
//! ([`cache_radiance_along`]), or going on through glossy hits ([`Retrace`]); the pixel takes
//! their mean. A pixel below the last share can be wrong by at most its own light, so the
//! error this leaves is bounded by the share (docs/render.md, "Bright pixels traced").

use super::near_field::cache_radiance_along;
use super::paths::{into_cache, CacheRay, Continuation};
use super::primary::Receiver;
use crate::bsdf::Bsdf;
use crate::gather::{Microbuffer, Senders};
use crate::sampler::Sampler;
use crate::spectrum::{luminance, Rgb};
use crate::trace::Tracer;

/// Which pixels are traced, and with how many rays: a pixel holding more than a tier's share
/// of the receiver's reflected light (by luminance) is traced with the tier's rays per side,
/// squared. Each tier's rays carry at most 1/2048 of the light each, so a pixel's rays are as
/// many as its light needs; a pixel below the last share is left as the cut splatted it, and
/// can be wrong by at most its own light. The first share is eight times a 16² buffer pixel's
/// under even light, and its 64 rays place an edge across the pixel to an eighth of its width.
/// Measured at 256² against Mitsuba's max_depth 64 (default caches): the first tier alone gave
/// relMSE 2.41e-4 (cbox-diffuse), 1.23e-3 (ceiling-diffuse), 7.2e-4 (cbox-rough), 6.4e-4
/// (cbox-mirror), 1.75e-3 (wall-glossy); the three, 1.99e-4, 5.9e-4, 4.9e-4, 4.0e-4, 1.23e-3,
/// for renders 2–3.1 times as long (one session, runs apart). Tiers of 16, 4 and 1 rays, or a
/// last tier of one ray, were worse on wall-glossy (2.5e-3, 1.6e-3): one ray cannot place an
/// edge.
pub const TIERS: [(f32, u32); 3] = [(1.0 / 32.0, 8), (1.0 / 128.0, 4), (1.0 / 512.0, 2)];

/// A glass receiver's transmitted pixels (its buffer's lower hemisphere: the inside of its
/// solid) below the last of [`TIERS`]' shares are traced too, with one ray each, down to this
/// share. The cut splats a solid's far side from inside as discs of a concave surface, whose
/// gaps leave the pixels partly covered: a rough glass sphere (α 0.1) under a white sky came
/// out 0.953 of the path tracer's light with [`TIERS`] alone, 0.982 with this tier (at 1/4096
/// and at 1/100 000 alike; tests/glass_furnace.rs). The inside of a solid is smooth light
/// seen through the solid's own far side, so one ray a pixel places it.
pub const TRANSMITTED_TIER: (f32, u32) = (1.0 / 4096.0, 1);

/// The rays per side for a pixel holding `share` of its receiver's light ([`TIERS`], and
/// [`TRANSMITTED_TIER`] for a `transmitted` one), if it is traced.
fn rays_per_side(share: f32, transmitted: bool) -> Option<u32> {
    let last = transmitted.then_some(&TRANSMITTED_TIER);
    TIERS
        .iter()
        .chain(last)
        .find(|&&(least, _)| share > least)
        .map(|&(_, side)| side)
}

/// A traced ray's light from emitters through glossy hits is capped at this many times the
/// luminance the cut found in its pixel (see [`Retrace`]). The cut reads a mirror's or clear
/// glass's directional maps, which blur a lamp seen in them, so its pixel is darker than what
/// the rays find there, and a low cap clips the light itself, not only the glints. Measured
/// at 256² with the default caches against Mitsuba's max_depth 64 (2 048 spp for the Cornell
/// boxes, 8 192 for caustic.gltf, noise taken out), caps of 16, 64 and 256: cbox-mirror
/// relMSE 3.95e-4, 2.44e-4, 2.23e-4; cbox-glossy 3.87e-4, 3.28e-4, 3.24e-4; cbox-rough
/// 2.32e-4, 2.27e-4, 2.30e-4; caustic.gltf 5.67e-4, 5.61e-4, 5.81e-4 (no cap: 5.99e-4, its
/// ceiling speckled where the sphere mirrors the lamp), its caustic spot 7.70e-3, 7.31e-3,
/// 7.21e-3; wall-glossy and ceiling-rough the same at every cap (docs/render.md, "The glint
/// cap measured again").
pub const GLINT_CAP: f32 = 64.0;

/// Sample indices of the bright pixels' streams start here, above any camera sample's and
/// the path-traced gather's.
const BRIGHT_STREAMS: u64 = 1 << 41;

/// How the bright pixels' rays go on through glossy hits (item 2 of issue 75, V-Ray's light
/// cache "retrace"): where a ray meets a surface smoother than the render's glossy threshold,
/// the cache's directional map there would blur the lobe (a glass sphere's caustic on the
/// floor, a gold box's reflection of the room), so the ray goes on as the path-traced gather's
/// do (`paths::into_cache`: next-event estimation and a BSDF sample at each glossy hit, the cache
/// read at the first rough one). What the cache holds beyond arrives smooth; the emitters seen
/// through the glossy hits are path-traced, and a glint (a small lamp mirrored in a sphere)
/// that one ray of a pixel's 64 finds would speckle the image, so that part of each ray is
/// capped at [`GLINT_CAP`] times the pixel's mean from the cut. Each ray's random numbers are
/// keyed by its receiver, pixel and place in the grid: the same image at any thread count,
/// and for every frame.
#[derive(Clone, Copy, Debug)]
pub struct Retrace {
    /// Where the rays read the cache.
    pub(crate) continuation: Continuation,
    /// The render's seed.
    pub(crate) seed: u64,
}

/// The light receiver `r` reflects towards its viewer through `bsdf` from `mb` (resolved),
/// as [`Microbuffer::convolve`] gives it, once the pixels that hold more than the last of
/// [`TIERS`]' shares of it are traced, replacing what the cut splatted there; and the rays
/// traced. The BSDF is evaluated over the buffer once ([`Microbuffer::bsdf_factors`]): where
/// no pixel is traced the convolution already made is the answer, and where some are, the
/// same factors convolve the traced light ([`Microbuffer::convolve_with`]), the same terms
/// summed in the same order as [`Microbuffer::convolve`].
///
/// With `retrace`, the rays go on through glossy hits ([`Retrace`]); without, each reads the
/// cache at its first hit.
///
/// A glass receiver's transmitted pixels are traced as its reflected ones are: rays into its
/// own solid, going on through (or reading the inward light at) its far side. (They were
/// left to the cut until the convolution integrated the BSDF over a lobe's pixels: at each
/// pixel's centre, the transmitted lobe came out 5–7 % dark, which the cut's light there,
/// wrong either way by scene, had hidden; docs/render.md, "Bright pixels traced".)
pub fn reflect_tracing_bright_pixels(
    ctx: &Tracer,
    senders: &Senders,
    r: &Receiver,
    mb: &mut Microbuffer,
    bsdf: &Bsdf,
    retrace: Option<Retrace>,
) -> (Rgb, u64) {
    // The BSDF is evaluated once per lit pixel; the convolution after tracing reuses it.
    let factors: Vec<(usize, Rgb)> = mb.bsdf_factors(bsdf, r.view).collect();
    let terms: Vec<(usize, Rgb)> = factors
        .iter()
        .map(|&(k, f)| (k, mb.convolved_term(k, f)))
        .collect();
    let reflected = terms.iter().fold(Rgb::ZERO, |a, &(_, b)| a + b);
    let total: f32 = terms.iter().map(|&(_, l)| luminance(l)).sum();
    if !(total > 0.0) || !total.is_finite() {
        return (reflected, 0);
    }
    let mut traced = 0;
    for (k, l) in terms {
        let transmitted = mb.pixels[k].dir.z < 0.0;
        let Some(side) = rays_per_side(luminance(l) / total, transmitted) else {
            continue;
        };
        let (mut sum, mut cos_sum, mut hits) = (Rgb::ZERO, Rgb::ZERO, 0);
        let directions = mb.pixel_directions(k, side);
        let cap = GLINT_CAP * luminance(mb.radiance[k]);
        for (j, &(local, cos)) in directions.iter().enumerate() {
            let w = mb.frame.to_world(local).normalize();
            let found = match retrace {
                Some(retrace) => {
                    let mut sampler = ray_sampler(retrace.seed, r, k, j);
                    let ray = into_cache(
                        ctx,
                        senders,
                        (r.spawn(w), w),
                        r.mesh,
                        retrace.continuation,
                        &mut sampler,
                    );
                    ray.hit.then(|| glint_capped(ray, cap))
                }
                None => cache_radiance_along(ctx, senders, r, w, f32::INFINITY).map(|(_, l)| l),
            };
            if let Some(radiance) = found {
                sum += radiance;
                cos_sum += radiance * cos;
                hits += 1;
            }
        }
        traced += directions.len() as u64;
        mb.set_traced(k, sum, cos_sum, hits, directions.len() as u32);
    }
    if traced == 0 {
        return (reflected, 0);
    }
    (mb.convolve_with(&factors), traced)
}

/// `ray`'s light with its emitted part's luminance capped at `cap` ([`GLINT_CAP`]).
fn glint_capped(ray: CacheRay, cap: f32) -> Rgb {
    let emitted = luminance(ray.emitted);
    if emitted > cap {
        ray.light - ray.emitted * (1.0 - cap / emitted)
    } else {
        ray.light
    }
}

/// The random numbers of ray `j` through pixel `k` of receiver `r`'s buffer: keyed by the
/// receiver (its image pixel, the quarter of it its sample came from, and the specular chain
/// that led to it), not by the order receivers are gathered in.
fn ray_sampler(seed: u64, r: &Receiver, k: usize, j: usize) -> Sampler {
    let receiver = u64::from(r.pixel) ^ (u64::from(r.quarter.map_or(4, u32::from)) << 32) ^ r.chain;
    Sampler::new(
        seed,
        receiver,
        BRIGHT_STREAMS + ((k as u64) << 12) + j as u64,
    )
}

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
//! pixel of the upper hemisphere holding more than [`BRIGHT_SHARE`] of the receiver's
//! reflected light is traced instead (a glass receiver's transmitted pixels keep the cut's
//! light: see [`reflect_tracing_bright_pixels`]): [`RAYS_PER_SIDE`]² rays through the centres of equal-area parts of it (a fixed
//! grid: no noise, the same for every frame), each reading the cache where it hits as the near
//! field's rays do ([`cache_radiance_along`]), and the pixel takes their mean. A pixel below
//! the share can be wrong by at most its own light, so the error this leaves is bounded by
//! the share; the spread of ordinary indirect light keeps every pixel below it in the five
//! reference scenes but a few (docs/render.md, "Bright pixels traced").

use super::near_field::cache_radiance_along;
use super::primary::Receiver;
use crate::bsdf::Bsdf;
use crate::gather::{Microbuffer, Senders};
use crate::spectrum::{luminance, Rgb};
use crate::trace::Tracer;

/// A pixel holding more than this share of a receiver's reflected light (by luminance) is
/// traced. Eight times the share of one of a 16² buffer's pixels under even light.
pub const BRIGHT_SHARE: f32 = 1.0 / 32.0;

/// Rays per side of a traced pixel's grid: 64 rays, each a 64th of the pixel, so an edge
/// across the pixel is placed to an eighth of its width.
pub const RAYS_PER_SIDE: u32 = 8;

/// The light receiver `r` reflects towards its viewer through `bsdf` from `mb` (resolved),
/// as [`Microbuffer::convolve`] gives it, once the pixels that hold more than
/// [`BRIGHT_SHARE`] of it are traced, replacing what the cut splatted there; and the rays
/// traced. Where no pixel is traced the convolution already made is the answer (the same
/// terms summed in the same order), so the BSDF is evaluated over the buffer once.
///
/// Only the upper hemisphere's: traced, a glass receiver's transmitted pixels (rays into its
/// own solid, reading the inward light where they leave it) made cbox-rough's sphere 7 % too
/// dark (its mean against the reference 0.974 → 0.898), a bias not yet understood.
pub fn reflect_tracing_bright_pixels(
    ctx: &Tracer,
    senders: &Senders,
    r: &Receiver,
    mb: &mut Microbuffer,
    bsdf: &Bsdf,
) -> (Rgb, u64) {
    let terms: Vec<(usize, Rgb)> = mb.convolved_pixels(bsdf, r.view).collect();
    let reflected = terms.iter().fold(Rgb::ZERO, |a, &(_, b)| a + b);
    let total: f32 = terms.iter().map(|&(_, l)| luminance(l)).sum();
    if !(total > 0.0) || !total.is_finite() {
        return (reflected, 0);
    }
    let mut traced = 0;
    for (k, l) in terms {
        if luminance(l) <= BRIGHT_SHARE * total || mb.pixels[k].dir.z < 0.0 {
            continue;
        }
        let (mut sum, mut cos_sum, mut hits) = (Rgb::ZERO, Rgb::ZERO, 0);
        let directions = mb.pixel_directions(k, RAYS_PER_SIDE);
        for &(local, cos) in &directions {
            let w = mb.frame.to_world(local).normalize();
            if let Some((_, radiance)) = cache_radiance_along(ctx, senders, r, w, f32::INFINITY) {
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
    (mb.convolve(bsdf, r.view), traced)
}

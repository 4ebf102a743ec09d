//! A render receiver's near field, traced: the leaves its cut finds too near to splat whole
//! are replaced by one ray through the centre of each pixel of its buffer that they reach.
//!
//! Surfels are discs that tile a surface only roughly: Poisson-disk centres leave gaps
//! between the discs and let them overhang the surface's edges by up to a radius. From afar
//! that averages out; within a few radii of a receiver it is what the receiver sees. The
//! Cornell box's light hangs 1 cm under the ceiling, about one disc radius at the default
//! 50 000 surfels: the ceiling above its rim, which sees the room only through that gap, took
//! the room's light through the gaps of the light's discs, at 10 to 15 times its true
//! brightness, and that row of pixels held a quarter of cbox-diffuse's relMSE at 512². The
//! contacts of boxes and spheres with the floor lit up the same way. The gather's split
//! leaves (`gather::cut`) place each disc's pieces exactly, but the gaps and overhangs are in
//! the discs themselves.
//!
//! So the render's cut sets its near leaves aside ([`NearLeaves::Aside`]), and from the
//! receiver a ray through the centre of each pixel that one of their discs, widened to twice
//! its radius for the gaps between discs ([`CAP_RADII`]), reaches finds the true surface, up
//! to the far edge of the farthest near leaf's disc. (Every pixel traced gave the same image
//! to relMSE 7e-8 on cbox-diffuse at 512², for 1.6 times the rays.) The cache's light there is read as the path-traced
//! gather reads it ([`Senders::lookup_at`]: the nearest surfel of the hit mesh facing the same
//! way; none, for the back of a one-sided emitter, is dark), covering the pixel; it hides
//! what the cut splatted at and behind it there, and on its surface (`Microbuffer::record_hits`). Beyond the
//! reach of the rays the cut's splats stand. A pixel's ray decides all of it, so the near
//! field is resolved to the buffer's pixels (16 × 16 by default), as the rest of it is.
//!
//! The bake keeps splitting its near leaves: its receivers are the surfels themselves, and
//! its transport is recorded link by link between surfels (`bake::bounce`), which a ray's hit
//! is not.
//!
//! [`NearLeaves::Aside`]: crate::gather::cut::NearLeaves::Aside

use super::primary::Receiver;
use crate::gather::lookup::Lookup;
use crate::gather::microbuffer::Sender;
use crate::gather::{Microbuffer, Senders};
use crate::spectrum::Rgb;
use crate::trace::{intersect_geometry_within, GeometricHit, Tracer};
use glam::Vec3;

/// Record in `mb` (its cut's senders recorded, not yet resolved) what receiver `r` sees
/// within reach of the near leaves `leaves` (surfel indices), one ray per pixel. Returns the
/// rays traced.
pub fn trace_near_field(
    ctx: &Tracer,
    senders: &Senders,
    r: &Receiver,
    mb: &mut Microbuffer,
    leaves: &[u32],
) -> u64 {
    // Each leaf's disc, widened for the gaps between discs, seen from the receiver: the
    // cosine and sine of the half-angle it subtends, around its local direction.
    let mut reach = 0.0f32;
    let caps: Vec<(Vec3, f32, f32)> = leaves
        .iter()
        .map(|&i| {
            let s = &senders.surfels[i as usize];
            let v = Vec3::from(s.p) - r.p;
            let (d, radius) = (v.length(), (s.area / std::f32::consts::PI).sqrt());
            reach = reach.max(d + radius);
            let sin = (CAP_RADII * radius / d).min(1.0);
            (
                mb.frame.to_local(v / d),
                (1.0 - sin * sin).max(0.0).sqrt(),
                sin,
            )
        })
        .collect();
    let mut found = Vec::new();
    let mut traced = 0;
    for (k, px) in mb.pixels.iter().enumerate() {
        // A pixel no widened disc reaches holds nothing the rays are for (the half-angle
        // of a cap of the pixel's solid angle, doubled for its corners, is added).
        let sin_px = (px.solid_angle / std::f32::consts::PI).sqrt().min(0.5) * 2.0;
        let cos_px = (1.0 - sin_px * sin_px).max(0.0).sqrt();
        let reached = caps
            .iter()
            .any(|&(dir, cos, sin)| cos <= 0.0 || px.dir.dot(dir) >= cos * cos_px - sin * sin_px);
        if !reached {
            continue;
        }
        traced += 1;
        let w = mb.frame.to_world(px.dir).normalize();
        let Some((found_hit, radiance)) = cache_radiance_along(ctx, senders, r, w, reach) else {
            continue;
        };
        let CacheHit { p, ng, t, lookup } = found_hit;
        let sender = Sender {
            offset: p - r.p,
            // The pixel's footprint there: what holds its depth together with the senders
            // of the same surface in the neighbouring pixels.
            radius: t * px.solid_angle.sqrt(),
            normal: ng,
            radiance,
            lookup,
        };
        found.push((k, sender));
    }
    mb.record_hits(&found);
    traced
}

/// Where a receiver's ray met the scene, and where the cache's light there is read.
pub struct CacheHit {
    /// The hit point.
    pub p: Vec3,
    /// Its unit geometric normal (front face).
    pub ng: Vec3,
    /// The distance to it.
    pub t: f32,
    /// The cache's radiance there towards the receiver ([`Senders::lookup_at`]).
    pub lookup: Lookup,
}

/// What receiver `r` sees along unit direction `w` within `t_max`: the hit and the cache's
/// reflected radiance there towards it, read as the path-traced gather reads it (the nearest
/// surfel of the hit mesh facing the same way; none, for the back of a one-sided emitter, is
/// dark). `None` where the ray leaves the scene.
pub fn cache_radiance_along(
    ctx: &Tracer,
    senders: &Senders,
    r: &Receiver,
    w: Vec3,
    t_max: f32,
) -> Option<(CacheHit, Rgb)> {
    let GeometricHit { p, ng, hit, .. } = intersect_geometry_within(ctx, r.spawn(w), w, t_max)?;
    let lookup = senders
        .lookup_at(p, hit.mesh, ng, -w, r.mesh)
        .unwrap_or(Lookup::Nothing);
    let radiance = senders.evaluated(lookup);
    Some((
        CacheHit {
            p,
            ng,
            t: hit.t,
            lookup,
        },
        radiance,
    ))
}

/// How far round a near leaf's disc, in its radii, rays are traced: twice the disc, for the
/// gaps between discs (Poisson-disk centres leave no point of a surface more than about a
/// radius from one).
pub const CAP_RADII: f32 = 2.0;

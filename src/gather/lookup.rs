//! Where a sender's radiance towards a receiver is read, decided from geometry alone.
//!
//! A gather decides, for every sender it splats, which stored quantity gives the sender's
//! radiance in the receiver's direction: a surfel's RGB value, a texel of a surfel's map, a
//! node's exact diffuse radiance (S·ω)/(N·ω), or a texel of a node's radiant intensity over its
//! projected area. That decision depends only on positions, normals and projected areas, never
//! on the radiance itself. The final render evaluates a [`Lookup`] at once against the cache's
//! maps ([`super::senders::Senders::radiance_of`]); the bake records it once and evaluates it
//! against every bounce's light (`bounce::transport`), so that later bounces repeat no geometry.

use glam::{Vec2, Vec3};

/// The address of a sender's radiance towards one receiver (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lookup {
    /// Nothing reaches the receiver (a hidden back face, a solid's inward light).
    Nothing,
    /// The RGB radiance of surfel `surfel` (a diffuse surfel seen from its front).
    SurfelRgb { surfel: u32 },
    /// The map of surfel `surfel` at the texel holding `point` of its unit square; `front`:
    /// seen from the front, where its emission (which the gather must not see) leaves.
    SurfelMap {
        surfel: u32,
        point: Vec2,
        front: bool,
    },
    /// Node `node`'s exact diffuse radiance S·`u`, per channel, with S = Σ A L n over its
    /// surfels and `u` = ω/(N·ω) (every surfel below diffuse and facing ω).
    NodeNormal { node: u32, u: Vec3 },
    /// Node `node`'s radiant intensity at the texel holding `point`, times `scale` (one over
    /// the projected area it is divided by).
    NodeMap { node: u32, point: Vec2, scale: f32 },
}

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
    /// The RGB radiance of a diffuse surfel seen from its front.
    SurfelRgb {
        /// The surfel.
        surfel: u32,
    },
    /// A surfel's map at one texel.
    SurfelMap {
        /// The surfel.
        surfel: u32,
        /// The point of the map's unit square whose texel is read.
        point: Vec2,
        /// Seen from the front, where its emission (which the gather must not see) leaves.
        front: bool,
    },
    /// A node's exact diffuse radiance S·`u`, per channel, with S = Σ A L n over its surfels
    /// (every surfel below diffuse and facing ω).
    NodeNormal {
        /// The node.
        node: u32,
        /// ω/(N·ω), N = Σ A n over its surfels.
        u: Vec3,
    },
    /// A node's radiant intensity at one texel, divided by its projected area.
    NodeMap {
        /// The node.
        node: u32,
        /// The point of the map's unit square whose texel is read.
        point: Vec2,
        /// One over the projected area.
        scale: f32,
    },
}

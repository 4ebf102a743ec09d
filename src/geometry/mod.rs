//! Geometric building blocks: shading frames, sampling warps, solid-angle sampling of triangles, special functions, the watertight
//! ray–triangle test and self-intersection-free ray offsets.

pub mod frame;
pub mod offset;
pub mod special;
pub mod spherical_triangle;
pub mod triangle;
pub mod warp;

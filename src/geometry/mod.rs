//! Geometric building blocks: shading frames, sampling warps, solid-angle sampling of triangles, a triangle's projected solid angle, special functions, the watertight
//! ray–triangle test and self-intersection-free ray offsets.

pub mod frame;
pub mod offset;
pub mod polygon_irradiance;
pub mod special;
pub mod spherical_triangle;
pub mod triangle;
pub mod warp;

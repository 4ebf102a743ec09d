//! Geometric building blocks: shading frames, sampling warps, special functions, the watertight
//! ray–triangle test and self-intersection-free ray offsets.

pub mod frame;
pub mod offset;
pub mod special;
pub mod triangle;
pub mod warp;

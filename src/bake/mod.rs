//! The bake (DESIGN.md §5): surfels, their direct light, the surfel tree and its wavelet coding.

pub mod direct;
pub mod lightcuts;
pub mod pipeline;
pub mod plan;
pub mod store;

pub use direct::DirectLight;
pub use pipeline::{bake, bake_cancellable, BakeSettings, Baked, Quality};
pub use plan::Plan;

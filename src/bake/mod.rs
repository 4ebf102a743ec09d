//! The bake (docs/design.md §5): surfels, their direct light, the surfel tree and its wavelet coding.

pub mod baked;
pub mod bounce;
pub mod direct;
pub mod lightcuts;
pub mod pipeline;
pub mod plan;
pub mod relight;
pub mod settings;
pub mod store;

pub use baked::Baked;
pub use direct::DirectLight;
pub use pipeline::{bake, bake_cancellable, bake_with_transport};
pub use plan::Plan;
pub use settings::{BakeSettings, Quality};

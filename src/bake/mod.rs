//! The bake (DESIGN.md §5): surfels, their direct light, the surfel tree and its wavelet coding.

pub mod coding;
pub mod direct;
pub mod lightcuts;
pub mod pipeline;
pub mod plan;
pub mod surfels;
pub mod tree;

pub use coding::{encode, node_sums, CodedTree, NodeCoding};
pub use direct::DirectLight;
pub use pipeline::{bake, bake_cancellable, BakeSettings, Baked, Quality, SurfelRadiance};
pub use plan::Plan;
pub use surfels::{sample_surfels, sample_surfels_with_density, Surfel};
pub use tree::{Node, SurfelTree};

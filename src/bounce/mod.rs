//! Multi-bounce light in the cache (DESIGN.md §5.7–§5.8, spec §8).

pub mod bsdf_operator;
pub mod iterate;
pub mod receivers;
pub mod transport;
pub mod view_tree;

pub use bsdf_operator::BsdfOperator;
pub use iterate::{add_bounces, BounceReport, BounceSettings, TransportReport};

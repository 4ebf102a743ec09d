//! Multi-bounce light in the cache (docs/design.md §5.7–§5.8, docs/method.md §8).

pub mod bsdf_operator;
pub mod iterate;
pub mod kept;
pub mod receivers;
pub mod report;
pub mod run;
pub mod settings;
pub mod transport;
pub mod view_tree;

pub use bsdf_operator::BsdfOperator;
pub use iterate::add_bounces;
pub use kept::{KeptProjected, KeptTransport, TransportHandoff};
pub use report::{BounceReport, TransportReport};
pub use settings::BounceSettings;

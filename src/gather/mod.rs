//! The final gather from the cache (docs/design.md §7, docs/method.md §2.3, §3, §7).

pub mod cut;
pub mod fpbgi;
pub mod lookup;
pub mod microbuffer;
pub mod nearest;
pub mod senders;

pub use cut::{splat_cut, CutStats};
pub use microbuffer::Microbuffer;
pub use senders::Senders;

//! The final gather from the cache (DESIGN.md §7, spec §2.3, §3, §7).

pub mod microbuffer;

pub use microbuffer::Microbuffer;

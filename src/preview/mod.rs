//! The Vulkan previewer (DESIGN.md §8, spec §9): splatting the cache with ash, headless and in a
//! window. Built so far: the device ([`device`]).

pub mod device;

//! # wpbgi
//!
//! Noise-free global illumination for glTF and USD pipelines. wpbgi reads a scene whose
//! materials are Mitsuba 3's `diffuse`, `roughconductor` and `roughdielectric`, bakes its light
//! into a cache (surfels whose outgoing radiance is kept as sparse Haar wavelets over
//! directions, in a bounding-sphere tree, with multiple bounces), and renders final frames from
//! that cache. A reference path tracer with Mitsuba's semantics ([`reference`](mod@reference))
//! is the ground truth every faster method is measured against.
//!
//! The front door is re-exported here: [`Scene`], [`BakeSettings`] and [`bake()`], the
//! [`Cache`] a bake writes and a render reads, [`RenderSettings`] and [`render()`], the Vulkan
//! [`Preview`], and [`Error`]. The library never prints and never exits: every fallible
//! operation returns [`Error`], whose message is one sentence naming the file, the object or
//! the setting at fault, and long operations report progress through a callback. Settings
//! start from their defaults (those of the `wpbgi` command) and refuse a field out of range
//! (`validate()`).
//!
//! Bake the bundled Cornell box, save the cache, and render a frame from it:
//!
//! ```
//! use wpbgi::{bake, render, BakeSettings, Cache, Quality, RenderSettings, Scene};
//! # fn main() -> Result<(), wpbgi::Error> {
//! let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cbox-rough.gltf"));
//! let scene = Scene::load(path)?;
//! // The draft preset, smaller still; bounces are automatic, as with `wpbgi bake`.
//! let settings = BakeSettings { points: 4000, ..BakeSettings::preset(Quality::Draft) };
//! let baked = bake(&scene, &settings, &|_stage, _fraction| {})?;
//! let cache_path = std::env::temp_dir().join(format!("wpbgi-doc-{}.wpc", std::process::id()));
//! wpbgi::bake::store::save(&cache_path, &scene, &baked)?;
//!
//! // Any later process: open the cache (refused if the scene changed since) and render.
//! let cache = Cache::open_fresh(&scene, &cache_path)?;
//! let camera = scene.default_camera(64, 64)?;
//! let frame = render(&scene, &cache, &camera, &RenderSettings::default(), &|_, _| {})?;
//! assert!(frame.beauty.pixels.iter().all(|p| p.is_finite()));
//! let image_path = std::env::temp_dir().join(format!("wpbgi-doc-{}.exr", std::process::id()));
//! wpbgi::image::write_exr(&image_path, &frame.beauty)?;
//! # std::fs::remove_file(&cache_path).ok();
//! # std::fs::remove_file(&image_path).ok();
//! # Ok(()) }
//! ```

// `!(x > y)` is the idiom throughout for "fails unless x > y", which rejects NaN as well; the
// `partial_cmp` form clippy suggests would hide that intent.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Every public item says what it is: the crate is read as much as it is called.
#![warn(missing_docs)]

pub mod accel;
pub mod assemble;
pub mod atomic;
pub mod bake;
pub mod bsdf;
pub mod cache;
pub mod compare;
pub mod denoise;
pub mod emitters;
pub mod error;
pub mod fast_hash;
#[doc(hidden)]
pub mod fuzzing;
pub mod gather;
pub mod geometry;
pub mod haar;
pub mod image;
pub mod machine;
pub mod preview;
pub mod progress;
pub mod reference;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod spectrum;
pub mod surfels;
pub mod trace;
pub(crate) mod validate;

pub use bake::{bake, BakeSettings, Quality};
/// A baked cache, read and validated: what [`render()`] and [`Preview`] draw from.
pub use cache::store::BakedCache as Cache;
pub use error::Error;
pub use preview::Preview;
/// The final render from a [`Cache`].
pub use render::render_final as render;
/// The settings of the final render ([`render()`]).
pub use render::FinalSettings as RenderSettings;
pub use scene::Scene;

/// This crate's version, as caches record it (it enters their hash).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The README's Rust example, compiled as a doc test so that it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub(crate) struct ReadmeDoctests;

//! # wpbgi
//!
//! Wavelet point-based global illumination for glTF and USD pipelines. This crate reads a scene
//! whose materials are Mitsuba 3's `diffuse`, `roughconductor` and `roughdielectric`, and renders
//! it; the reference path tracer in [`reference`](mod@reference) is the ground truth that every faster method in
//! the crate is measured against.
//!
//! The library never prints and never exits: every fallible operation returns
//! [`Error`], and long operations report progress through a callback.
//!
//! ```no_run
//! use wpbgi::{reference::{render, RenderSettings}, scene::Scene};
//! # fn main() -> Result<(), wpbgi::Error> {
//! let scene = Scene::load("scene.gltf".as_ref())?;
//! let settings = RenderSettings { spp: 16, max_depth: 8, ..Default::default() };
//! let camera = scene.default_camera(256, 256)?;
//! let out = render(&scene, &camera, &settings, &|_| {})?;
//! wpbgi::image::write_exr(std::path::Path::new("out.exr"), &out.mean)?;
//! # Ok(()) }
//! ```

// `!(x > y)` is the idiom throughout for "fails unless x > y", which rejects NaN as well; the
// `partial_cmp` form clippy suggests would hide that intent.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

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
#[doc(hidden)]
pub mod fuzzing;
pub mod gather;
pub mod geometry;
pub mod haar;
pub mod image;
pub mod machine;
pub mod preview;
pub mod reference;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod spectrum;
pub mod surfels;
pub mod trace;
pub(crate) mod validate;

pub use error::Error;

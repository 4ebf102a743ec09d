//! What a comparison measured: the reference image, each run's method, times, memory and
//! error, and the report that holds them (written out by [`super::Report::write`]).

use crate::bake::Quality;
use crate::image::Image;
use serde_json::{json, Value};
use std::path::PathBuf;

/// The image every run is measured against.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The reference image.
    pub image: Image,
    /// The file it was read from, or `None` when it was rendered here.
    pub path: Option<PathBuf>,
    /// For a rendered reference: its samples per pixel and seconds.
    pub spp: Option<u32>,
    /// Its render time (a rendered reference).
    pub seconds: Option<f64>,
}

/// Which method made a run's image.
#[derive(Clone, Debug, PartialEq)]
pub enum Method {
    /// Bake at a preset, then the final render from the cache.
    Cache {
        /// The bake's preset.
        preset: Quality,
        /// Its surfel count.
        points: usize,
    },
    /// The path tracer at `spp` samples per pixel (a point of its progressive render).
    PathTracer {
        /// Samples per pixel.
        spp: u32,
    },
    /// The same image denoised ([`crate::reference::RenderOutput::denoised`]); its seconds
    /// include the first hits' and the denoiser's.
    Denoised {
        /// Samples per pixel before denoising.
        spp: u32,
    },
}

impl Method {
    /// The method's name in the report.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Cache { .. } => "wpbgi",
            Method::PathTracer { .. } => "path tracer",
            Method::Denoised { .. } => "path tracer + OIDN",
        }
    }

    /// The method as tables and plots label it: the cache with its preset, the path tracer
    /// with its samples per pixel.
    pub fn label(&self) -> String {
        match self {
            Method::Cache { preset, .. } => format!("wpbgi {}", preset.name()),
            Method::PathTracer { spp } | Method::Denoised { spp } => {
                format!("{}, {spp} spp", self.name())
            }
        }
    }
}

/// One measured run.
#[derive(Clone, Debug)]
pub struct Run {
    /// The method that made the image.
    pub method: Method,
    /// Seconds spent baking (0 for the path tracers).
    pub bake_seconds: f64,
    /// Seconds spent rendering the image.
    pub render_seconds: f64,
    /// Peak resident memory during the run (bytes), where the OS tells it.
    pub peak_memory: Option<u64>,
    /// Mean squared error against the reference.
    pub mse: f64,
    /// Relative MSE: the mean over pixels and channels of (x − ref)² / (ref² + 0.01).
    pub rel_mse: f64,
    /// Mean structural similarity with the reference.
    pub mssim: f64,
}

impl Run {
    /// Bake plus render.
    pub fn total_seconds(&self) -> f64 {
        self.bake_seconds + self.render_seconds
    }

    /// The run's label (see [`Method::label`]).
    pub fn label(&self) -> String {
        self.method.label()
    }

    pub(super) fn to_json(&self) -> Value {
        let (preset, extra) = match &self.method {
            Method::Cache { preset, points } => (Some(preset.name()), json!({ "surfels": points })),
            Method::PathTracer { spp } | Method::Denoised { spp } => (None, json!({ "spp": spp })),
        };
        let mut v = json!({
            "method": self.method.name(),
            "preset": preset,
            "bake_s": self.bake_seconds,
            "render_s": self.render_seconds,
            "total_s": self.total_seconds(),
            "peak_memory_bytes": self.peak_memory,
            "mse": self.mse,
            "rel_mse": self.rel_mse,
            "mssim": self.mssim,
        });
        if let (Some(o), Some(e)) = (v.as_object_mut(), extra.as_object()) {
            o.extend(e.clone());
        }
        v
    }
}

/// Every run of a comparison and what they were compared against.
#[derive(Clone, Debug)]
pub struct Report {
    /// The scene compared on.
    pub scene: PathBuf,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Worker threads every run used.
    pub threads: usize,
    /// What the runs are measured against.
    pub reference: Reference,
    /// The cache's runs (one per preset), then the path tracer's and the denoised path
    /// tracer's, each in the order of its samples.
    pub runs: Vec<Run>,
    /// Why the denoised curve is missing (the denoiser did not load), if it is.
    pub denoiser_missing: Option<String>,
}

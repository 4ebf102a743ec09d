//! Error against run time (DESIGN.md §9): the cache's bake and final render at several quality
//! presets, and the path tracer given the same wall time as each, all measured against one
//! reference image.
//!
//! Each run records its bake and render seconds, its peak memory (the process's resident set,
//! reset before the run where the OS allows, see [`memory`]), and its error against the
//! reference: MSE, relative MSE (Σ (x − r)² / (r² + 0.01), the metric the tests use) and MSSIM
//! of the sRGB images (`image-compare`, 8 × 8 windows; 1 is identical), a structural metric
//! that noise and blur both lower. [`Report::write`] writes `report.json`,
//! `error_vs_time.svg`, `error_vs_time.png` and `summary.md`.

pub mod memory;
mod plot;

use crate::atomic::write_atomically;
use crate::bake::{bake, BakeSettings, Quality};
use crate::bounce::BounceSettings;
use crate::cache::store::BakedCache;
use crate::error::{Error, Result};
use crate::image::{error_against, srgb8, Image};
use crate::reference::{render, RenderSettings};
use crate::render::{render_final, FinalSettings};
use crate::scene::{Camera, Scene};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// What to compare.
#[derive(Clone, Debug)]
pub struct CompareSettings {
    /// Bake presets, each baked and rendered once.
    pub presets: Vec<Quality>,
    /// Samples per pixel of the reference when none is given.
    pub reference_spp: u32,
    /// The bakes' indirect bounces (`wpbgi bake`'s default: automatic).
    pub bounces: BounceSettings,
    pub final_settings: FinalSettings,
    pub seed: u64,
}

impl Default for CompareSettings {
    fn default() -> Self {
        CompareSettings {
            presets: vec![Quality::Draft, Quality::Preview, Quality::Final],
            reference_spp: 1024,
            bounces: BounceSettings::auto(),
            final_settings: FinalSettings::default(),
            seed: 0,
        }
    }
}

/// The image every run is measured against.
#[derive(Clone, Debug)]
pub struct Reference {
    pub image: Image,
    /// The file it was read from, or `None` when it was rendered here.
    pub path: Option<PathBuf>,
    /// For a rendered reference: its samples per pixel and seconds.
    pub spp: Option<u32>,
    pub seconds: Option<f64>,
}

impl Reference {
    /// Path-trace the reference at `spp` samples per pixel.
    pub fn render(
        scene: &Scene,
        camera: &Camera,
        spp: u32,
        seed: u64,
        progress: &(dyn Fn(f32) + Sync),
    ) -> Result<Reference> {
        let settings = RenderSettings {
            spp,
            seed: seed ^ 0x7265_6665_7265_6e63,
            ..Default::default()
        };
        let out = render(scene, camera, &settings, progress)?;
        Ok(Reference {
            image: out.mean,
            path: None,
            spp: Some(out.spp),
            seconds: Some(out.seconds),
        })
    }
}

/// Which method made a run's image.
#[derive(Clone, Debug, PartialEq)]
pub enum Method {
    /// Bake at a preset, then the final render from the cache.
    Cache { preset: Quality, points: usize },
    /// The path tracer, given the wall time of the cache run at `matched`.
    PathTracer { matched: Quality, spp: u32 },
}

/// One measured run.
#[derive(Clone, Debug)]
pub struct Run {
    pub method: Method,
    pub bake_seconds: f64,
    pub render_seconds: f64,
    /// Peak resident memory during the run (bytes), where the OS tells it.
    pub peak_memory: Option<u64>,
    pub mse: f64,
    pub rel_mse: f64,
    pub mssim: f64,
}

impl Run {
    pub fn total_seconds(&self) -> f64 {
        self.bake_seconds + self.render_seconds
    }

    pub fn label(&self) -> String {
        match &self.method {
            Method::Cache { preset, .. } => format!("wpbgi {}", preset.name()),
            Method::PathTracer { matched, .. } => {
                format!("path tracer ({} time)", matched.name())
            }
        }
    }

    fn to_json(&self) -> Value {
        let (method, preset, extra) = match &self.method {
            Method::Cache { preset, points } => {
                ("wpbgi", preset.name(), json!({ "surfels": points }))
            }
            Method::PathTracer { matched, spp } => {
                ("path tracer", matched.name(), json!({ "spp": spp }))
            }
        };
        let mut v = json!({
            "method": method,
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
    pub scene: PathBuf,
    pub width: u32,
    pub height: u32,
    pub threads: usize,
    pub reference: Reference,
    pub runs: Vec<Run>,
}

/// Refuse a reference of another size than the render's (`width` × `height`), before any
/// work, in one sentence.
pub fn check_size(reference: &Image, width: u32, height: u32) -> std::result::Result<(), String> {
    if (reference.width, reference.height) == (width, height) {
        Ok(())
    } else {
        Err(size_mismatch(reference, width, height))
    }
}

fn size_mismatch(reference: &Image, width: u32, height: u32) -> String {
    format!(
        "the reference image is {}x{} but the render is {width}x{height}",
        reference.width, reference.height
    )
}

/// An image's error against the reference: (MSE, relative MSE, MSSIM).
pub fn errors(image: &Image, reference: &Image) -> Result<(f64, f64, f64)> {
    let (mse, rel) = error_against(image, reference).ok_or_else(|| {
        Error::InvalidSetting(size_mismatch(reference, image.width, image.height))
    })?;
    Ok((mse, rel, mssim(image, reference)))
}

/// MSSIM of the two images' 8-bit sRGB encodings (clamped, no tone mapping), the worst of
/// the three channels.
fn mssim(a: &Image, b: &Image) -> f64 {
    let rgb8 = |img: &Image| {
        let bytes = img
            .pixels
            .iter()
            .flat_map(|p| [srgb8(p.x), srgb8(p.y), srgb8(p.z)])
            .collect();
        image::RgbImage::from_raw(img.width, img.height, bytes)
    };
    match (rgb8(a), rgb8(b)) {
        (Some(x), Some(y)) => {
            image_compare::rgb_similarity_structure(&image_compare::Algorithm::MSSIMSimple, &x, &y)
                .map_or(f64::NAN, |s| s.score)
        }
        _ => f64::NAN,
    }
}

/// Bake and render `scene` at each preset, and path-trace it for as long as each took;
/// `progress` gets the stage and its fraction done.
pub fn compare(
    scene: &Scene,
    camera: &Camera,
    reference: Reference,
    settings: &CompareSettings,
    progress: &(dyn Fn(&str, f32) + Sync),
) -> Result<Report> {
    if settings.presets.is_empty() {
        return Err(Error::InvalidSetting(
            "compare needs at least one preset".into(),
        ));
    }
    let mut runs = Vec::new();
    for &preset in &settings.presets {
        let name = preset.name();
        // The cache: bake in memory, then render from it.
        memory::reset_peak();
        let bake_settings = BakeSettings {
            seed: settings.seed,
            bounces: settings.bounces,
            ..BakeSettings::from_quality(preset)
        };
        let start = Instant::now();
        let baked = bake(scene, &bake_settings, &|stage, f| {
            progress(&format!("{name}: baking ({stage})"), f)
        })?;
        let cache = BakedCache::in_memory(&scene.path, &baked)?;
        let bake_seconds = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let final_settings = FinalSettings {
            seed: settings.seed,
            ..settings.final_settings.clone()
        };
        let out = render_final(scene, &cache, camera, &final_settings, &|stage, f| {
            progress(&format!("{name}: rendering ({stage})"), f)
        })?;
        let render_seconds = start.elapsed().as_secs_f64();
        let peak_memory = memory::peak();
        drop((baked, cache));
        let (mse, rel_mse, mssim) = errors(&out.beauty, &reference.image)?;
        let cached = Run {
            method: Method::Cache {
                preset,
                points: bake_settings.points,
            },
            bake_seconds,
            render_seconds,
            peak_memory,
            mse,
            rel_mse,
            mssim,
        };
        // The path tracer in the same wall time.
        memory::reset_peak();
        let budget = cached.total_seconds();
        let pt = render(
            scene,
            camera,
            &RenderSettings {
                spp: 1,
                seed: settings.seed,
                time_limit: Some(Duration::from_secs_f64(budget.max(1e-3))),
                ..Default::default()
            },
            &|f| progress(&format!("{name}: path tracing"), f),
        )?;
        let (mse, rel_mse, mssim) = errors(&pt.mean, &reference.image)?;
        let traced = Run {
            method: Method::PathTracer {
                matched: preset,
                spp: pt.spp,
            },
            bake_seconds: 0.0,
            render_seconds: pt.seconds,
            peak_memory: memory::peak(),
            mse,
            rel_mse,
            mssim,
        };
        runs.push(cached);
        runs.push(traced);
    }
    Ok(Report {
        scene: scene.path.clone(),
        width: camera.width,
        height: camera.height,
        threads: rayon::current_num_threads(),
        reference,
        runs,
    })
}

impl Report {
    /// The report as `report.json` holds it (documented in the README).
    pub fn to_json(&self) -> Value {
        json!({
            "scene": self.scene.display().to_string(),
            "width": self.width,
            "height": self.height,
            "threads": self.threads,
            "wpbgi_version": env!("CARGO_PKG_VERSION"),
            "reference": {
                "path": self.reference.path.as_ref().map(|p| p.display().to_string()),
                "spp": self.reference.spp,
                "seconds": self.reference.seconds,
            },
            "runs": self.runs.iter().map(Run::to_json).collect::<Vec<_>>(),
        })
    }

    /// A short Markdown summary: the table of runs and how the two methods compare.
    pub fn summary_markdown(&self) -> String {
        let mut s = format!(
            "# wpbgi compare: {}\n\n{}×{}, {} threads. Reference: {}.\n\n",
            self.scene.display(),
            self.width,
            self.height,
            self.threads,
            match (
                &self.reference.path,
                self.reference.spp,
                self.reference.seconds
            ) {
                (Some(p), _, _) => format!("`{}`", p.display()),
                (None, Some(spp), Some(t)) => format!("path traced here, {spp} spp in {t:.1} s"),
                _ => "path traced here".into(),
            }
        );
        s += "| run | bake s | render s | total s | peak MB | MSE | relMSE | MSSIM |\n";
        s += "|---|---:|---:|---:|---:|---:|---:|---:|\n";
        for r in &self.runs {
            let memory = r
                .peak_memory
                .map_or("–".to_string(), |b| format!("{}", b / 1_000_000));
            s += &format!(
                "| {} | {:.2} | {:.2} | {:.2} | {memory} | {:.3e} | {:.3e} | {:.4} |\n",
                r.label(),
                r.bake_seconds,
                r.render_seconds,
                r.total_seconds(),
                r.mse,
                r.rel_mse,
                r.mssim
            );
        }
        s += "\n";
        for pair in self.runs.chunks(2) {
            if let [cache, traced] = pair {
                let ratio = traced.rel_mse / cache.rel_mse.max(f64::MIN_POSITIVE);
                s += &format!(
                    "- {}: in {:.2} s the cache reaches relMSE {:.3e}; the path tracer, in the \
                     same time, {:.3e} ({}).\n",
                    cache.label(),
                    cache.total_seconds(),
                    cache.rel_mse,
                    traced.rel_mse,
                    if ratio >= 1.0 {
                        format!("{ratio:.1}× the cache's error")
                    } else {
                        format!("{:.1}× less than the cache's", 1.0 / ratio)
                    }
                );
            }
        }
        s += "\nThe plot: `error_vs_time.svg` / `.png` (relMSE against total seconds, log-log).\n";
        s
    }

    /// Write `report.json`, `error_vs_time.svg`, `error_vs_time.png` and `summary.md` into
    /// `dir` (created if needed), each atomically.
    pub fn write(&self, dir: &Path) -> Result<()> {
        std::fs::create_dir_all(dir).map_err(|e| Error::Output {
            path: dir.to_path_buf(),
            reason: e.to_string(),
        })?;
        let text = |name: &str, body: String| {
            write_atomically(&dir.join(name), |tmp| {
                std::fs::write(tmp, body).map_err(|e| e.to_string())
            })
        };
        let json = serde_json::to_string_pretty(&self.to_json()).map_err(|e| Error::Output {
            path: dir.join("report.json"),
            reason: e.to_string(),
        })?;
        text("report.json", json + "\n")?;
        text(
            "error_vs_time.svg",
            plot::svg(self).map_err(|e| Error::Output {
                path: dir.join("error_vs_time.svg"),
                reason: e,
            })?,
        )?;
        let (w, h, rgb) = plot::png_pixels(self).map_err(|e| Error::Output {
            path: dir.join("error_vs_time.png"),
            reason: e,
        })?;
        crate::image::write_png_rgb8(&dir.join("error_vs_time.png"), w, h, &rgb)?;
        text("summary.md", self.summary_markdown())
    }
}

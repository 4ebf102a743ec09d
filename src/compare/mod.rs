//! Error against run time (docs/design.md §9): the cache's bake and final render at several quality
//! presets, one point each, against the path tracer's whole curve (one progressive render, its
//! image at 1, 2, 4, … samples per pixel, up to the longest cache run's time) and the same
//! curve denoised by Intel Open Image Denoise with the guides a user would give it (the
//! first hit's albedo and normal): what a user would pick instead of baking. All are measured
//! against one reference image.
//!
//! Each run records its bake and render seconds, its peak memory (the process's resident set,
//! reset before the run where the OS allows, see [`memory`]), and its error against the
//! reference: MSE, relative MSE (Σ (x − r)² / (r² + 0.01), the metric the tests use) and MSSIM
//! of the sRGB images (`image-compare`, 8 × 8 windows; 1 is identical), a structural metric
//! that noise and blur both lower. [`Report::write`] writes `report.json`,
//! `error_vs_time.svg`, `error_vs_time.png` and `summary.md`.

pub mod memory;
mod plot;
pub mod report;
pub mod shot;

pub use report::{Method, Reference, Report, Run};

use crate::atomic::write_atomically;
use crate::bake::bounce::BounceSettings;
use crate::bake::{bake, BakeSettings, Quality};
use crate::cache::store::BakedCache;
use crate::error::{Error, Result};
use crate::image::{error_against, srgb8, Image};
use crate::progress::Progress;
use crate::reference::{render, RenderOutput, RenderSettings};
use crate::render::{render_final, FinalSettings};
use crate::scene::{Camera, Scene};
use crate::validate::{require, require_positive};
use serde_json::{json, Value};
use std::path::Path;
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
    /// The cache's final render (its gather, samples, microbuffer).
    pub final_settings: FinalSettings,
    /// Seed of the path tracer's samples.
    pub seed: u64,
}

impl CompareSettings {
    /// Refuse a field out of range, in a sentence that names it ([`compare`] calls this
    /// first).
    pub fn validate(&self) -> Result<()> {
        const S: &str = "CompareSettings";
        require(
            !self.presets.is_empty(),
            S,
            "presets",
            "empty",
            "at least one preset",
        )?;
        require_positive(S, "reference_spp", self.reference_spp as u64)?;
        self.bounces.validate()?;
        self.final_settings.validate()
    }
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

/// Mixed into the seed of a reference rendered here, so that its samples are not the path
/// tracer's under comparison.
const REFERENCE_SEED: u64 = 0x7265_6665_7265_6e63;

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
            seed: seed ^ REFERENCE_SEED,
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

/// A path-traced render's seconds without those spent keeping its first hits (which only the
/// denoiser needs).
fn traced_seconds(out: &RenderOutput) -> f64 {
    out.seconds - out.first_hits.as_ref().map_or(0.0, |h| h.seconds)
}

/// `out` denoised, with the seconds of the render and the denoiser together; `None`, with
/// `missing` saying why, when the denoiser fails (and from then on, without trying again).
fn denoise(out: &RenderOutput, missing: &mut Option<String>) -> Option<(Image, f64)> {
    if missing.is_some() {
        return None;
    }
    let start = Instant::now();
    match out.denoised(rayon::current_num_threads()) {
        Some(Ok(image)) => Some((image, out.seconds + start.elapsed().as_secs_f64())),
        Some(Err(e)) => {
            *missing = Some(e.to_string());
            None
        }
        None => {
            *missing = Some("the render kept no first hits".into());
            None
        }
    }
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
    progress: Progress,
) -> Result<Report> {
    settings.validate()?;
    let mut runs = Vec::new();
    for &preset in &settings.presets {
        let name = preset.name();
        // The cache: bake in memory, then render from it.
        memory::reset_peak();
        let (cache, points, bake_seconds) = bake_preset(scene, preset, settings, &|stage, f| {
            progress(&format!("{name}: baking ({stage})"), f)
        })?;
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
        drop(cache);
        let (mse, rel_mse, mssim) = errors(&out.beauty, &reference.image)?;
        let cached = Run {
            method: Method::Cache { preset, points },
            bake_seconds,
            render_seconds,
            peak_memory,
            mse,
            rel_mse,
            mssim,
        };
        runs.push(cached);
    }
    // The path tracer's curve, up to the longest cache run's time, and the same denoised.
    let budget = runs.iter().map(Run::total_seconds).fold(1e-3, f64::max);
    let mut denoised = Vec::new();
    let mut denoiser_missing = None;
    memory::reset_peak();
    crate::reference::render_progressive(
        scene,
        camera,
        &RenderSettings {
            seed: settings.seed,
            first_hits: true,
            ..Default::default()
        },
        Duration::from_secs_f64(budget),
        &|f| progress("path tracing", f),
        &mut |out| {
            let peak_memory = memory::peak();
            let (mse, rel_mse, mssim) = errors(&out.mean, &reference.image)?;
            runs.push(Run {
                method: Method::PathTracer { spp: out.spp },
                bake_seconds: 0.0,
                render_seconds: traced_seconds(&out),
                peak_memory,
                mse,
                rel_mse,
                mssim,
            });
            if let Some((image, seconds)) = denoise(&out, &mut denoiser_missing) {
                let (mse, rel_mse, mssim) = errors(&image, &reference.image)?;
                denoised.push(Run {
                    method: Method::Denoised { spp: out.spp },
                    bake_seconds: 0.0,
                    render_seconds: seconds,
                    peak_memory: memory::peak(),
                    mse,
                    rel_mse,
                    mssim,
                });
            }
            Ok(())
        },
    )?;
    runs.extend(denoised);
    Ok(Report {
        scene: scene.path.clone(),
        width: camera.width,
        height: camera.height,
        threads: rayon::current_num_threads(),
        reference,
        runs,
        denoiser_missing,
    })
}

/// Bake `scene` at `preset` in memory: the cache, its surfel count and the bake's seconds
/// (the cache's encoding included, as a file's would be).
fn bake_preset(
    scene: &Scene,
    preset: Quality,
    settings: &CompareSettings,
    progress: Progress,
) -> Result<(BakedCache, usize, f64)> {
    let bake_settings = BakeSettings {
        seed: settings.seed,
        bounces: settings.bounces,
        ..BakeSettings::preset(preset)
    };
    let start = Instant::now();
    let baked = bake(scene, &bake_settings, progress)?;
    let cache = crate::bake::store::in_memory(&scene.path, &baked)?;
    Ok((cache, bake_settings.points, start.elapsed().as_secs_f64()))
}

/// A path tracer run's samples per pixel (0 for a cache run).
fn spp_of(r: &Run) -> u32 {
    match r.method {
        Method::PathTracer { spp } | Method::Denoised { spp } => spp,
        Method::Cache { .. } => 0,
    }
}

impl Report {
    /// The report as `report.json` holds it (documented in the README).
    pub fn to_json(&self) -> Value {
        json!({
            "scene": self.scene.display().to_string(),
            "width": self.width,
            "height": self.height,
            "threads": self.threads,
            "wpbgi_version": crate::VERSION,
            "reference": {
                "path": self.reference.path.as_ref().map(|p| p.display().to_string()),
                "spp": self.reference.spp,
                "seconds": self.reference.seconds,
            },
            "runs": self.runs.iter().map(Run::to_json).collect::<Vec<_>>(),
            "denoiser_missing": self.denoiser_missing,
        })
    }

    /// A short Markdown summary: the table of runs and, for each cache run, when the path tracer
    /// and the denoised path tracer reach its error.
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
        let curve = |denoised: bool| {
            self.runs.iter().filter(move |r| match r.method {
                Method::PathTracer { .. } => !denoised,
                Method::Denoised { .. } => denoised,
                Method::Cache { .. } => false,
            })
        };
        for cache in self
            .runs
            .iter()
            .filter(|r| matches!(r.method, Method::Cache { .. }))
        {
            s += &format!(
                "- {} reaches relMSE {:.3e} in {:.2} s.",
                cache.label(),
                cache.rel_mse,
                cache.total_seconds()
            );
            for (denoised, name) in [(false, "The path tracer"), (true, "Denoised, it")] {
                if denoised && self.denoiser_missing.is_some() {
                    continue;
                }
                let first = curve(denoised).find(|r| r.rel_mse <= cache.rel_mse);
                let best = curve(denoised).min_by(|a, b| a.rel_mse.total_cmp(&b.rel_mse));
                s += &match (first, best) {
                    (Some(r), _) => {
                        let ratio = r.total_seconds() / cache.total_seconds().max(1e-9);
                        format!(
                            " {name} reaches it at {} spp in {:.2} s: {}.",
                            spp_of(r),
                            r.total_seconds(),
                            if ratio <= 1.0 {
                                format!("{:.1}× sooner than the cache", 1.0 / ratio.max(1e-9))
                            } else {
                                format!("the cache is {ratio:.1}× sooner")
                            }
                        )
                    }
                    (None, Some(b)) => format!(
                        " {name} does not within {:.2} s (its lowest: {:.3e} at {} spp): the \
                         cache is sooner.",
                        b.total_seconds(),
                        b.rel_mse,
                        spp_of(b)
                    ),
                    (None, None) => String::new(),
                };
            }
            s += "\n";
        }
        if let Some(why) = &self.denoiser_missing {
            s += &format!("- The denoised path tracer was not run: {why}\n");
        }
        s += "\nThe plot: `error_vs_time.svg` / `.png` (relMSE against total seconds, log-log).\n";
        s
    }

    /// Write `report.json`, `error_vs_time.svg`, `error_vs_time.png` and `summary.md` into
    /// `dir` (created if needed), each atomically.
    pub fn write(&self, dir: &Path) -> Result<()> {
        write_text_files(dir, &self.to_json(), self.summary_markdown())?;
        let svg = plot::svg(self).map_err(|e| Error::Output {
            path: dir.join("error_vs_time.svg"),
            reason: e,
        })?;
        write_text(dir, "error_vs_time.svg", svg)?;
        let (w, h, rgb) = plot::png_pixels(self).map_err(|e| Error::Output {
            path: dir.join("error_vs_time.png"),
            reason: e,
        })?;
        crate::image::write_png_rgb8(&dir.join("error_vs_time.png"), w, h, &rgb)
    }
}

/// Write `report.json` (`json`, pretty) and `summary.md` into `dir`, created if needed, each
/// atomically.
fn write_text_files(dir: &Path, json: &Value, summary: String) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::Output {
        path: dir.to_path_buf(),
        reason: e.to_string(),
    })?;
    let text = serde_json::to_string_pretty(json).map_err(|e| Error::Output {
        path: dir.join("report.json"),
        reason: e.to_string(),
    })?;
    write_text(dir, "report.json", text + "\n")?;
    write_text(dir, "summary.md", summary)
}

/// Write `body` to `dir/name` atomically.
fn write_text(dir: &Path, name: &str, body: String) -> Result<()> {
    write_atomically(&dir.join(name), |tmp| {
        std::fs::write(tmp, body).map_err(|e| e.to_string())
    })
}

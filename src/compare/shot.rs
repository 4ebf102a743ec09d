//! A shot (issue 21): what a cache is for, many frames from one bake. The camera orbits its
//! target over the frames ([`Camera::orbit`]; 0° is a still camera); each preset is baked
//! once and renders every frame, and the path tracer, raw and denoised, renders each frame
//! in the cache's seconds per frame (its bake shared out over the frames). Every frame is
//! measured against its own reference, and each method's flicker by a temporal metric: the
//! mean over consecutive frames of the mean squared difference of their errors,
//! ((x_t − r_t) − (x_{t−1} − r_{t−1}))², over pixels and channels. Camera motion moves the
//! image and its reference together and so does not count; noise that changes from frame to
//! frame does. A still camera gives a cache exactly 0 (the same cache, camera and seed give
//! the same bytes), while the path tracer draws new samples each frame (its seed is the
//! frame's, as production renderers animate their noise by default), so its noise counts.

use super::{bake_preset, denoise, errors, traced_seconds, CompareSettings, Method, Reference};
use crate::error::{Error, Result};
use crate::image::Image;
use crate::progress::Progress;
use crate::reference::{render_progressive, RenderOutput, RenderSettings};
use crate::render::{render_final, FinalSettings};
use crate::scene::{Camera, Scene};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The shot's cameras: `camera` turning by `orbit_degrees` about its up axis over `frames`
/// frames (at least 2: the temporal metric compares consecutive ones), from half the angle
/// one way to half the other, around the point of its view axis level with the scene's
/// centre (the preview's orbit target); 0° is a still camera.
pub fn cameras(
    scene: &Scene,
    camera: &Camera,
    frames: u32,
    orbit_degrees: f32,
) -> Result<Vec<Camera>> {
    if frames < 2 {
        return Err(Error::InvalidSetting(format!(
            "a shot needs at least 2 frames, not {frames}"
        )));
    }
    if !orbit_degrees.is_finite() {
        return Err(Error::InvalidSetting(format!(
            "the orbit must be a finite angle, not {orbit_degrees}"
        )));
    }
    let (lo, hi) = scene.bounds();
    let target = camera.orbit_target(0.5 * (lo + hi));
    (0..frames)
        .map(|i| {
            let t = i as f32 / (frames - 1) as f32 - 0.5;
            let yaw = (orbit_degrees * t).to_radians();
            camera.orbit(target, camera.up, yaw, 0.0).ok_or_else(|| {
                Error::InvalidSetting(format!(
                    "camera {:?} cannot orbit: it looks along its up axis",
                    camera.name
                ))
            })
        })
        .collect()
}

/// One frame of one method.
#[derive(Clone, Debug)]
pub struct FrameRun {
    /// The path tracer's samples per pixel (none for the cache).
    pub spp: Option<u32>,
    /// Wall seconds of this frame's render (the denoised path tracer's include its first
    /// hits and the denoiser).
    pub render_seconds: f64,
    /// Mean squared error against the frame's reference.
    pub mse: f64,
    /// Relative MSE (see [`super::Run::rel_mse`]).
    pub rel_mse: f64,
}

/// One method's frames.
#[derive(Clone, Debug)]
pub struct ShotRun {
    /// The method (for the path tracer, its first frame's samples per pixel).
    pub method: Method,
    /// The cache's bake (once for the shot); 0 for the path tracer.
    pub bake_seconds: f64,
    /// Its frames, in order.
    pub frames: Vec<FrameRun>,
    /// Mean over consecutive frames of the mean squared difference of their errors.
    pub temporal_mse: f64,
}

impl ShotRun {
    /// Bake and renders shared out over the frames.
    pub fn seconds_per_frame(&self) -> f64 {
        let rendering: f64 = self.frames.iter().map(|f| f.render_seconds).sum();
        (self.bake_seconds + rendering) / self.frames.len().max(1) as f64
    }

    /// Mean relative MSE over the frames.
    pub fn mean_rel_mse(&self) -> f64 {
        self.frames.iter().map(|f| f.rel_mse).sum::<f64>() / self.frames.len().max(1) as f64
    }

    fn to_json(&self) -> Value {
        json!({
            "method": self.method.name(),
            "preset": match &self.method {
                Method::Cache { preset, .. } => Some(preset.name()),
                _ => None,
            },
            "bake_s": self.bake_seconds,
            "seconds_per_frame": self.seconds_per_frame(),
            "mean_rel_mse": self.mean_rel_mse(),
            "temporal_mse": self.temporal_mse,
            "frames": self.frames.iter().enumerate().map(|(i, f)| json!({
                "frame": i + 1,
                "spp": f.spp,
                "render_s": f.render_seconds,
                "mse": f.mse,
                "rel_mse": f.rel_mse,
            })).collect::<Vec<_>>(),
        })
    }
}

/// A shot's every run.
#[derive(Clone, Debug)]
pub struct ShotReport {
    /// The scene compared on.
    pub scene: PathBuf,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Worker threads every run used.
    pub threads: usize,
    /// Frames in the shot.
    pub frames: usize,
    /// The camera's turn over the shot (see [`cameras`]).
    pub orbit_degrees: f32,
    /// For references rendered here: their samples per pixel and total seconds.
    pub reference_spp: Option<u32>,
    /// See `reference_spp`.
    pub reference_seconds: Option<f64>,
    /// The cache's runs (one per preset), then the path tracer's and the denoised one's.
    pub runs: Vec<ShotRun>,
    /// Why the denoised run is missing (the denoiser did not load), if it is.
    pub denoiser_missing: Option<String>,
}

/// Frame errors and the temporal metric as frames arrive.
struct Errors {
    frames: Vec<FrameRun>,
    previous: Option<Image>,
    temporal_sum: f64,
}

impl Errors {
    fn new() -> Self {
        Errors {
            frames: Vec::new(),
            previous: None,
            temporal_sum: 0.0,
        }
    }

    fn add(
        &mut self,
        image: &Image,
        reference: &Image,
        spp: Option<u32>,
        seconds: f64,
    ) -> Result<()> {
        let (mse, rel_mse, _) = errors(image, reference)?;
        let error = Image {
            width: image.width,
            height: image.height,
            pixels: (image.pixels.iter().zip(&reference.pixels))
                .map(|(x, r)| *x - *r)
                .collect(),
        };
        if let Some(prev) = &self.previous {
            self.temporal_sum += crate::image::error_against(&error, prev).map_or(0.0, |e| e.0);
        }
        self.previous = Some(error);
        self.frames.push(FrameRun {
            spp,
            render_seconds: seconds,
            mse,
            rel_mse,
        });
        Ok(())
    }

    fn finish(self, method: Method, bake_seconds: f64) -> ShotRun {
        let pairs = self.frames.len().saturating_sub(1).max(1) as f64;
        ShotRun {
            method,
            bake_seconds,
            temporal_mse: self.temporal_sum / pairs,
            frames: self.frames,
        }
    }
}

/// Render the shot along `cameras` (see [`cameras`]), each measured against its reference:
/// each preset baked once and rendering every frame, then the path tracer, raw and
/// denoised, in the slowest preset's seconds per frame.
pub fn shot(
    scene: &Scene,
    cameras: &[Camera],
    references: &[Reference],
    settings: &CompareSettings,
    orbit_degrees: f32,
    progress: Progress,
) -> Result<ShotReport> {
    if settings.presets.is_empty() {
        return Err(Error::InvalidSetting(
            "compare needs at least one preset".into(),
        ));
    }
    let (Some(first), Some(first_reference), true) = (
        cameras.first(),
        references.first(),
        cameras.len() == references.len(),
    ) else {
        return Err(Error::InvalidSetting(format!(
            "a shot of {} frames needs as many references, not {}",
            cameras.len(),
            references.len()
        )));
    };
    for (i, (cam, r)) in cameras.iter().zip(references).enumerate() {
        super::check_size(&r.image, cam.width, cam.height)
            .map_err(|m| Error::InvalidSetting(format!("frame {}: {m}", i + 1)))?;
    }
    let n = cameras.len() as f32;
    let mut runs = Vec::new();
    for &preset in &settings.presets {
        let name = preset.name();
        let (cache, points, bake_seconds) = bake_preset(scene, preset, settings, &|stage, f| {
            progress(&format!("{name}: baking ({stage})"), f)
        })?;
        let final_settings = FinalSettings {
            seed: settings.seed,
            ..settings.final_settings.clone()
        };
        let mut errs = Errors::new();
        for (i, (cam, reference)) in cameras.iter().zip(references).enumerate() {
            let start = Instant::now();
            let out = render_final(scene, &cache, cam, &final_settings, &|stage, f| {
                progress(
                    &format!("{name}: frame {} ({stage})", i + 1),
                    (i as f32 + f) / n,
                )
            })?;
            errs.add(
                &out.beauty,
                &reference.image,
                None,
                start.elapsed().as_secs_f64(),
            )?;
        }
        runs.push(errs.finish(Method::Cache { preset, points }, bake_seconds));
    }
    // The path tracer, each frame in the slowest cache's seconds per frame.
    let budget = runs
        .iter()
        .map(ShotRun::seconds_per_frame)
        .fold(1e-3, f64::max);
    let (mut raw, mut denoised) = (Errors::new(), Errors::new());
    let mut denoiser_missing = None;
    for (i, (cam, reference)) in cameras.iter().zip(references).enumerate() {
        let mut last: Option<RenderOutput> = None;
        render_progressive(
            scene,
            cam,
            &RenderSettings {
                seed: settings.seed.wrapping_add(i as u64),
                // The denoiser's guides, while it works.
                first_hits: denoiser_missing.is_none(),
                ..Default::default()
            },
            Duration::from_secs_f64(budget),
            &|f| {
                progress(
                    &format!("path tracing, frame {}", i + 1),
                    (i as f32 + f) / n,
                )
            },
            &mut |out| {
                last = Some(out);
                Ok(())
            },
        )?;
        let out =
            last.ok_or_else(|| Error::InvalidSetting("the path tracer made no image".into()))?;
        raw.add(
            &out.mean,
            &reference.image,
            Some(out.spp),
            traced_seconds(&out),
        )?;
        if let Some((image, seconds)) = denoise(&out, &mut denoiser_missing) {
            denoised.add(&image, &reference.image, Some(out.spp), seconds)?;
        }
    }
    let first_spp = |e: &Errors| e.frames.first().and_then(|f| f.spp).unwrap_or(0);
    let spp = first_spp(&raw);
    runs.push(raw.finish(Method::PathTracer { spp }, 0.0));
    if denoiser_missing.is_none() {
        let spp = first_spp(&denoised);
        runs.push(denoised.finish(Method::Denoised { spp }, 0.0));
    }
    Ok(ShotReport {
        scene: scene.path.clone(),
        width: first.width,
        height: first.height,
        threads: rayon::current_num_threads(),
        frames: cameras.len(),
        orbit_degrees,
        reference_spp: first_reference.spp,
        reference_seconds: first_reference
            .seconds
            .map(|_| references.iter().filter_map(|r| r.seconds).sum()),
        runs,
        denoiser_missing,
    })
}

impl ShotReport {
    /// The report as `report.json` holds it for a shot (documented in the README).
    pub fn to_json(&self) -> Value {
        json!({
            "scene": self.scene.display().to_string(),
            "width": self.width,
            "height": self.height,
            "threads": self.threads,
            "wpbgi_version": crate::VERSION,
            "shot": {
                "frames": self.frames,
                "orbit_degrees": self.orbit_degrees,
            },
            "reference": {
                "spp": self.reference_spp,
                "seconds": self.reference_seconds,
            },
            "runs": self.runs.iter().map(ShotRun::to_json).collect::<Vec<_>>(),
            "denoiser_missing": self.denoiser_missing,
        })
    }

    /// The shot in Markdown: per method its seconds per frame, mean error and flicker, then
    /// every frame's relMSE.
    pub fn summary_markdown(&self) -> String {
        let mut s = format!(
            "# wpbgi compare, a shot: {}\n\n{}×{}, {} frames, the camera orbiting {}°, {} \
             threads. References: {}.\n\n",
            self.scene.display(),
            self.width,
            self.height,
            self.frames,
            self.orbit_degrees,
            self.threads,
            match (self.reference_spp, self.reference_seconds) {
                (Some(spp), Some(t)) => format!("path traced here, {spp} spp, {t:.1} s in all"),
                _ => "read, one per frame".into(),
            }
        );
        s += "| method | bake s | s per frame | mean relMSE | temporal MSE |\n";
        s += "|---|---:|---:|---:|---:|\n";
        for r in &self.runs {
            s += &format!(
                "| {} | {:.2} | {:.2} | {:.3e} | {:.3e} |\n",
                r.method.label(),
                r.bake_seconds,
                r.seconds_per_frame(),
                r.mean_rel_mse(),
                r.temporal_mse
            );
        }
        s += "\nrelMSE per frame:\n\n| frame |";
        for r in &self.runs {
            s += &format!(" {} |", r.method.label());
        }
        s += "\n|---:|";
        s += &"---:|".repeat(self.runs.len());
        s += "\n";
        for i in 0..self.frames {
            s += &format!("| {} |", i + 1);
            for r in &self.runs {
                s += &r
                    .frames
                    .get(i)
                    .map_or(" – |".to_string(), |f| format!(" {:.3e} |", f.rel_mse));
            }
            s += "\n";
        }
        if let Some(why) = &self.denoiser_missing {
            s += &format!("\nThe denoised path tracer was not run: {why}\n");
        }
        s += "\nThe temporal MSE is the mean over consecutive frames of the mean squared \
              difference of their errors against their references: flicker, not motion.\n";
        s
    }

    /// Write `report.json` and `summary.md` into `dir` (created if needed), each atomically.
    pub fn write(&self, dir: &Path) -> Result<()> {
        super::write_text_files(dir, &self.to_json(), self.summary_markdown())
    }
}

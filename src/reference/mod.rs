//! The reference path tracer: the ground truth every faster method in the crate is measured
//! against (docs/design.md §9).
//!
//! Unidirectional path tracing with next-event estimation and multiple importance sampling
//! (power heuristic), Russian roulette, and Mitsuba's `path` integrator semantics, so that our
//! images agree with Mitsuba's in expectation: `max_depth` counts path segments (1 = directly
//! visible emitters, 2 = direct lighting, −1 = unlimited), Russian roulette starts at `rr_depth`
//! with continuation probability `min(max(throughput)·η², RR_MAX)`, one-sided BSDFs and
//! emitters are black from behind, the box pixel filter averages samples uniform over each
//! pixel.
//!
//! The one departure: Mitsuba caps the continuation probability at 0.95, we at 0.999. The
//! expectation is the same. But with 0.95, a path in a scene of albedo ρ > 0.95 carries a
//! throughput that grows as (ρ/0.95)^k, and the variance diverges: the stability matrix's
//! closed box of albedo 0.99 (exact answer 100) read 79 at 64 samples per pixel. With 0.999 the
//! throughput stays bounded wherever ρ ≤ 0.999, and a path trapped by total internal
//! reflection still ends (after 1000 bounces on average).
//!
//! Every random number is keyed by (pixel, sample index, dimension), so an image is a pure
//! function of the scene and the settings: byte-identical for any thread count.

mod integrator;

pub use integrator::{radiance, RenderContext, Transport};

use crate::error::{Error, Result};
use crate::image::Image;
use crate::sampler::Sampler;
use crate::scene::{Camera, Scene};
use crate::spectrum::Rgb;
use crate::trace::{intersect, Tracer};
use crate::validate::{in_range, require, require_max_depth, require_positive};
use glam::{DVec3, Vec2};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Settings of a reference render.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// Samples per pixel (with `time_limit`: samples per pass).
    pub spp: u32,
    /// Longest path in segments; −1 for unlimited (Mitsuba's `max_depth`).
    pub max_depth: i32,
    /// Depth from which Russian roulette may end paths (Mitsuba's `rr_depth`).
    pub rr_depth: u32,
    /// Seed of every random stream.
    pub seed: u64,
    /// Render passes of `spp` samples until this much time has passed.
    pub time_limit: Option<Duration>,
    /// The light transport to estimate.
    pub transport: Transport,
    /// Also average what each camera sample hits first ([`FirstHits`]), for a denoiser.
    pub first_hits: bool,
}

impl RenderSettings {
    /// Refuse a field out of range, in a sentence that names it ([`render`] calls this first).
    pub fn validate(&self) -> Result<()> {
        const S: &str = "RenderSettings";
        require_positive(S, "spp", self.spp as u64)?;
        require_max_depth(S, self.max_depth)?;
        if let Transport::CacheOneBounce { smooth_below, .. } = self.transport {
            require(
                in_range(smooth_below, 0.0, 1.0, true),
                S,
                "transport.smooth_below",
                smooth_below,
                "a roughness in [0, 1]",
            )?;
        }
        Ok(())
    }

    /// The integrator's context for these settings: what [`radiance`] needs, built once per
    /// render.
    pub fn context<'a>(&self, scene: &'a Scene) -> RenderContext<'a> {
        RenderContext {
            tracer: Tracer::new(scene),
            max_depth: self.max_depth,
            rr_depth: self.rr_depth,
            transport: self.transport,
        }
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            spp: 16,
            max_depth: -1,
            rr_depth: 5,
            seed: 0,
            time_limit: None,
            transport: Transport::Full,
            first_hits: false,
        }
    }
}

/// The result: the mean image, the per-pixel variance of a one-sample estimate (for error
/// bars and statistical tests), the samples taken and the wall time.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The mean over the samples.
    pub mean: Image,
    /// The per-pixel variance of a one-sample estimate.
    pub variance: Image,
    /// Samples per pixel taken.
    pub spp: u32,
    /// Wall seconds.
    pub seconds: f64,
    /// With [`RenderSettings::first_hits`]: what the same camera samples hit first.
    pub first_hits: Option<FirstHits>,
}

/// What a render's camera samples hit first, averaged per pixel over the same samples as its
/// mean: the albedo and normal that guide a denoiser, and the emission seen directly (the
/// environment's where the ray escapes), which a denoiser must not blur (the emitters' edges).
#[derive(Clone, Debug)]
pub struct FirstHits {
    /// Mean albedo of the first hits.
    pub albedo: Image,
    /// Mean shading normal of the first hits.
    pub normal: Image,
    /// Mean emission seen directly.
    pub emission: Image,
    /// The seconds they took (one more closest-hit ray per camera sample), part of the
    /// render's.
    pub seconds: f64,
}

impl RenderOutput {
    /// The mean denoised by Intel Open Image Denoise ([`crate::denoise`], on `threads`
    /// threads): the light after the first hit, guided by the first hit's albedo and
    /// normal, with the emission seen directly added back as rendered (as `render
    /// --denoise` keeps emission and direct light). `None` without [`FirstHits`].
    pub fn denoised(&self, threads: usize) -> Option<Result<Image>> {
        let hits = self.first_hits.as_ref()?;
        let mut beyond = self.mean.clone();
        for (b, e) in beyond.pixels.iter_mut().zip(&hits.emission.pixels) {
            *b = (*b - *e).max(Rgb::ZERO);
        }
        Some(
            crate::denoise::denoise(&beyond, &hits.albedo, &hits.normal, threads).map(|mut d| {
                for (p, e) in d.pixels.iter_mut().zip(&hits.emission.pixels) {
                    *p += *e;
                }
                d
            }),
        )
    }
}

/// Render `camera`'s view of `scene`. `progress` receives the fraction done (0..1) from any
/// thread; the library prints nothing.
pub fn render(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    progress: &(dyn Fn(f32) + Sync),
) -> Result<RenderOutput> {
    check(scene, camera, settings)?;
    let start = Instant::now();
    let ctx = settings.context(scene);
    let mut acc = Accumulation::new(camera, settings.first_hits);
    // A time-limited render takes passes of `spp` samples until the time is up and reports
    // progress against the time; otherwise one pass, with progress per finished row.
    match settings.time_limit {
        None => acc.pass(&ctx, camera, settings.seed, settings.spp, Some(progress)),
        Some(limit) => loop {
            acc.pass(&ctx, camera, settings.seed, settings.spp, None);
            let elapsed = start.elapsed();
            progress((elapsed.as_secs_f32() / limit.as_secs_f32()).min(1.0));
            if elapsed >= limit || acc.taken as u64 + settings.spp as u64 > u32::MAX as u64 {
                break;
            }
        },
    }
    Ok(acc.output(start.elapsed().as_secs_f64()))
}

/// Render progressively for about `budget` of path tracing: passes that double the samples
/// per pixel (1, 2, 4, …; the last one shortened to end near the budget), handing
/// `checkpoint` the image after each, as [`render`] would have made it at that many samples.
/// The budget counts the path tracing; a checkpoint's `seconds` count that and its first hits
/// (`FirstHits::seconds`), not the time `checkpoint` itself takes. `settings.spp` and
/// `time_limit` are not read.
pub(crate) fn render_progressive(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    budget: Duration,
    progress: &(dyn Fn(f32) + Sync),
    checkpoint: &mut dyn FnMut(RenderOutput) -> Result<()>,
) -> Result<()> {
    check(
        scene,
        camera,
        &RenderSettings {
            spp: 1,
            ..settings.clone()
        },
    )?;
    let ctx = settings.context(scene);
    let mut acc = Accumulation::new(camera, settings.first_hits);
    // Seconds of path tracing, and of everything (the first hits too).
    let (mut traced, mut spent) = (0.0f64, 0.0f64);
    let budget = budget.as_secs_f64();
    loop {
        let mut count = acc.taken.max(1);
        // Seconds per sample per pixel so far: shorten the last pass to end near the budget.
        if acc.taken > 0 {
            let rate = traced / f64::from(acc.taken);
            let left = ((budget - traced) / rate).floor();
            count = count.min(left.max(1.0) as u32);
        }
        let start = Instant::now();
        let hits_before = acc.hits_seconds;
        acc.pass(&ctx, camera, settings.seed, count, None);
        let seconds = start.elapsed().as_secs_f64();
        spent += seconds;
        traced += seconds - (acc.hits_seconds - hits_before);
        progress((traced / budget).min(1.0) as f32);
        checkpoint(acc.output(spent))?;
        if traced >= budget || acc.taken as u64 * 2 > u32::MAX as u64 {
            return Ok(());
        }
    }
}

/// The settings and camera a render refuses.
fn check(scene: &Scene, camera: &Camera, settings: &RenderSettings) -> Result<()> {
    settings.validate()?;
    Camera::check_size(camera.width, camera.height).map_err(Error::InvalidSetting)?;
    scene.check_renderable()
}

/// Per-pixel sums of the samples taken so far, in f64: the order of addition is fixed per
/// pixel, so the image is the same for any thread count.
struct Accumulation {
    width: u32,
    height: u32,
    sum: Vec<DVec3>,
    sum2: Vec<DVec3>,
    /// With first hits: per pixel the sums of albedo, normal and emission.
    hits: Option<Vec<[DVec3; 3]>>,
    /// Seconds spent on the first hits.
    hits_seconds: f64,
    taken: u32,
}

impl Accumulation {
    fn new(camera: &Camera, first_hits: bool) -> Self {
        let n = camera.width as usize * camera.height as usize;
        Accumulation {
            width: camera.width,
            height: camera.height,
            sum: vec![DVec3::ZERO; n],
            sum2: vec![DVec3::ZERO; n],
            hits: first_hits.then(|| vec![[DVec3::ZERO; 3]; n]),
            hits_seconds: 0.0,
            taken: 0,
        }
    }

    /// Take `count` more samples of every pixel; `row_progress`: report the fraction of rows
    /// done.
    fn pass(
        &mut self,
        ctx: &RenderContext,
        camera: &Camera,
        seed: u64,
        count: u32,
        row_progress: Option<&(dyn Fn(f32) + Sync)>,
    ) {
        let (w, h) = (self.width as usize, self.height as usize);
        let first = self.taken;
        let done_rows = AtomicU64::new(0);
        self.sum
            .par_chunks_mut(w)
            .zip(self.sum2.par_chunks_mut(w))
            .enumerate()
            .for_each(|(y, (row, row2))| {
                for x in 0..w {
                    let pixel = (y * w + x) as u64;
                    for s in first..first + count {
                        let mut sampler = Sampler::new(seed, pixel, s as u64);
                        let film = Vec2::new(x as f32, y as f32) + sampler.next_2d();
                        let (o, d) = camera.generate_ray(film);
                        let l = radiance(ctx, o, d, &mut sampler).as_dvec3();
                        row[x] += l;
                        row2[x] += l * l;
                    }
                }
                if let Some(progress) = row_progress {
                    let n = done_rows.fetch_add(1, Ordering::Relaxed) + 1;
                    progress(n as f32 / h as f32);
                }
            });
        if let Some(hits) = &mut self.hits {
            let start = Instant::now();
            hits.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
                for (x, sums) in row.iter_mut().enumerate() {
                    let pixel = (y * w + x) as u64;
                    for s in first..first + count {
                        add_first_hit(ctx, camera, seed, (x, y, pixel), s, sums);
                    }
                }
            });
            self.hits_seconds += start.elapsed().as_secs_f64();
        }
        self.taken += count;
    }

    /// The render so far, `seconds` its time.
    fn output(&self, seconds: f64) -> RenderOutput {
        let n = f64::from(self.taken.max(1));
        let image = |f: &dyn Fn(usize) -> DVec3| Image {
            width: self.width,
            height: self.height,
            pixels: (0..self.sum.len()).map(|i| f(i).as_vec3()).collect(),
        };
        let mean = image(&|i| self.sum[i] / n);
        let variance = image(&|i| {
            if self.taken > 1 {
                ((self.sum2[i] - self.sum[i] * (self.sum[i] / n)) / (n - 1.0)).max(DVec3::ZERO)
            } else {
                DVec3::ZERO
            }
        });
        let first_hits = self.hits.as_ref().map(|hits| FirstHits {
            albedo: image(&|i| hits[i][0] / n),
            normal: image(&|i| hits[i][1].normalize_or_zero()),
            emission: image(&|i| hits[i][2] / n),
            seconds: self.hits_seconds,
        });
        RenderOutput {
            mean,
            variance,
            spp: self.taken,
            seconds,
            first_hits,
        }
    }
}

/// Add what camera sample `s` of pixel (`x`, `y`) (index `pixel`) hits first to `sums`
/// (albedo, normal, emission), keyed as the render keys its samples.
fn add_first_hit(
    ctx: &RenderContext,
    camera: &Camera,
    seed: u64,
    (x, y, pixel): (usize, usize, u64),
    s: u32,
    sums: &mut [DVec3; 3],
) {
    let mut sampler = Sampler::new(seed, pixel, s as u64);
    let (o, d) = camera.generate_ray(Vec2::new(x as f32, y as f32) + sampler.next_2d());
    let Some(hit) = intersect(&ctx.tracer, o, d) else {
        if let Some(env) = &ctx.tracer.scene.environment {
            sums[2] += env.radiance(d).as_dvec3();
        }
        return;
    };
    let material = &ctx.tracer.scene.materials[ctx.tracer.scene.meshes[hit.mesh as usize].material];
    let front = hit.frame.to_local(-d).z > 0.0;
    sums[0] += material
        .bsdf_at(&ctx.tracer.scene.textures, hit.uv)
        .albedo_estimate()
        .as_dvec3();
    sums[1] += hit.frame.n.as_dvec3();
    sums[2] += material
        .emission_at(&ctx.tracer.scene.textures, hit.uv, front)
        .as_dvec3();
}

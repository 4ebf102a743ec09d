//! The final render from a cache (docs/design.md §7, docs/method.md §2.3, §3, §7).
//!
//! 1. Centre rays find the primary hits, and follow mirrors and clear glass to the rough
//!    surfaces they show; pixels on an edge of either (another mesh, a normal turning by
//!    more than 25°, or a depth step of 5 %) get 16 or 64 samples of a scrambled
//!    (0, 2)-sequence, as many as the edge needs, of which one per quarter of the pixel
//!    gathers; other mirror and glass pixels 4, one per quarter, the first gathering; the
//!    others one sample (`pixels.rs`, adaptive anti-aliasing).
//! 2. Each camera sample is traced to its rough hits ([`primary`]): emission, direct light by
//!    ray tracing, specular chains; every rough hit becomes a receiver.
//! 3. The gather, per tile ([`tile_side`]): receivers get their indirect light from the cache
//!    through a microbuffer ([`crate::gather`]), one by one (`pbgi`) or by clusters (`fpbgi`, the
//!    default). Glossy receivers (roughness below `glossy_below`) always gather alone, through
//!    a buffer refined by their BSDF (docs/method.md §7), since a shared uniform cluster buffer would
//!    blur their lobe. Or (`paths`) each receiver traces rays drawn from its BSDF and takes
//!    the cache's light where they hit ([`paths`]): noisy, no buffers.
//!
//! A frame whose shorter side is from 256 to 511 pixels is rendered at twice its size and
//! box-filtered down ([`auto_supersample`], [`FinalOutput::filtered_down`]): the grid and the
//! samples above follow the frame, so the larger frame gathers as often and samples its
//! edges, caustics and glass more finely (docs/render.md, "Small frames rendered at twice the
//! size").
//!
//! Steps 2 and 3 run a band of tiles at a time, so the receivers held are one band's; what a
//! render needs at least is checked against the memory available before any work.
//!
//! Every random number is keyed by (pixel, sample), and every tile is processed in a fixed
//! order, so the image is the same for any thread count.

pub mod bright;
pub mod near_field;
pub mod paths;
mod pixels;
pub mod primary;
pub mod sparse;

use crate::bsdf::{Bsdf, Diffuse};
use crate::cache::store::BakedCache;
use crate::error::{Error, Result};
use crate::gather::cut::STRADDLE_RADII;
use crate::gather::fpbgi::{cluster, ClusterGather, ClusterReceivers};
use crate::gather::{CutStats, Microbuffer, Senders};
use crate::geometry::frame::Frame;
use crate::image::Image;
use crate::progress::Progress;
use crate::scene::{Camera, Scene};
use crate::spectrum::{luminance, Rgb};
use crate::trace::Tracer;
use crate::validate::{in_range, require, require_max_depth, require_positive};
use glam::Vec3;
use pixels::PixelSampling;
use primary::{PrimarySample, PrimarySettings, Receiver};
use rayon::prelude::*;
use sparse::SparsePlan;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

/// How receivers gather.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GatherMode {
    /// One cut and one microbuffer per receiver (docs/method.md §2.3).
    Pbgi,
    /// Clustered receivers sharing the far field (docs/method.md §3).
    Fpbgi,
    /// Rays drawn from each receiver's BSDF, ending in the cache ([`paths`]).
    Paths,
}

/// Settings of a final render.
#[derive(Clone, Debug)]
pub struct FinalSettings {
    /// How receivers gather (FPBGI by default).
    pub gather: GatherMode,
    /// Base microbuffer pixels per side (per hemisphere).
    pub mb_size: u32,
    /// Refine glossy receivers' buffers by BSDF importance (docs/method.md §7); off: uniform buffers.
    pub adaptive: bool,
    /// Receivers smoother than this are glossy: they gather alone, through buffers refined by
    /// their BSDF (rougher lobes are resolved by the uniform buffer: on cbox-rough, α = 0.2
    /// gave relMSE 7.4e-4 uniform against 7.9e-4 adaptive).
    pub glossy_below: f32,
    /// BSDF importance: split a pixel holding more than this share of the reflected light.
    pub adaptive_share: f32,
    /// BSDF importance: most splits of a base pixel.
    pub adaptive_levels: u32,
    /// Emitter samples per pixel at each rough hit, spread over a pixel's camera samples (as
    /// many BSDF samples at glossy hits; in large frames, half at diffuse hits whose light
    /// has a closed form; see `LightShare`).
    pub light_samples: u32,
    /// Receivers smoother than this follow their specular chain.
    pub specular_below: f32,
    /// Longest specular chain, in vertices.
    pub chain_depth: u32,
    /// Mitsuba's `max_depth` (−1: everything the cache holds).
    pub max_depth: i32,
    /// FPBGI: clusters per [`CLUSTER_PIXELS`] gathering receivers of a tile (docs/method.md
    /// §3.7): a 32 × 32 tile's, four times as many in a tile of 64 ([`tile_side`]).
    pub clusters: usize,
    /// FPBGI: the far threshold r/d (docs/method.md §3.3).
    pub far_eps: f32,
    /// The path-traced gather's rays per receiver.
    pub spp: u32,
    /// The path-traced gather goes on through glossy hits to the first rough one, instead of
    /// reading the cache's directional maps there ([`paths`]): no bias from the maps' blur,
    /// more noise. Worth it under a denoiser (`render --denoise` turns it on), not in a raw
    /// image. Only where the cache holds every bounce beyond (a multi-bounce cache, no
    /// `max_depth`).
    pub paths_through_glossy: bool,
    /// The rays through a receiver's brightest buffer pixels go on through glossy hits to the
    /// first rough one instead of reading the cache's directional maps there
    /// ([`bright::Retrace`]): sharper caustics and glossy reflections, no visible noise.
    /// Only where the cache holds every bounce beyond (a multi-bounce cache, no `max_depth`).
    pub retrace_glossy: bool,
    /// Receivers gather on a sparse grid and interpolate between where the light is smooth
    /// ([`sparse`]); off, every receiver gathers.
    pub sparse: bool,
    /// Seed of every random stream.
    pub seed: u64,
    /// Render only the pixels x0 ≤ x < x1, y0 ≤ y < y1 of the camera's image (`[x0, y0, x1,
    /// y1]`). Every pixel comes out as in the whole image, bit for bit: the render works in
    /// tiles of the whole image and keeps the crop's part of those it touches.
    pub crop: Option<[u32; 4]>,
    /// Render at this many times the camera's width and height and box-filter each block of
    /// pixels down to one ([`FinalOutput::filtered_down`]); `None`: [`auto_supersample`].
    pub supersample: Option<u32>,
}

/// The most [`FinalSettings::supersample`] takes.
pub const MAX_SUPERSAMPLE: u32 = 4;

/// The supersampling a render of `width` × `height` takes unless told: 2 for a frame whose
/// shorter side is from 256 to 511 pixels, gathered from the cache on the sparse grid; else 1.
///
/// The render's choices follow the frame, not the pixel ([`sparse::coarsest_cell`], the
/// halved shadow rays of [`primary::HALVED_FROM`], the edge quarters' borrowed light): at
/// 512² its gathers are as many as at 256², spread over four times the pixels. Measured at
/// 256² against Mitsuba's max_depth 64 (default caches, one session, docs/render.md,
/// "Small frames rendered at twice the size"), the 512² render box-filtered to 256² had 0.53
/// to 0.77 of the relMSE of the 256² render on seven of the eight scenes (0.91 on
/// wall-glossy), in 0.66–0.92 of its time on the four without mirrors or clear glass and
/// 1.39–1.81 on the four with them. Frames under 256 (thumbnails, the tests' 128²) are not
/// measured and render as before; the path-traced gather and `--dense`, whose every pixel
/// gathers, would cost four times as much.
pub fn auto_supersample(width: u32, height: u32, settings: &FinalSettings) -> u32 {
    let short = width.min(height);
    let fits = 2 * width.max(height) <= Camera::MAX_SIDE;
    // The frames whose grid is still the base one (`sparse::coarsest_cell`).
    if (sparse::ANCHOR_FRAME..2 * sparse::ANCHOR_FRAME).contains(&short)
        && fits
        && settings.sparse
        && settings.gather != GatherMode::Paths
    {
        2
    } else {
        1
    }
}

impl FinalSettings {
    /// Refuse a field out of range, in a sentence that names it ([`render_final`] calls this
    /// first; the crop is checked there, against the camera).
    pub fn validate(&self) -> Result<()> {
        const S: &str = "FinalSettings";
        require(
            (2..=256).contains(&self.mb_size) && self.mb_size.is_multiple_of(2),
            S,
            "mb_size",
            self.mb_size,
            "even and between 2 and 256",
        )?;
        require(
            in_range(self.glossy_below, 0.0, 1.0, true),
            S,
            "glossy_below",
            self.glossy_below,
            "a roughness in [0, 1]",
        )?;
        require(
            in_range(self.adaptive_share, 0.0, 1.0, true) && self.adaptive_share > 0.0,
            S,
            "adaptive_share",
            self.adaptive_share,
            "a fraction in (0, 1]",
        )?;
        require(
            self.adaptive_levels <= MAX_ADAPTIVE_LEVELS,
            S,
            "adaptive_levels",
            self.adaptive_levels,
            &format!("at most {MAX_ADAPTIVE_LEVELS}"),
        )?;
        require_positive(S, "light_samples", self.light_samples as u64)?;
        require(
            in_range(self.specular_below, 0.0, 1.0, true),
            S,
            "specular_below",
            self.specular_below,
            "a roughness in [0, 1]",
        )?;
        require_max_depth(S, self.max_depth)?;
        require_positive(S, "clusters", self.clusters as u64)?;
        require(
            self.far_eps.is_finite() && self.far_eps >= 0.0,
            S,
            "far_eps",
            self.far_eps,
            "a number from 0",
        )?;
        require_positive(S, "spp", self.spp as u64)?;
        match self.supersample {
            Some(f) => require(
                (1..=MAX_SUPERSAMPLE).contains(&f),
                S,
                "supersample",
                f,
                &format!("from 1 to {MAX_SUPERSAMPLE}"),
            ),
            None => Ok(()),
        }
    }
}

/// The most splits of a base microbuffer pixel (a pixel at this level is 4⁻⁸ of its base
/// pixel, far below any lobe the importance could resolve).
pub const MAX_ADAPTIVE_LEVELS: u32 = 8;

impl Default for FinalSettings {
    fn default() -> Self {
        FinalSettings {
            gather: GatherMode::Fpbgi,
            mb_size: Microbuffer::DEFAULT_SIDE,
            adaptive: true,
            glossy_below: 0.15,
            adaptive_share: 1.0 / 64.0,
            adaptive_levels: 5,
            light_samples: 32,
            specular_below: 0.03,
            chain_depth: 8,
            max_depth: -1,
            clusters: 200,
            far_eps: 0.1,
            spp: 16,
            paths_through_glossy: false,
            retrace_glossy: true,
            sparse: true,
            seed: 0,
            crop: None,
            supersample: None,
        }
    }
}

/// The anchor cells ([`sparse::coarsest_cell`]) along a tile's side ([`tile_side`]).
pub const TILE_CELLS: u32 = 8;

/// The side of a tile in a frame of `width` × `height` pixels: the unit of work, of FPBGI's
/// clusters and of the sparse receivers' plan, which puts anchors on the tile's last row and
/// column as on its first so that every tile is computed alone. [`TILE_CELLS`] of the
/// frame's anchor spacing: 32 pixels under 512 on the shorter side, 64 from 512. A tile of
/// four cells (32 pixels at 512²) gathered 25 anchors where a frame-wide grid has 16; at
/// eight cells, 81 for 64. At 512², with one task a tile, the five reference scenes
/// rendered in 0.88–0.97 of the time, at relMSE from 1.5 % lower to 1.9 % higher
/// (docs/render.md, "Tiles of eight cells"). It depends on the whole frame only, so a crop
/// works in the tiles its frame does.
pub fn tile_side(width: u32, height: u32) -> u32 {
    TILE_CELLS * sparse::coarsest_cell(width, height)
}

/// The pixels (of a 32 × 32 tile) that [`FinalSettings::clusters`] counts clusters per.
pub const CLUSTER_PIXELS: usize = 1024;

/// The pixels of a band of tiles: the render holds the pixel samples and gathered values of
/// one band at a time (48 bytes a pixel and 20 a receiver; a tile's receivers, about 230
/// bytes a pixel, only while it is gathered), and waits for its slowest tile before the next.
const BAND_PIXELS: usize = 262_144;

/// The tiles of a band of tiles of side `tile`: [`BAND_PIXELS`] worth, and at least four per
/// thread.
fn band_tiles(tile: u32) -> usize {
    (BAND_PIXELS / (tile * tile) as usize).max(4 * rayon::current_num_threads())
}

/// The crop (`[x0, y0, x1, y1]`, as [`FinalSettings::crop`]) of tile `[column, row]`
/// (counted from 1, row 1 at the top) of a grid of `[columns, rows]` tiles over a
/// `width × height` image: a farm's split of a frame. Column i spans ⌊(i − 1)·W/C⌋ to
/// ⌊i·W/C⌋, each inner bound rounded down to a multiple of the frame's [`tile_side`] where
/// no tile comes out empty so (the render works in whole tiles: a crop that cuts one renders
/// all of it), and likewise for rows.
pub fn grid_crop(
    (width, height): (u32, u32),
    [columns, rows]: [u32; 2],
    [column, row]: [u32; 2],
) -> Result<[u32; 4]> {
    if columns == 0 || rows == 0 || columns > width || rows > height {
        return Err(Error::InvalidSetting(format!(
            "a {columns}x{rows} tile grid does not fit a {width}x{height} image (at least one \
             pixel a tile each way)"
        )));
    }
    if !(1..=columns).contains(&column) || !(1..=rows).contains(&row) {
        return Err(Error::InvalidSetting(format!(
            "tile {column},{row} is not in the {columns}x{rows} grid (columns 1 to {columns}, \
             rows 1 to {rows})"
        )));
    }
    let tile = tile_side(width, height);
    let bound = |size: u32, parts: u32, i: u32| {
        let plain = |i: u32| (u64::from(i) * u64::from(size) / u64::from(parts)) as u32;
        let aligned = |i: u32| {
            if i == parts {
                size
            } else {
                plain(i) / tile * tile
            }
        };
        if (0..parts).all(|k| aligned(k) < aligned(k + 1)) {
            aligned(i)
        } else {
            plain(i)
        }
    };
    Ok([
        bound(width, columns, column - 1),
        bound(height, rows, row - 1),
        bound(width, columns, column),
        bound(height, rows, row),
    ])
}

/// What the gather did, summed over the image.
#[derive(Clone, Copy, Debug, Default)]
pub struct GatherStats {
    /// Receivers gathered (rough hits the camera's paths reached).
    pub receivers: u64,
    /// Of those, the ones gathered in clusters (FPBGI).
    pub clustered: u64,
    /// Clusters made.
    pub clusters: u64,
    /// Nodes visited and splatted by receivers, and by clusters (shared).
    pub receiver_cut: CutStats,
    /// See `receiver_cut`.
    pub cluster_cut: CutStats,
    /// Microbuffer pixels (after refinement) over all receivers.
    pub pixels: u64,
    /// Receivers that took their light from their cell's anchors, or from quarters of their
    /// pixel on their surface, instead of gathering ([`sparse`]).
    pub interpolated: u64,
    /// Of those, the glossy and rough-dielectric ones, which took their outgoing radiance
    /// from anchors with the same BSDF ([`sparse`]).
    pub interpolated_glossy: u64,
    /// Rays traced for receivers' near fields ([`near_field`]).
    pub near_rays: u64,
    /// Rays traced through receivers' brightest buffer pixels ([`bright`]).
    pub bright_rays: u64,
}

impl GatherStats {
    fn add(&mut self, o: &GatherStats) {
        self.receivers += o.receivers;
        self.clustered += o.clustered;
        self.clusters += o.clusters;
        self.receiver_cut += o.receiver_cut;
        self.cluster_cut += o.cluster_cut;
        self.pixels += o.pixels;
        self.interpolated += o.interpolated;
        self.interpolated_glossy += o.interpolated_glossy;
        self.near_rays += o.near_rays;
        self.bright_rays += o.bright_rays;
    }
}

/// The render: the beauty image, its AOVs, and what it cost.
pub struct FinalOutput {
    /// The image: emission, direct and indirect light.
    pub beauty: Image,
    /// Emission and direct light.
    pub direct: Image,
    /// Light from the cache.
    pub indirect: Image,
    /// `indirect`, split by the first hit: on a diffuse surface seen directly, or on a glossy
    /// or specular one (and everything seen through mirrors and glass). The two sum to
    /// `indirect` up to rounding.
    pub indirect_diffuse: Image,
    /// See `indirect_diffuse`.
    pub indirect_glossy: Image,
    /// The first hit's albedo (for a denoiser).
    pub albedo: Image,
    /// World-space shading normal of the first hit (as RGB = xyz).
    pub normal: Image,
    /// Distance to the first hit (0 where none), in all three channels.
    pub depth: Image,
    /// Coverage: per pixel, the fraction of its camera samples that hit the scene.
    pub alpha: Vec<f32>,
    /// Seconds per stage, in order.
    pub timings: Vec<(&'static str, f64)>,
    /// What the gather did (cuts, splats, clusters).
    pub stats: GatherStats,
    /// Camera samples taken (adaptive anti-aliasing).
    pub samples: u64,
    /// Where the images lie in the camera's whole image: their top-left pixel ((0, 0) but
    /// for a crop).
    pub origin: (u32, u32),
}

/// Render `camera`'s view of `scene` from `cache` (already checked to belong to the scene).
/// `progress` receives the stage and its fraction done.
pub fn render_final(
    scene: &Scene,
    cache: &BakedCache,
    camera: &Camera,
    settings: &FinalSettings,
    progress: Progress,
) -> Result<FinalOutput> {
    render_final_cancellable(
        scene,
        cache,
        camera,
        settings,
        progress,
        &AtomicBool::new(false),
    )
}

/// [`render_final`], stopping with [`Error::Cancelled`] soon after `cancel` is set (by another
/// thread or a signal handler): the flag is looked at per tile ([`tile_side`]).
pub fn render_final_cancellable(
    scene: &Scene,
    cache: &BakedCache,
    camera: &Camera,
    settings: &FinalSettings,
    progress: Progress,
    cancel: &AtomicBool,
) -> Result<FinalOutput> {
    let stop = || crate::error::check_cancel(cancel);
    Camera::check_size(camera.width, camera.height).map_err(Error::InvalidSetting)?;
    settings.validate()?;
    let (w, h) = (camera.width, camera.height);
    let [x0, y0, x1, y1] = settings.crop.unwrap_or([0, 0, w, h]);
    if !(x0 < x1 && x1 <= w && y0 < y1 && y1 <= h) {
        return Err(Error::InvalidSetting(format!(
            "the crop {x0},{y0},{x1},{y1} is not a non-empty part of the {w}x{h} image \
             (x0,y0,x1,y1: the pixels x0 ≤ x < x1, y0 ≤ y < y1)"
        )));
    }
    let factor = settings
        .supersample
        .unwrap_or_else(|| auto_supersample(w, h, settings));
    if factor > 1 {
        // The frame at `factor` times the size, the crop's pixels with it: a crop of it is
        // the same part of the whole, so crops still assemble byte for byte.
        Camera::check_size(w * factor, h * factor).map_err(Error::InvalidSetting)?;
        let fine = FinalSettings {
            supersample: Some(1),
            crop: settings.crop.map(|c| c.map(|v| v * factor)),
            ..settings.clone()
        };
        let camera = camera.clone().with_size(w * factor, h * factor);
        let out = render_final_cancellable(scene, cache, &camera, &fine, progress, cancel)?;
        // The larger frame's sides (and its crop's) are multiples of `factor` by construction.
        return out.filtered_down(factor).ok_or_else(|| {
            Error::InvalidSetting(format!(
                "a {w}x{h} frame cannot be filtered down by {factor}"
            ))
        });
    }
    scene.check_renderable()?;
    let mut timings = Vec::new();
    let primary_settings = PrimarySettings {
        max_depth: settings.max_depth,
        light_samples: settings.light_samples,
        specular_below: settings.specular_below,
        chain_depth: settings.chain_depth,
        smooth_quarters: settings.gather == GatherMode::Paths,
        halve_closed_form: w.min(h) >= primary::HALVED_FROM,
        seed: settings.seed,
    };
    // The centre hits of the tiles the crop touches and of the pixels around them: the edge
    // test reads a pixel's four neighbours, a primary hit's clearance the centre hits within
    // `sparse::CLEARANCE_PIXELS`, so that a crop decides as its frame does.
    let tile = tile_side(w, h);
    let (tx0, ty0) = (x0 / tile * tile, y0 / tile * tile);
    let (tx1, ty1) = (
        (x1.div_ceil(tile) * tile).min(w),
        (y1.div_ceil(tile) * tile).min(h),
    );
    let border = sparse::CLEARANCE_PIXELS.max(1);
    let rect = [
        tx0.saturating_sub(border),
        ty0.saturating_sub(border),
        (tx1 + border).min(w),
        (ty1 + border).min(h),
    ];
    check_fits((x1 - x0, y1 - y0), rect, tile)?;
    let t = Instant::now();
    let ctx = Tracer::new(scene);
    // The centre rays are traced while the cache's senders are read: the reading is partly
    // serial (the tree is rebuilt a level at a time, its sums bottom-up), and the rays fill
    // the other cores meanwhile. "load" is the reading's own time, the rest of the step the
    // primary pass's.
    let (senders, sampling) = rayon::join(
        || {
            let t = Instant::now();
            Senders::from_cache(cache).map(|s| (s, t.elapsed().as_secs_f64()))
        },
        || PixelSampling::new(&ctx, camera, &primary_settings, rect),
    );
    let (senders, load_seconds) = senders.map_err(Error::Cache)?;
    let step = t.elapsed().as_secs_f64();
    let load_seconds = load_seconds.min(step);
    timings.push(("load", load_seconds));
    let mut primary_seconds = step - load_seconds;
    let mut gather_seconds = 0.0;
    // The tiles of the whole image that the crop touches.
    let tiles: Vec<(u32, u32)> = (y0 / tile..y1.div_ceil(tile))
        .flat_map(|ty| (x0 / tile..x1.div_ceil(tile)).map(move |tx| (tx, ty)))
        .collect();
    let (cw, ch) = (x1 - x0, y1 - y0);
    let mut out = FinalOutput {
        beauty: Image::new(cw, ch),
        direct: Image::new(cw, ch),
        indirect: Image::new(cw, ch),
        indirect_diffuse: Image::new(cw, ch),
        indirect_glossy: Image::new(cw, ch),
        albedo: Image::new(cw, ch),
        normal: Image::new(cw, ch),
        depth: Image::new(cw, ch),
        alpha: vec![0.0; cw as usize * ch as usize],
        timings,
        stats: GatherStats::default(),
        samples: 0,
        origin: (x0, y0),
    };
    // A pixel of the whole image → its index in the crop.
    let in_crop = |pixel: u32| {
        let (x, y) = (pixel % w, pixel / w);
        ((x0..x1).contains(&x) && (y0..y1).contains(&y))
            .then(|| ((y - y0) * cw + (x - x0)) as usize)
    };
    // A band of tiles at a time, each traced, then gathered, then added to the images: the
    // receivers (about 230 bytes a pixel, measured) are held for one band, not for the
    // image. Every tile is computed alone, so the bands' size changes nothing in the images.
    let done = AtomicUsize::new(0);
    // Rays go on through glossy hits only where the cache holds all the light beyond them.
    let whole_beyond = settings.max_depth < 0 && cache.bounces() > 0;
    let through = |asked: bool| paths::Continuation {
        through_glossy: asked && whole_beyond,
        glossy_below: settings.glossy_below,
        most: settings.chain_depth,
    };
    let frame = FramePlan {
        cell: sparse::coarsest_cell(w, h),
        tile_clusters: settings.clusters * (tile * tile) as usize / CLUSTER_PIXELS,
        paths: through(settings.paths_through_glossy),
        retrace: (settings.retrace_glossy && whole_beyond).then(|| bright::Retrace {
            continuation: through(true),
            seed: settings.seed,
        }),
    };
    for band in tiles.chunks(band_tiles(tile)) {
        let t = Instant::now();
        // Each tile traced and gathered in one task, its receivers dropped at its end: one
        // wait for the slowest tile per band, not two, and no band's receivers held at once.
        let done_tiles: Vec<(TilePrimary, Vec<Gathered>, GatherStats, [f64; 2])> = band
            .par_iter()
            .map(|&(tx, ty)| {
                stop()?;
                let t = Instant::now();
                let origin = (tx * tile, ty * tile);
                let mut traced =
                    primary_tile(&ctx, camera, &sampling, &primary_settings, origin, tile);
                let traced_seconds = t.elapsed().as_secs_f64();
                stop()?;
                let t = Instant::now();
                let size = (tile.min(w - origin.0), tile.min(h - origin.1));
                let rect = (origin, size, w);
                let (values, stats) =
                    gather_tile(&ctx, &senders, &sampling, &traced, rect, frame, settings);
                traced.receivers = Vec::new();
                let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                progress("render", n as f32 / tiles.len() as f32);
                let seconds = [traced_seconds, t.elapsed().as_secs_f64()];
                Ok((traced, values, stats, seconds))
            })
            .collect::<Result<_>>()?;
        // The band's wall time, shared between the two stages as their summed task times are.
        let [traced, gathered] = done_tiles
            .iter()
            .fold([0.0; 2], |[a, b], (.., s)| [a + s[0], b + s[1]]);
        let wall = t.elapsed().as_secs_f64();
        let traced_share = if traced + gathered > 0.0 {
            traced / (traced + gathered)
        } else {
            0.5
        };
        primary_seconds += wall * traced_share;
        gather_seconds += wall * (1.0 - traced_share);
        for (traced, values, stats, _) in &done_tiles {
            out.samples += traced.samples;
            for (pixel, s) in &traced.pixels {
                let Some(i) = in_crop(*pixel) else {
                    continue;
                };
                out.direct.pixels[i] = s.direct;
                out.albedo.pixels[i] = s.albedo;
                out.normal.pixels[i] = s.normal;
                out.depth.pixels[i] = Vec3::splat(if s.depth.is_finite() { s.depth } else { 0.0 });
                out.alpha[i] = s.alpha.min(1.0);
            }
            out.stats.add(stats);
            for (pixel, l, glossy) in values {
                if let Some(i) = in_crop(*pixel) {
                    out.indirect.pixels[i] += *l;
                    let part = if *glossy {
                        &mut out.indirect_glossy
                    } else {
                        &mut out.indirect_diffuse
                    };
                    part.pixels[i] += *l;
                }
            }
        }
    }
    out.timings.push(("primary and direct", primary_seconds));
    out.timings.push(("gather", gather_seconds));
    for i in 0..out.beauty.pixels.len() {
        for img in [
            &mut out.direct,
            &mut out.indirect,
            &mut out.indirect_diffuse,
            &mut out.indirect_glossy,
        ] {
            if !img.pixels[i].is_finite() {
                img.pixels[i] = Rgb::ZERO;
            }
        }
    }
    out.compose();
    Ok(out)
}

impl FinalOutput {
    /// This render, made at `factor` times the size, box-filtered down: each block of
    /// `factor` × `factor` pixels becomes their mean ([`Image::box_downsample`]: the light, the
    /// albedo; and the coverage), the normal their mean made unit, the depth the nearest hit's,
    /// the beauty direct plus indirect again. `None` unless `factor` divides both sides.
    pub fn filtered_down(mut self, factor: u32) -> Option<FinalOutput> {
        let (w, h) = (self.beauty.width / factor, self.beauty.height / factor);
        // Per pixel of the result, `reduce` over its block's pixel indices in the input.
        let per_block = |reduce: &dyn Fn(&mut dyn Iterator<Item = usize>) -> f32| -> Vec<f32> {
            let (f, fine_width) = (factor as usize, self.beauty.width as usize);
            (0..(w * h) as usize)
                .map(|i| {
                    let (x, y) = (i % w as usize * f, i / w as usize * f);
                    reduce(&mut (0..f * f).map(|k| (y + k / f) * fine_width + x + k % f))
                })
                .collect()
        };
        let scale = 1.0 / (factor * factor) as f32;
        let alpha = per_block(&|block| block.map(|i| self.alpha[i]).sum::<f32>() * scale);
        let depth = per_block(&|block| {
            let nearest = block
                .map(|i| self.depth.pixels[i].x)
                .filter(|&d| d > 0.0)
                .fold(f32::INFINITY, f32::min);
            if nearest.is_finite() {
                nearest
            } else {
                0.0
            }
        });
        let mut normal = self.normal.box_downsample(factor)?;
        for n in &mut normal.pixels {
            *n = n.normalize_or_zero();
        }
        let mut out = FinalOutput {
            beauty: Image::new(w, h),
            direct: self.direct.box_downsample(factor)?,
            indirect: self.indirect.box_downsample(factor)?,
            indirect_diffuse: self.indirect_diffuse.box_downsample(factor)?,
            indirect_glossy: self.indirect_glossy.box_downsample(factor)?,
            albedo: self.albedo.box_downsample(factor)?,
            normal,
            depth: Image {
                width: w,
                height: h,
                pixels: depth.into_iter().map(Rgb::splat).collect(),
            },
            alpha,
            timings: std::mem::take(&mut self.timings),
            stats: self.stats,
            samples: self.samples,
            origin: (self.origin.0 / factor, self.origin.1 / factor),
        };
        out.compose();
        Some(out)
    }

    /// The beauty: direct plus indirect light, pixel by pixel.
    fn compose(&mut self) {
        for ((b, d), i) in self
            .beauty
            .pixels
            .iter_mut()
            .zip(&self.direct.pixels)
            .zip(&self.indirect.pixels)
        {
            *b = *d + *i;
        }
    }

    /// Denoise the indirect light with Intel Open Image Denoise ([`crate::denoise`], on
    /// `threads` threads), guided by the first hit's albedo and normal, and compose the
    /// beauty again. Emission and direct light stay as rendered: denoising the whole beauty
    /// smeared the emitters' edges (caustic's MSE 4.3e-3 → 0.52, docs/render.md). Adds the
    /// seconds it took to the timings as "denoise".
    pub fn denoise_indirect(&mut self, threads: usize) -> Result<()> {
        let t = Instant::now();
        self.indirect =
            crate::denoise::denoise(&self.indirect, &self.albedo, &self.normal, threads)?;
        self.compose();
        self.timings.push(("denoise", t.elapsed().as_secs_f64()));
        Ok(())
    }
}

/// A tile after the primary pass: its pixels (image index, sample), its receivers (dropped
/// once gathered) and its camera samples.
struct TilePrimary {
    pixels: Vec<(u32, PrimarySample)>,
    receivers: Vec<Receiver>,
    samples: u64,
}

/// Refuse, before any work, a render that cannot fit: the floor of what it holds (the
/// crop's nine images, the centre hits of `rect`, one band's pixel samples and gathered
/// values, and the receivers of the tiles in flight, at least one per pixel) above the
/// memory this machine has available. The centre hits of mirrors and glass
/// keep their chains' ends besides, so a render it lets through may still need more.
fn check_fits((cw, ch): (u32, u32), rect: [u32; 4], tile: u32) -> Result<()> {
    let crop = u64::from(cw) * u64::from(ch);
    let centres = u64::from(rect[2] - rect[0]) * u64::from(rect[3] - rect[1]);
    let tile_pixels = u64::from(tile * tile);
    let band = band_tiles(tile) as u64 * tile_pixels;
    let in_flight = rayon::current_num_threads() as u64 * tile_pixels;
    let floor = crop * (8 * size_of::<Rgb>() + size_of::<f32>()) as u64
        + centres * PixelSampling::BYTES_PER_PIXEL as u64
        + band.min(centres) * (size_of::<(u32, PrimarySample)>() + size_of::<Gathered>()) as u64
        + in_flight.min(centres) * size_of::<Receiver>() as u64;
    match crate::machine::available_memory() {
        Some(available) if floor > available => Err(Error::InvalidSetting(format!(
            "a render of {cw}x{ch} pixels needs at least {} MB, and this machine has {} MB \
             available; render it in crops (--crop, or --tile-grid for a farm)",
            floor / 1_000_000,
            available / 1_000_000
        ))),
        _ => Ok(()),
    }
}

/// Trace the pixels of the tile at `origin` of side `tile`.
fn primary_tile(
    ctx: &Tracer,
    camera: &Camera,
    sampling: &PixelSampling,
    settings: &PrimarySettings,
    origin: (u32, u32),
    tile: u32,
) -> TilePrimary {
    let (w, h) = (camera.width, camera.height);
    let mut out = TilePrimary {
        pixels: Vec::new(),
        receivers: Vec::new(),
        samples: 0,
    };
    for y in origin.1..(origin.1 + tile).min(h) {
        for x in origin.0..(origin.0 + tile).min(w) {
            let (sample, samples) =
                sampling.trace_pixel(ctx, camera, settings, (x, y), &mut out.receivers);
            out.samples += u64::from(samples);
            out.pixels.push((y * w + x, sample));
        }
    }
    out
}

/// Make `mb` the buffer of receiver `r`: spherical when it transmits, refined by its BSDF when
/// glossy.
fn prepare_buffer(mb: &mut Microbuffer, r: &Receiver, settings: &FinalSettings) {
    mb.reset(r.bsdf.is_two_sided(), r.frame);
    if settings.adaptive && is_glossy(r, settings) {
        mb.refine_for_bsdf(
            &r.bsdf,
            r.view,
            settings.adaptive_share,
            settings.adaptive_levels,
        );
    }
}

fn is_glossy(r: &Receiver, settings: &FinalSettings) -> bool {
    r.bsdf.alpha().is_some_and(|a| a < settings.glossy_below)
}

/// A glossy receiver that only reflects gathers through a buffer of this many times the
/// base pixels per side ([`FinalSettings::mb_size`]), before its BSDF refines it.
///
/// Refinement splits the pixels that hold its lobe, but the rest of the buffer, the near
/// field's one ray per pixel (`near_field`) and the cut's choice of which leaves are near
/// follow the base grid. wall-glossy's gold box (α 0.05), whose side face the camera sees
/// at about 75°, rendered 8 % darker there than Mitsuba and 3.7 % darker than `--gather paths
/// --spp 1024` reads the same cache; with a 32² base the face is within 1 % of the paths
/// gather, and the buffer's convolution was not at fault (tests/microbuffer.rs holds it to the
/// albedo to 85°). Measured at 256² (docs/render.md, "Glossy receivers on a finer grid"):
/// relMSE −11 % on wall-glossy and cbox-glossy for 9 % and 2 % more render time (18 % and
/// 27 % in a second run, docs/benchmarks.md). Glass keeps
/// the base grid: its spherical buffers at 2 × 32² cost cbox-rough 36 % more time for 4 %
/// less error.
pub const GLOSSY_BASE_FACTOR: u32 = 2;

/// Whether receiver `r` gathers through a buffer of [`GLOSSY_BASE_FACTOR`] times the base side.
fn has_finer_base(r: &Receiver, settings: &FinalSettings) -> bool {
    is_glossy(r, settings) && !r.bsdf.is_two_sided()
}

/// What the gather decides once for the whole frame (so a crop decides it as the frame does).
#[derive(Clone, Copy, Debug)]
struct FramePlan {
    /// The sparse plan's anchor spacing ([`sparse::coarsest_cell`]).
    cell: u32,
    /// FPBGI's clusters in a tile of gathering receivers ([`FinalSettings::clusters`] per
    /// [`CLUSTER_PIXELS`] of the tile's [`tile_side`]²).
    tile_clusters: usize,
    /// Where the paths gather reads the cache: through glossy hits where asked for, the
    /// cache holds every bounce beyond them and no `max_depth` limits the paths.
    paths: paths::Continuation,
    /// How the bright pixels' rays go on through glossy hits, if they do.
    retrace: Option<bright::Retrace>,
}

/// Gather every receiver of a tile (at `origin`, `size` pixels, in an image `width` wide);
/// `sampling`, the frame's centre hits, gives the clearance of those that borrow their light
/// ([`sparse::clearance`]); returns (pixel, weighted indirect radiance, whether it came by a
/// glossy first hit).
fn gather_tile(
    ctx: &Tracer,
    senders: &Senders,
    sampling: &PixelSampling,
    tile: &TilePrimary,
    (origin, size, width): ((u32, u32), (u32, u32), u32),
    frame: FramePlan,
    settings: &FinalSettings,
) -> (Vec<Gathered>, GatherStats) {
    let receivers = &tile.receivers;
    let mut stats = GatherStats {
        receivers: receivers.len() as u64,
        ..Default::default()
    };
    if settings.gather == GatherMode::Paths {
        let out = receivers
            .iter()
            .enumerate()
            .map(|(k, r)| {
                let key = (settings.seed, k as u64);
                (
                    r.pixel,
                    paths::path_gather(ctx, senders, r, settings.spp, frame.paths, key),
                    by_glossy_hit(r),
                )
            })
            .collect();
        return (out, stats);
    }
    // The grid's anchors and the receivers that cannot interpolate gather first; then the
    // others interpolate where their cell allows, finer grids gathering where it does not.
    let plan = SparsePlan::new(receivers, origin, size, width, frame.cell, settings.sparse);
    let mut value = vec![Rgb::ZERO; receivers.len()];
    // How far the surfaces around a primary hit that shade it lie, from the centre hits.
    let clearance = |k: usize| {
        let r = &receivers[k];
        let pixel = (r.pixel % width, r.pixel / width);
        sparse::clearance(r, sampling.surfaces_around(pixel, sparse::CLEARANCE_PIXELS))
    };
    // The luminance of a receiver's pixel before the gather: its emission and direct light
    // (the tile's pixels are in row-major order).
    let floor = |k: usize| {
        let (x, y) = (receivers[k].pixel % width, receivers[k].pixel / width);
        let i = (y - origin.1) * size.0 + (x - origin.0);
        luminance(tile.pixels[i as usize].1.direct)
    };
    let (interpolated, glossy) =
        plan.run(receivers, &mut value, clearance, floor, |which, value| {
            let sets = (&plan, frame.tile_clusters, frame.retrace);
            gather_set(
                (ctx, senders),
                receivers,
                which,
                sets,
                settings,
                value,
                &mut stats,
            )
        });
    stats.interpolated = interpolated as u64;
    stats.interpolated_glossy = glossy as u64;
    let out = receivers
        .iter()
        .enumerate()
        .map(|(k, r)| {
            (
                r.pixel,
                r.weight * (plan.albedo_of(k, r) * value[k]),
                by_glossy_hit(r),
            )
        })
        .collect();
    (out, stats)
}

/// A receiver's gathered light: its pixel, its weighted indirect radiance, and whether it
/// came by a glossy first hit ([`by_glossy_hit`]).
type Gathered = (u32, Rgb, bool);

/// Whether receiver `r`'s light reaches the camera by a glossy or specular first hit (the
/// `indirect_glossy` layer), rather than straight from a diffuse surface.
fn by_glossy_hit(r: &Receiver) -> bool {
    r.chain != 0 || !matches!(r.bsdf, Bsdf::Diffuse(_))
}

/// Gather receivers `which` into `value`: the irradiance of those whose value the plan keeps
/// as irradiance ([`SparsePlan::by_irradiance`]), the outgoing radiance of the others.
///
/// The receivers that gather alone and the clusters are independent of one another, so they
/// are gathered in parallel, each task with buffers of its own: a tile's gather is the unit of
/// the render's work, and the costliest tiles (a light's outline, contacts) take three to
/// four times the mean, so a frame's last tiles left a core idle for 3–7 % of the band's
/// time (cbox-diffuse at 512²); their clusters now spread over every core. Each receiver's
/// value comes from its own gather and the stats are integer sums, so neither depends on
/// which thread took what.
fn gather_set(
    (ctx, senders): (&Tracer, &Senders),
    receivers: &[Receiver],
    which: &[usize],
    (plan, tile_clusters, retrace): (&SparsePlan, usize, Option<bright::Retrace>),
    settings: &FinalSettings,
    value: &mut [Rgb],
    stats: &mut GatherStats,
) {
    let white = Bsdf::Diffuse(Diffuse {
        reflectance: Rgb::ONE,
    });
    let (clustered, alone): (Vec<usize>, Vec<usize>) = which.iter().partition(|&&k| {
        settings.gather == GatherMode::Fpbgi && !is_glossy(&receivers[k], settings)
    });
    // A task's buffer, of `factor` times the base pixels per side, and traversal stack.
    let scratch = |factor: u32| {
        (
            Microbuffer::new(
                factor * settings.mb_size,
                false,
                Frame::from_normal(Vec3::Z),
            ),
            Vec::new(),
        )
    };
    let base_scratch = || scratch(1);
    // Receiver `k`'s buffer filled by `gather`, then shaded: its value.
    let gather_one = |gather: &mut ClusterGather,
                      (mb, stack): &mut (Microbuffer, Vec<u32>),
                      k: usize,
                      stats: &mut GatherStats| {
        let r = &receivers[k];
        prepare_buffer(mb, r, settings);
        // A hemispherical buffer's near field is traced ([`near_field`]); a two-sided
        // receiver's (glass) sees its own surface curving round it, which its cut's rules
        // for its own mesh's discs handle.
        stats.receiver_cut += if mb.spherical {
            gather.fill(r.p, r.mesh, mb, stack)
        } else {
            let near_rays = &mut stats.near_rays;
            let mut trace = |mb: &mut Microbuffer, leaves: &[u32]| {
                *near_rays += near_field::trace_near_field(ctx, senders, r, mb, leaves);
            };
            gather.fill_tracing_near(r.p, r.mesh, mb, stack, &mut trace)
        };
        stats.pixels += mb.pixels.len() as u64;
        let bsdf = if plan.by_irradiance(k) {
            &white
        } else {
            &r.bsdf
        };
        let (reflected, rays) =
            bright::reflect_tracing_bright_pixels(ctx, senders, r, mb, bsdf, retrace);
        stats.bright_rays += rays;
        reflected
    };
    // Each lone receiver's value and what its gather cost.
    let gathered_alone: Vec<(Rgb, GatherStats)> = alone
        .par_iter()
        .map_init(
            || {
                let gather = ClusterGather::alone(senders).whole_straddling_beyond(STRADDLE_RADII);
                (gather, scratch(1), None)
            },
            |(gather, plain, finer), &k| {
                let mut s = GatherStats::default();
                // The finer buffer is made on a task's first glossy receiver, not for every task.
                let buffers = if has_finer_base(&receivers[k], settings) {
                    finer.get_or_insert_with(|| scratch(GLOSSY_BASE_FACTOR))
                } else {
                    plain
                };
                (gather_one(gather, buffers, k, &mut s), s)
            },
        )
        .collect();
    for (&k, (v, s)) in alone.iter().zip(gathered_alone) {
        value[k] = v;
        stats.add(&s);
    }
    if clustered.is_empty() || senders.nodes.is_empty() {
        return;
    }
    let points: Vec<(Vec3, Vec3)> = clustered
        .iter()
        .map(|&k| (receivers[k].p, receivers[k].frame.n))
        .collect();
    // `clusters` per [`CLUSTER_PIXELS`] of receivers, up to the tile's: as many fewer as the
    // set has fewer receivers than the tile has pixels, so that a cluster's shared cut still
    // serves about as many members.
    let count = tile_clusters.min((settings.clusters * points.len()).div_ceil(CLUSTER_PIXELS));
    let clusters = cluster(&points, count);
    stats.clustered += clustered.len() as u64;
    stats.clusters += clusters.len() as u64;
    // Each cluster's members' values and what its gathers cost.
    let gathered_clusters: Vec<(Vec<(usize, Rgb)>, GatherStats)> = clusters
        .par_iter()
        .map_init(base_scratch, |scratch, c| {
            let active = &receivers[clustered[c.active as usize]];
            let cluster_receivers = ClusterReceivers::of(
                c,
                (active.p, active.mesh, active.frame),
                active.bsdf.is_two_sided(),
                false,
            );
            let mut gather = ClusterGather::shared(
                senders,
                &cluster_receivers,
                settings.far_eps,
                settings.mb_size,
            )
            .whole_straddling_beyond(STRADDLE_RADII);
            let mut s = GatherStats {
                cluster_cut: gather.shared_stats(),
                ..Default::default()
            };
            let values = c
                .members
                .iter()
                .map(|&m| {
                    let k = clustered[m as usize];
                    (k, gather_one(&mut gather, scratch, k, &mut s))
                })
                .collect();
            (values, s)
        })
        .collect();
    for (values, s) in gathered_clusters {
        for (k, v) in values {
            value[k] = v;
        }
        stats.add(&s);
    }
}

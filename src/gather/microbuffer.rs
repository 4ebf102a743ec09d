//! The microbuffer: a receiver's small RGBZ image of its incoming light (docs/method.md §2.3, §7).
//!
//! The pixels tile the hemisphere around the receiver's normal with the equal-area concentric
//! map (docs/design.md §5.3), so a pixel's solid angle is 2π times its area in the map's unit square
//! and every pixel is valid (the thesis's Nusselt map has neither property). A spherical
//! microbuffer, for receivers that transmit, adds a second grid for the lower hemisphere.
//!
//! The buffer is adaptive (docs/method.md §7.2): it starts as a uniform n × n grid per hemisphere, and any
//! pixel can be split 2 × 2, recursively, where the receiver's BSDF needs finer directions
//! ([`Microbuffer::refine_for_bsdf`]). A uniform buffer is the case with no split.
//!
//! Senders, each no wider than a pixel (the cut splits wider surfels into pieces), are
//! recorded with their coverage of the pixels they fall on and composited front to back by
//! [`Microbuffer::resolve`]. Convolution with the
//! receiver's BSDF gives the outgoing radiance, L_o(ω_o) = Σₖ Lₖ f(ω_o, ωₖ) |cos θₖ| sₖ
//! (spec Eq. 2.1, with the pixel solid angle sₖ that Eq. 4.9 omits).

use super::lookup::Lookup;
use crate::bsdf::{Bsdf, TransportMode};
use crate::geometry::frame::Frame;
use crate::geometry::warp::{hemisphere_equal_area_to_square, square_to_hemisphere_equal_area};
use crate::spectrum::{luminance, Rgb};
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::f32::consts::TAU;
use std::sync::{Arc, Mutex, OnceLock};

const NO_CELL: u32 = u32::MAX;

/// The most one layer may cover a pixel (see [`Microbuffer::resolve`]).
pub const MAX_LAYER_COVER: f32 = 2.0;

/// The share of a glossy receiver's reflected light that its faint base pixels hold together
/// at most ([`Microbuffer::refine_for_bsdf`]): the directions far from its lobe, where the cut
/// need not open the far nodes that straddle the receiver's plane (`gather::cut`). At 1 %, a
/// cbox-glossy render at 512² visited 17 % fewer nodes in 0.96 of the time, at the same
/// relMSE (docs/render.md).
pub const FAINT_LIGHT: f32 = 0.01;

/// A refined buffer's pixel that holds more than this share of its receiver's BSDF weight
/// ([`Microbuffer::refine_for_bsdf`]) is convolved with the BSDF's mean over a
/// [`LOBE_QUADRATURE`]² grid of equal-area parts of it, not its value at the centre. The
/// midpoint rule misses the curvature of a narrow lobe: a rough dielectric's transmitted lobe
/// (α 0.1, η 1.5) under uniform light came out up to 7.4 % dark in refined buffers
/// (`tests/microbuffer.rs`), and a glass sphere under a white sky 11 % with the cut's light
/// (`tests/glass_furnace.rs`). The share leaves the pixels far
/// from the lobe, which hold almost none of the light, at one evaluation.
pub const LOBE_QUADRATURE_SHARE: f32 = 1.0 / 4096.0;

/// The parts per side of a lobe pixel's quadrature ([`LOBE_QUADRATURE_SHARE`]). Under uniform
/// light, α 0.1 glass's transmitted light with 1, 2, 4 and 8 parts per side in every pixel:
/// 0.926–1.008, 0.971–0.999, 0.991–1.000 and 0.998–1.000 of the exact integral, θo 0–45°.
pub const LOBE_QUADRATURE: u32 = 4;

/// The least cosine between the normals of two senders of one surface (30°): what
/// [`Shape::same_surface`] and [`Microbuffer::is_mixed`] take as facing one way.
const SAME_FACING: f32 = 0.866;

/// A square of one hemisphere's unit square: a pixel, or a pixel that was split.
#[derive(Clone, Copy, Debug)]
struct Cell {
    corner: Vec2,
    side: f32,
    lower: bool,
    /// The first of four consecutive child cells (x-major quadrants), or [`NO_CELL`].
    children: u32,
    /// The pixel of a leaf cell.
    pixel: u32,
}

/// One pixel of the buffer.
#[derive(Clone, Copy, Debug)]
pub struct Pixel {
    /// The local unit direction through its centre.
    pub dir: Vec3,
    /// Its solid angle.
    pub solid_angle: f32,
    /// The exact mean of |cos θ| over the pixel divided by |cos θ| at its centre.
    pub cos_weight: f32,
    /// How many times its base pixel was split to make it.
    pub level: u32,
    cell: u32,
}

/// A sender as a microbuffer records it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sender {
    /// Its centre relative to the receiver (world axes).
    pub offset: Vec3,
    /// Its bounding radius.
    pub radius: f32,
    /// Its unit normal when all its surfels face about one way, else zero: senders of one
    /// surface are told from occluders by it.
    pub normal: Vec3,
    /// Its radiance towards the receiver.
    pub radiance: Rgb,
    /// Where that radiance is read (what a buffer that records links keeps).
    pub lookup: Lookup,
}

impl Sender {
    /// A sender without a known orientation along unit direction `w` at distance `dist`.
    pub fn at(w: Vec3, dist: f32, radius: f32, radiance: Rgb) -> Sender {
        Sender {
            offset: w * dist,
            radius,
            normal: Vec3::ZERO,
            radiance,
            lookup: Lookup::Nothing,
        }
    }

    fn shape(&self) -> Shape {
        Shape {
            offset: self.offset,
            radius: self.radius,
            normal: self.normal,
        }
    }
}

/// Where a sender lies, as compositing needs it (see [`Shape::same_surface`]).
#[derive(Clone, Copy, Debug)]
struct Shape {
    offset: Vec3,
    radius: f32,
    normal: Vec3,
}

impl Shape {
    /// Whether `b`, no nearer than `self`, lies on the same surface: when their depths are
    /// within their radii and the pixel's depth footprint `spread` (the pixel's angular size
    /// times the distance), which holds a curved surface together, or, with both
    /// orientations known and within 30°, when `b`'s centre is within their radii of
    /// `self`'s plane, which holds a plane seen at a grazing angle together. `da` and `db`
    /// are the lengths of their offsets (what [`Splat::dist`] keeps).
    fn same_surface(&self, da: f32, b: &Shape, db: f32, spread: f32) -> bool {
        let coplanar = self.normal != Vec3::ZERO
            && b.normal != Vec3::ZERO
            && self.normal.dot(b.normal) > SAME_FACING
            && (b.offset - self.offset).dot(self.normal).abs() <= self.radius + b.radius;
        coplanar || db - 2.0 * b.radius <= da + 2.0 * self.radius + 2.0 * da * spread
    }
}

/// Where a direction falls in a buffer ([`Microbuffer::locate`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Located {
    /// |cos θ| of the direction in the buffer's frame.
    cos: f32,
    /// Its point of the hemisphere's unit square.
    square: Vec2,
    /// Whether it lies in the lower hemisphere.
    lower: bool,
}

/// A sender recorded in a pixel, waiting for [`Microbuffer::resolve`].
#[derive(Clone, Copy, Debug)]
struct Splat {
    pixel: u32,
    dist: f32,
    /// |cos θ| of its direction in the receiver's frame.
    cos: f32,
    /// The fraction of the pixel it covers.
    coverage: f32,
    shape: Shape,
    radiance: Rgb,
    /// Its lookup's index in the buffer's [`Links::sources`], or [`NO_SOURCE`].
    source: u32,
}

/// A splat whose buffer records no links.
pub(crate) const NO_SOURCE: u32 = u32::MAX;

/// One term of a pixel's light in a buffer that records links: pixel `pixel`'s radiance is
/// Σ `w` · L(`source`) over its links, and its cosine-weighted radiance Σ `w_cos` · L(`source`),
/// with L(source) the radiance at [`Links::sources`]`[source]`. The weights are geometry alone
/// (coverage, compositing, closing), so the same links serve any light the tree sends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelLink {
    /// The buffer pixel.
    pub pixel: u32,
    /// Index into [`Links::sources`].
    pub source: u32,
    /// Weight of the source's radiance in the pixel's radiance.
    pub w: f32,
    /// Its weight in the pixel's cosine-weighted radiance.
    pub w_cos: f32,
}

/// A buffer's light as links (see [`PixelLink`]).
#[derive(Clone, Debug, Default)]
pub struct Links {
    /// The lookups the links read.
    pub sources: Vec<Lookup>,
    /// The links, in no particular order once the buffer is closed.
    pub entries: Vec<PixelLink>,
    /// Right after [`Microbuffer::resolve`], `entries` run pixel by pixel and pixel k's end
    /// at `ends[k]`.
    ends: Vec<u32>,
}

impl Links {
    /// The links of pixel `k`, as [`Microbuffer::resolve`] left them.
    fn of_pixel(&self, k: usize) -> &[PixelLink] {
        let begin = if k == 0 { 0 } else { self.ends[k - 1] as usize };
        &self.entries[begin..self.ends[k] as usize]
    }
}

/// A receiver's microbuffer.
#[derive(Clone, Debug)]
pub struct Microbuffer {
    /// Base pixels per side of each hemisphere's grid.
    pub n: u32,
    /// Whether it covers the whole sphere (a transmitting receiver) or the hemisphere
    /// above `frame.n`.
    pub spherical: bool,
    /// The receiver's shading frame (its normal is `frame.n`).
    pub frame: Frame,
    cells: Vec<Cell>,
    /// Its pixels (directions and solid angles), coarse cells and refined ones alike.
    pub pixels: Vec<Pixel>,
    /// After [`Microbuffer::resolve`]: per pixel, the composited radiance (its mean over the
    /// pixel), the same weighted by each sender's own |cos θ| (what the convolution uses, so
    /// that a pixel half covered by the upper part of a surface is not weighted by the
    /// pixel's mean cosine), the distance to
    /// the nearest sender (∞ where none) and the covered fraction.
    pub radiance: Vec<Rgb>,
    /// See `radiance`.
    pub cos_radiance: Vec<Rgb>,
    /// See `radiance`.
    pub depth: Vec<f32>,
    /// See `radiance`.
    pub alpha: Vec<f32>,
    /// After [`Microbuffer::resolve`]: per pixel, the coverage its radiance was summed over
    /// (up to [`MAX_LAYER_COVER`]; `alpha` is this clamped to 1).
    pub coverage: Vec<f32>,
    pending: Vec<Splat>,
    /// Cells still to visit while splatting (kept to save allocations).
    scratch: Vec<u32>,
    /// Splat order, per-pixel run ends and sort keys while resolving (kept to save
    /// allocations).
    order: Vec<u32>,
    starts: Vec<u32>,
    keys: Vec<u64>,
    /// The light as links, when the buffer records them ([`Microbuffer::record_links`]).
    links: Option<Box<Links>>,
    /// Per base pixel, after [`Microbuffer::refine_for_bsdf`]: whether its part of the
    /// receiver's reflected light is faint ([`Microbuffer::is_faint_at`]); empty where none
    /// is.
    faint: Vec<bool>,
    /// After [`Microbuffer::refine_for_bsdf`]: per pixel, whether it is convolved by
    /// quadrature ([`LOBE_QUADRATURE_SHARE`]); empty where none is.
    lobe: Vec<bool>,
    /// After [`Microbuffer::resolve`] of a buffer that records links: per pixel, whether it
    /// holds more than one surface (see [`Microbuffer::is_mixed`]); empty otherwise.
    mixed: Vec<bool>,
}

/// The base grid of one size, built once and copied into every buffer of that size.
#[derive(Debug)]
struct BaseGrid {
    cells: Vec<Cell>,
    pixels: Vec<Pixel>,
}

/// Base grids by (size, spherical).
type GridCache = Mutex<HashMap<(u32, bool), Arc<BaseGrid>>>;

fn base_grid(n: u32, spherical: bool) -> Arc<BaseGrid> {
    static GRIDS: OnceLock<GridCache> = OnceLock::new();
    let grids = GRIDS.get_or_init(Default::default);
    let mut grids = grids.lock().unwrap_or_else(|e| e.into_inner());
    grids
        .entry((n, spherical))
        .or_insert_with(|| {
            let hemispheres = if spherical { 2 } else { 1 };
            let side = 1.0 / n as f32;
            let mut cells = Vec::new();
            let mut pixels = Vec::new();
            for h in 0..hemispheres {
                for y in 0..n {
                    for x in 0..n {
                        let cell = Cell {
                            corner: Vec2::new(x as f32, y as f32) * side,
                            side,
                            lower: h == 1,
                            children: NO_CELL,
                            pixel: pixels.len() as u32,
                        };
                        pixels.push(pixel_of_cell(&cell, cells.len() as u32, 0));
                        cells.push(cell);
                    }
                }
            }
            Arc::new(BaseGrid { cells, pixels })
        })
        .clone()
}

fn pixel_of_cell(c: &Cell, cell: u32, level: u32) -> Pixel {
    let mut dir = square_to_hemisphere_equal_area(c.corner + Vec2::splat(0.5 * c.side));
    if c.lower {
        dir.z = -dir.z;
    }
    Pixel {
        dir,
        solid_angle: TAU * c.side * c.side,
        cos_weight: cosine_weight(c.corner, c.side),
        level,
        cell,
    }
}

/// For the square [c, c + side]² of the unit square (aligned to an even grid, so it lies on one
/// side of each axis of the concentric map), the ratio of its exact mean cos θ to cos θ at its
/// centre. On the concentric map z = 1 − r² with r = max(|x|, |y|) over [−1, 1]², so the mean
/// has a closed form; the centre value alone overestimates every ring by (2/n)²/4, which summed
/// is a 2/n² bias of every convolution (0.8 % at n = 16).
fn cosine_weight(corner: Vec2, side: f32) -> f32 {
    let h = 2.0 * side as f64;
    let (x0, y0) = (2.0 * corner.x as f64 - 1.0, 2.0 * corner.y as f64 - 1.0);
    // Fold into the first quadrant: [a, a + h] × [b, b + h], which lies where x ≥ y, where
    // y ≥ x, or on the diagonal (a = b).
    let fold = |lo: f64| if lo >= -1e-9 { lo.max(0.0) } else { -lo - h };
    let (a, b) = (fold(x0), fold(y0));
    let (lo, hi) = (a.max(b), a.max(b) + h);
    let mean_r2 = if (a - b).abs() > 0.5 * h {
        // r is the larger coordinate throughout, uniform over [lo, hi].
        (hi.powi(3) - lo.powi(3)) / (3.0 * h)
    } else {
        // The square [lo, hi]²: mean of max² = 2/h² ∫ x² (x − lo) dx over [lo, hi].
        2.0 / (h * h) * ((hi.powi(4) - lo.powi(4)) / 4.0 - lo * (hi.powi(3) - lo.powi(3)) / 3.0)
    };
    let centre = 1.0 - (lo + 0.5 * h).powi(2);
    ((1.0 - mean_r2) / centre) as f32
}

/// Sort `keys` (distinct) ascending: by insertion for the few splats a pixel usually holds,
/// where the standard sort's dispatch was the hottest part of [`Microbuffer::resolve`] in a
/// profile.
fn sort_small(keys: &mut [u64]) {
    const INSERTION: usize = 24;
    if keys.len() > INSERTION {
        keys.sort_unstable();
        return;
    }
    for i in 1..keys.len() {
        let key = keys[i];
        let mut j = i;
        while j > 0 && keys[j - 1] > key {
            keys[j] = keys[j - 1];
            j -= 1;
        }
        keys[j] = key;
    }
}

/// Overlap of the intervals [a0, a1] and [b0, b1].
#[inline]
fn overlap(a0: f32, a1: f32, b0: f32, b1: f32) -> f32 {
    (a1.min(b1) - a0.max(b0)).max(0.0)
}

impl Microbuffer {
    /// Pixels per side (per hemisphere) of a diffuse receiver's buffer: the final render's
    /// default (`FinalSettings::mb_size`) and the bounces' buffer for diffuse surfels.
    pub const DEFAULT_SIDE: u32 = 16;

    /// An empty uniform buffer of `n × n` pixels per hemisphere around the normal of `frame`;
    /// `n` must be even (the pixel grid then follows the concentric map's rings).
    pub fn new(n: u32, spherical: bool, frame: Frame) -> Self {
        assert!(
            n >= 2 && n.is_multiple_of(2),
            "microbuffer size must be even"
        );
        let base = base_grid(n, spherical);
        let count = base.pixels.len();
        Microbuffer {
            n,
            spherical,
            frame,
            cells: base.cells.clone(),
            pixels: base.pixels.clone(),
            radiance: vec![Rgb::ZERO; count],
            cos_radiance: vec![Rgb::ZERO; count],
            depth: vec![f32::INFINITY; count],
            alpha: vec![0.0; count],
            coverage: vec![0.0; count],
            pending: Vec::new(),
            scratch: Vec::new(),
            order: Vec::new(),
            starts: Vec::new(),
            keys: Vec::new(),
            links: None,
            faint: Vec::new(),
            lobe: Vec::new(),
            mixed: Vec::new(),
        }
    }

    /// Keep, beside the radiance, each pixel's light as links to the senders' lookups (see
    /// [`PixelLink`]): what the bake's transport stores.
    pub fn record_links(&mut self) {
        self.links = Some(Box::default());
    }

    /// The links, if the buffer records them.
    pub fn links(&self) -> Option<&Links> {
        self.links.as_deref()
    }

    /// The index of `lookup` among the links' sources ([`NO_SOURCE`] when not recording).
    fn source_of(&mut self, lookup: Lookup) -> u32 {
        match &mut self.links {
            Some(links) => {
                links.sources.push(lookup);
                (links.sources.len() - 1) as u32
            }
            None => NO_SOURCE,
        }
    }

    /// Empty the buffer for another receiver, with the base grid of a uniform buffer (reusing
    /// its memory: a new buffer per receiver cost 2 % of a render).
    pub fn reset(&mut self, spherical: bool, frame: Frame) {
        if spherical != self.spherical || self.is_refined() {
            let base = base_grid(self.n, spherical);
            let count = base.pixels.len();
            self.spherical = spherical;
            self.cells.clone_from(&base.cells);
            self.pixels.clone_from(&base.pixels);
            for v in [&mut self.radiance, &mut self.cos_radiance] {
                v.truncate(count);
                v.resize(count, Rgb::ZERO);
            }
            self.depth.resize(count, f32::INFINITY);
            self.depth.truncate(count);
            for v in [&mut self.alpha, &mut self.coverage] {
                v.resize(count, 0.0);
                v.truncate(count);
            }
        }
        self.frame = frame;
        self.pending.clear();
        self.faint.clear();
        self.lobe.clear();
        if let Some(links) = &mut self.links {
            links.sources.clear();
            links.entries.clear();
        }
    }

    /// Whether pixel `k`, as [`Microbuffer::resolve`] left it, holds more than one surface:
    /// senders whose normals differ by more than 30° (or one without a normal: a node whose
    /// surfels face many ways), or that lie apart in depth. Its coverages then composite
    /// layers that may hide one another's brightest parts, which a pixel-wide coverage cannot
    /// resolve (`bake::bounce::close_buffer` traces such pixels). Classified only in a buffer
    /// that records links (the bake's); `false` in any other.
    pub fn is_mixed(&self, k: usize) -> bool {
        self.mixed.get(k).copied().unwrap_or(false)
    }

    /// Whether pixel `k` borders the horizon: its square touches the edge of its hemisphere's
    /// unit square, which the equal-area map takes to the horizon. There the cut's footprints
    /// are clipped and what falls past the edge is moved inside ([`Microbuffer::splat`]).
    pub fn at_horizon(&self, k: usize) -> bool {
        let cell = &self.cells[self.pixels[k].cell as usize];
        let far = cell.corner + Vec2::splat(cell.side);
        cell.corner.x <= 0.0 || cell.corner.y <= 0.0 || far.x >= 1.0 || far.y >= 1.0
    }

    /// Mark pixel `k` as holding more than one surface ([`Microbuffer::is_mixed`]): a shared
    /// buffer's light composited with the member's own.
    pub(crate) fn mark_mixed(&mut self, k: usize) {
        if let Some(m) = self.mixed.get_mut(k) {
            *m = true;
        }
    }

    /// Whether any pixel was split.
    pub(crate) fn is_refined(&self) -> bool {
        self.cells.len() as u32 > self.n * self.n * if self.spherical { 2 } else { 1 }
    }

    /// Solid angle of a base pixel.
    pub fn pixel_solid_angle(&self) -> f32 {
        TAU / (self.n * self.n) as f32
    }

    /// Whether `at` lies in a base pixel whose part of the receiver's reflected light is
    /// faint (see [`Microbuffer::refine_for_bsdf`]): a cut may stay coarse there.
    pub(crate) fn is_faint_at(&self, at: &Located) -> bool {
        !self.faint.is_empty() && self.faint[self.base_cell(at.square, at.lower) as usize]
    }

    /// Where world direction `w` (unit) falls in the buffer, or `None` below the horizon of a
    /// hemispherical buffer: found once for the cut's pixel test ([`Microbuffer::solid_angle_at`])
    /// and the splat ([`Microbuffer::splat_at`]), which both need it.
    #[inline]
    pub(crate) fn locate(&self, w: Vec3) -> Option<Located> {
        let local = self.frame.to_local(w);
        let (square, lower) = self.square_of(local)?;
        Some(Located {
            cos: local.z.abs(),
            square,
            lower,
        })
    }

    /// The solid angle of the pixel at `at`. A uniform buffer needs no pixel lookup.
    #[inline]
    pub(crate) fn solid_angle_at(&self, at: &Located) -> f32 {
        if !self.is_refined() {
            return self.pixel_solid_angle();
        }
        let cell = self.cell_at(at.square, at.lower);
        self.pixels[self.cells[cell as usize].pixel as usize].solid_angle
    }

    /// The point of the unit square and the hemisphere of local direction `l`, or `None` below
    /// the horizon of a hemispherical buffer.
    fn square_of(&self, l: Vec3) -> Option<(Vec2, bool)> {
        let lower = l.z < 0.0;
        if lower && !self.spherical {
            return None;
        }
        let p = hemisphere_equal_area_to_square(Vec3::new(l.x, l.y, l.z.abs()));
        Some((p.clamp(Vec2::ZERO, Vec2::ONE), lower))
    }

    /// The base cell (and base pixel: the base grid numbers both alike) holding point `p` of
    /// a hemisphere.
    fn base_cell(&self, p: Vec2, lower: bool) -> u32 {
        let n = self.n;
        let x = ((p.x * n as f32) as u32).min(n - 1);
        let y = ((p.y * n as f32) as u32).min(n - 1);
        (u32::from(lower) * n + y) * n + x
    }

    /// The leaf cell holding point `p` of a hemisphere.
    fn cell_at(&self, p: Vec2, lower: bool) -> u32 {
        let mut c = self.base_cell(p, lower);
        while self.cells[c as usize].children != NO_CELL {
            let cell = &self.cells[c as usize];
            let mid = cell.corner + Vec2::splat(0.5 * cell.side);
            c = cell.children + u32::from(p.x >= mid.x) + 2 * u32::from(p.y >= mid.y);
        }
        c
    }

    /// The pixel that sees world direction `w` (unit), or `None` below the horizon of a
    /// hemispherical buffer.
    pub fn pixel_of(&self, w: Vec3) -> Option<usize> {
        self.local_pixel_of(self.frame.to_local(w))
    }

    /// [`Microbuffer::pixel_of`] for a direction in the buffer's local frame.
    pub fn local_pixel_of(&self, l: Vec3) -> Option<usize> {
        let (p, lower) = self.square_of(l)?;
        Some(self.cells[self.cell_at(p, lower) as usize].pixel as usize)
    }

    /// The local direction at the centre of pixel `k`.
    pub fn local_direction(&self, k: usize) -> Vec3 {
        self.pixels[k].dir
    }

    /// Split pixel `k` into 2 × 2 (its index stays with the first quadrant; the other three
    /// are appended).
    pub fn split(&mut self, k: usize) {
        let cell_index = self.pixels[k].cell;
        let level = self.pixels[k].level + 1;
        let parent = self.cells[cell_index as usize];
        let first = self.cells.len() as u32;
        let half = 0.5 * parent.side;
        for q in 0..4u32 {
            let corner = parent.corner + Vec2::new((q % 2) as f32, (q / 2) as f32) * half;
            let pixel = if q == 0 {
                k as u32
            } else {
                self.pixels.len() as u32
            };
            let cell = Cell {
                corner,
                side: half,
                lower: parent.lower,
                children: NO_CELL,
                pixel,
            };
            let px = pixel_of_cell(&cell, first + q, level);
            if q == 0 {
                self.pixels[k] = px;
            } else {
                self.pixels.push(px);
                self.radiance.push(Rgb::ZERO);
                self.cos_radiance.push(Rgb::ZERO);
                self.depth.push(f32::INFINITY);
                self.alpha.push(0.0);
                self.coverage.push(0.0);
            }
            self.cells.push(cell);
        }
        self.cells[cell_index as usize].children = first;
    }

    /// BSDF importance (docs/method.md §7.1–§7.2, F_ρ): split every pixel whose share of the receiver's
    /// reflected light, w = max f·|cos| over the pixel × its solid angle, exceeds `share` of
    /// the total over the base pixels, down to `max_level` splits. The maximum is taken over a
    /// 3 × 3 grid of directions in the pixel and the lobe centres that fall in it, so that a
    /// lobe narrower than a pixel is never missed. `wo` is the outgoing direction (local).
    /// The base pixels far from the lobe are marked faint (`Microbuffer::is_faint_at`).
    pub fn refine_for_bsdf(&mut self, bsdf: &Bsdf, wo: Vec3, share: f32, max_level: u32) {
        let centres: Vec<Vec3> = bsdf.lobe_centres(wo).into_iter().flatten().collect();
        let mut lanes = BsdfLanes::default();
        let base = self.pixels.len();
        let weights: Vec<f32> = (0..base)
            .map(|k| lanes.weight(self, k, bsdf, wo, &centres))
            .collect();
        let total: f32 = weights.iter().sum();
        if !(total > 0.0) || !total.is_finite() {
            return;
        }
        self.mark_faint(&weights, total);
        let mut lobe: Vec<bool> = weights
            .iter()
            .map(|&w| w > LOBE_QUADRATURE_SHARE * total)
            .collect();
        let mut queue: Vec<(usize, f32)> = weights.into_iter().enumerate().collect();
        while let Some((k, w)) = queue.pop() {
            if w <= share * total || self.pixels[k].level >= max_level {
                continue;
            }
            let first_new = self.pixels.len();
            self.split(k);
            lobe.resize(self.pixels.len(), false);
            for child in std::iter::once(k).chain(first_new..first_new + 3) {
                let wc = lanes.weight(self, child, bsdf, wo, &centres);
                lobe[child] = wc > LOBE_QUADRATURE_SHARE * total;
                queue.push((child, wc));
            }
        }
        self.lobe = lobe;
    }

    /// Mark the base pixels (of BSDF weights `weights`, summing to `total`) whose reflected
    /// light is faint: the faintest, which together hold at most [`FAINT_LIGHT`] of the
    /// total, and whose neighbours (the eight around them) are as faint.
    fn mark_faint(&mut self, weights: &[f32], total: f32) {
        let mut order: Vec<usize> = (0..weights.len()).collect();
        order.sort_by(|&a, &b| weights[a].total_cmp(&weights[b]).then(a.cmp(&b)));
        let mut low = vec![false; weights.len()];
        let mut sum = 0.0;
        for k in order {
            sum += weights[k];
            if sum > FAINT_LIGHT * total {
                break;
            }
            low[k] = true;
        }
        let n = self.n as i32;
        self.faint = (0..weights.len())
            .map(|k| {
                let (h, y, x) = (k as i32 / (n * n), (k as i32 / n) % n, k as i32 % n);
                (-1..=1).all(|dy| {
                    (-1..=1).all(|dx| {
                        let (xx, yy) = (x + dx, y + dy);
                        !(0..n).contains(&xx)
                            || !(0..n).contains(&yy)
                            || low[((h * n + yy) * n + xx) as usize]
                    })
                })
            })
            .collect();
        if !self.faint.iter().any(|&f| f) {
            self.faint.clear();
        }
    }

    /// Record `sender`, covering `solid_angle` steradians. Its footprint, a square of that
    /// area centred on its direction in the (equal-area) map, is shared among the pixels it
    /// overlaps, so that a surface tiled by small senders covers every pixel behind it once,
    /// not some pixels twice and their neighbours not at all. Returns whether its direction
    /// has a pixel.
    pub fn splat(&mut self, sender: &Sender, solid_angle: f32) -> bool {
        let dist = sender.offset.length();
        if !(dist > 0.0) {
            return false;
        }
        match self.locate(sender.offset / dist) {
            Some(at) => self.splat_at(sender, dist, at, solid_angle),
            None => false,
        }
    }

    /// [`Microbuffer::splat`] of a sender at distance `dist` (the length of its offset) whose
    /// direction, its offset over `dist`, falls at `at`.
    pub(crate) fn splat_at(
        &mut self,
        sender: &Sender,
        dist: f32,
        at: Located,
        solid_angle: f32,
    ) -> bool {
        let Located {
            cos,
            square: p,
            lower,
        } = at;
        if !(solid_angle > 0.0) || !dist.is_finite() {
            return false;
        }
        // Half the side of the footprint in the unit square (whose area is 2π sr); nothing
        // covers more than a hemisphere.
        let solid_angle = solid_angle.min(TAU);
        let half = 0.5 * (solid_angle / TAU).sqrt();
        let (x0, x1) = ((p.x - half).max(0.0), (p.x + half).min(1.0));
        let (y0, y1) = ((p.y - half).max(0.0), (p.y + half).min(1.0));
        // What falls past the horizon (the map's edge) is moved inside, not lost.
        let area = (x1 - x0) * (y1 - y0);
        if !(area > 0.0) {
            return false;
        }
        let source = self.source_of(sender.lookup);
        let n = self.n as f32;
        let base = u32::from(lower) * self.n * self.n;
        let (bx0, bx1) = ((x0 * n) as u32, ((x1 * n) as u32).min(self.n - 1));
        let (by0, by1) = ((y0 * n) as u32, ((y1 * n) as u32).min(self.n - 1));
        let mut stack = std::mem::take(&mut self.scratch);
        for by in by0..=by1 {
            for bx in bx0..=bx1 {
                stack.push(base + by * self.n + bx);
                while let Some(c) = stack.pop() {
                    let cell = self.cells[c as usize];
                    let (cx0, cy0) = (cell.corner.x, cell.corner.y);
                    let o = overlap(x0, x1, cx0, cx0 + cell.side)
                        * overlap(y0, y1, cy0, cy0 + cell.side);
                    if o <= 0.0 {
                        continue;
                    }
                    if cell.children != NO_CELL {
                        stack.extend(cell.children..cell.children + 4);
                        continue;
                    }
                    let k = cell.pixel as usize;
                    // One sender covers a pixel at most once (a huge near one is clamped to
                    // the map).
                    let coverage = (solid_angle * (o / area) / self.pixels[k].solid_angle).min(1.0);
                    self.record(k, (dist, cos, coverage), sender, source);
                }
            }
        }
        self.scratch = stack;
        true
    }

    /// Record what rays through the centres of pixels found (`hits`: a pixel and the surface
    /// its ray hit, as a sender at the hit point with the surface's normal): each covers its
    /// whole pixel, with the pixel's exact mean cosine, and hides the senders recorded there
    /// that lie behind it or on its surface (their centre within their radius of its plane:
    /// a pixel spans more depth than a sender's radius where it sees a surface obliquely).
    /// The render's traced near field (`render::near_field`).
    pub(crate) fn record_hits(&mut self, hits: &[(usize, Sender)]) {
        let mut hit_of = vec![u32::MAX; self.pixels.len()];
        for (i, (k, _)) in hits.iter().enumerate() {
            hit_of[*k] = i as u32;
        }
        self.pending.retain(|s| {
            let Some((_, hit)) = hits.get(hit_of[s.pixel as usize] as usize) else {
                return true;
            };
            let behind = s.dist + s.shape.radius >= hit.offset.length();
            let on_it = (s.shape.offset - hit.offset).dot(hit.normal).abs() <= s.shape.radius;
            !(behind || on_it)
        });
        for (k, sender) in hits {
            let (dist, cos) = (sender.offset.length(), self.mean_cos(*k));
            let source = self.source_of(sender.lookup);
            self.record(*k, (dist, cos, 1.0), sender, source);
        }
    }

    /// Record `sender` covering the fraction `coverage` of pixel `k`.
    pub fn cover(&mut self, k: usize, sender: &Sender, coverage: f32) {
        let dist = sender.offset.length();
        if coverage > 0.0 && dist > 0.0 && dist.is_finite() {
            let cos = self.frame.to_local(sender.offset / dist).z.abs();
            let source = self.source_of(sender.lookup);
            self.record(k, (dist, cos, coverage), sender, source);
        }
    }

    fn record(
        &mut self,
        k: usize,
        (dist, cos, coverage): (f32, f32, f32),
        sender: &Sender,
        source: u32,
    ) {
        self.pending.push(Splat {
            pixel: k as u32,
            dist,
            cos,
            coverage,
            shape: sender.shape(),
            radiance: sender.radiance,
            source,
        });
    }

    /// Composite the recorded senders front to back in every pixel.
    ///
    /// Senders are grouped into layers, each the nearest remaining sender and those on its
    /// surface (see [`Sender`]; by depth alone, a surface seen at a grazing angle would split
    /// into layers that hide one another). Within a layer the coverages add without a clamp:
    /// the senders tile the surface, and a pixel that one of them overlaps by more than its
    /// share is balanced by a neighbour that gets less (clamping each pixel at full coverage
    /// loses 6 % of the light under an emitting disc at 16 × 16). A layer behind fills at most
    /// what the nearer ones left open. A pixel half covered by the edge of a surface gets half
    /// its light (a plain z-test lights it fully: +24 % irradiance under a disc at 16 × 16).
    pub fn resolve(&mut self) {
        self.radiance.fill(Rgb::ZERO);
        self.cos_radiance.fill(Rgb::ZERO);
        self.alpha.fill(0.0);
        self.coverage.fill(0.0);
        self.depth.fill(f32::INFINITY);
        // Only the bake traces mixed pixels (`bake::bounce::close_buffer`), and only its
        // buffers record links: a render's resolve does not classify them.
        let classify_mixed = self.links.is_some();
        self.mixed.clear();
        if classify_mixed {
            self.mixed.resize(self.pixels.len(), false);
        }
        let splats = std::mem::take(&mut self.pending);
        let order = self.order_by_pixel_and_depth(&splats);
        let mut links = self.links.take();
        if let Some(l) = &mut links {
            l.entries.clear();
            l.ends.clear();
        }
        let mut begin = 0;
        for k in 0..self.pixels.len() {
            let end = self.starts[k] as usize;
            let run = &order[begin..end];
            begin = end;
            let Some(&first) = run.first() else {
                if let Some(l) = &mut links {
                    l.ends.push(l.entries.len() as u32);
                }
                continue;
            };
            let footprint = self.pixels[k].solid_angle.sqrt();
            if classify_mixed {
                let front = &splats[first as usize];
                self.mixed[k] = front.shape.normal == Vec3::ZERO
                    || run.iter().any(|&j| {
                        let s = &splats[j as usize];
                        s.shape.normal.dot(front.shape.normal) <= SAME_FACING
                            || !front
                                .shape
                                .same_surface(front.dist, &s.shape, s.dist, footprint)
                    });
            }
            let mut open = 1.0f32;
            let mut covered = 0.0f32;
            let mut sum = Rgb::ZERO;
            let mut cos_sum = Rgb::ZERO;
            self.depth[k] = splats[first as usize].dist;
            let mut i = 0;
            while i < run.len() && open > 0.0 {
                let (front, front_dist) = {
                    let s = &splats[run[i] as usize];
                    (s.shape, s.dist)
                };
                let layer_start = i;
                let mut layer_cover = 0.0;
                let mut layer_sum = Rgb::ZERO;
                let mut layer_cos = Rgb::ZERO;
                while let Some(s) = run.get(i).map(|&j| &splats[j as usize]) {
                    if !front.same_surface(front_dist, &s.shape, s.dist, footprint) {
                        break;
                    }
                    layer_cover += s.coverage;
                    let l = s.radiance * s.coverage;
                    layer_sum += l;
                    layer_cos += l * s.cos;
                    i += 1;
                }
                // The nearest layer may over-cover (balancing a neighbour's under-covering,
                // see above) up to [`MAX_LAYER_COVER`]; a layer behind fills at most what is
                // still open. Coverages add across layers (their covered parts are taken as
                // disjoint, as for pieces of one curved surface that fall into several layers):
                // independent occluders would multiply, but then a closed object split into
                // layers would let light through.
                let limit = if open == 1.0 { MAX_LAYER_COVER } else { open };
                let scale = if layer_cover > limit {
                    limit / layer_cover
                } else {
                    1.0
                };
                sum += layer_sum * scale;
                cos_sum += layer_cos * scale;
                covered += layer_cover * scale;
                open = (open - layer_cover).max(0.0);
                if let Some(l) = &mut links {
                    l.entries.extend(run[layer_start..i].iter().map(|&j| {
                        let s = &splats[j as usize];
                        let w = s.coverage * scale;
                        PixelLink {
                            pixel: k as u32,
                            source: s.source,
                            w,
                            w_cos: w * s.cos,
                        }
                    }));
                }
            }
            if let Some(l) = &mut links {
                l.ends.push(l.entries.len() as u32);
            }
            self.radiance[k] = sum;
            self.cos_radiance[k] = cos_sum;
            self.alpha[k] = 1.0 - open;
            self.coverage[k] = covered;
        }
        self.order = order;
        self.links = links;
        self.pending = splats;
        self.pending.clear();
    }

    /// The indices of `splats` by pixel, then by distance (positive floats order as their
    /// bits), then by index: a counting sort over the pixels and an insertion sort of each
    /// pixel's few splats, several times faster than sorting the splats themselves.
    fn order_by_pixel_and_depth(&mut self, splats: &[Splat]) -> Vec<u32> {
        let mut order = std::mem::take(&mut self.order);
        let starts = &mut self.starts;
        group_by_pixel(
            splats.len(),
            self.pixels.len(),
            |i| splats[i].pixel,
            &mut order,
            starts,
        );
        // starts[k] is now the end of pixel k's run, which begins where pixel k − 1's ends.
        // Each run is sorted as one integer per splat, its distance's bits above its index
        // (sorting the indices by a key read through them cost twice as much).
        let keys = &mut self.keys;
        let mut begin = 0;
        for &end in starts.iter() {
            let run = &mut order[begin..end as usize];
            if run.len() > 1 {
                keys.clear();
                keys.extend(
                    run.iter().map(|&i| {
                        (u64::from(splats[i as usize].dist.to_bits()) << 32) | u64::from(i)
                    }),
                );
                sort_small(keys);
                for (slot, key) in run.iter_mut().zip(keys.iter()) {
                    *slot = *key as u32;
                }
            }
            begin = end as usize;
        }
        order
    }

    /// Normalise every pixel for which `closed(pixel)` holds (something lies behind it) to
    /// exactly full coverage: its radiance becomes the coverage-weighted mean of the senders
    /// that cover it, and its cosine the pixel's exact mean (the senders' own cosines, taken
    /// at their centres, overstated a closed room's irradiance by 0.15 %). The splats'
    /// coverage is right on average but not pixel by pixel; in a bake's bounces that error
    /// would be passed on to every further bounce.
    pub fn close_gaps(&mut self, closed: impl Fn(usize) -> bool) {
        // Per closed pixel: 1/coverage and its mean cosine, for the links.
        let mut closing = vec![None; self.pixels.len()];
        for (k, close) in closing.iter_mut().enumerate() {
            let c = self.coverage[k];
            if c > 0.0 && closed(k) {
                let l = self.radiance[k] / c;
                self.fill_pixel(k, l);
                *close = Some((1.0 / c, self.mean_cos(k)));
            }
        }
        if let Some(links) = &mut self.links {
            for e in links.entries.iter_mut() {
                if let Some((inverse, cos)) = closing[e.pixel as usize] {
                    e.w *= inverse;
                    e.w_cos = e.w * cos;
                }
            }
        }
    }

    /// The exact mean |cos θ| over pixel `k`.
    pub(crate) fn mean_cos(&self, k: usize) -> f32 {
        let px = &self.pixels[k];
        px.dir.z.abs() * px.cos_weight
    }

    /// Set pixel `k` to full coverage by radiance `l` (a pixel no splat reached, filled from
    /// what a ray through it hits).
    pub(crate) fn fill_pixel(&mut self, k: usize, l: Rgb) {
        self.radiance[k] = l;
        self.cos_radiance[k] = l * self.mean_cos(k);
        self.alpha[k] = 1.0;
        self.coverage[k] = 1.0;
    }

    /// [`Microbuffer::fill_pixel`] with the radiance at `lookup`: in a buffer that records
    /// links, pixel `k`'s links become that one lookup at full weight.
    pub(crate) fn fill_pixel_from(&mut self, k: usize, l: Rgb, lookup: Lookup) {
        self.fill_pixel(k, l);
        let cos = self.mean_cos(k);
        let source = self.source_of(lookup);
        if let Some(links) = &mut self.links {
            links.entries.retain(|e| e.pixel as usize != k);
            links.entries.push(PixelLink {
                pixel: k as u32,
                source,
                w: 1.0,
                w_cos: cos,
            });
        }
    }

    /// Composite the links of a shared buffer into this one's, as [`composite_shared`]
    /// composites their radiance: this buffer's links of pixel k scaled by `own[k]`
    /// (radiance, cosine-weighted), and for each `(k, c, w, w_cos)` of `from_shared` the
    /// shared links of pixel c added to pixel k, weighted `w` (radiance) and `w_cos` (cosine,
    /// the member pixel's) times their radiance weight. No-op unless both record links.
    ///
    /// [`composite_shared`]: super::fpbgi::composite_shared
    pub(crate) fn composite_links(
        &mut self,
        own: &[(f32, f32)],
        shared: &Microbuffer,
        from_shared: &[(u32, u32, f32, f32)],
    ) {
        let (Some(links), Some(shared)) = (&mut self.links, shared.links()) else {
            return;
        };
        for e in links.entries.iter_mut() {
            let (w, w_cos) = own[e.pixel as usize];
            e.w *= w;
            e.w_cos *= w_cos;
        }
        let offset = links.sources.len() as u32;
        links.sources.extend_from_slice(&shared.sources);
        for &(k, c, w, w_cos) in from_shared {
            links
                .entries
                .extend(shared.of_pixel(c as usize).iter().map(|e| PixelLink {
                    pixel: k,
                    source: e.source + offset,
                    w: e.w * w,
                    w_cos: e.w * w_cos,
                }));
        }
    }

    /// The local directions through an `m × m` grid of equal-area parts of pixel `k`, the
    /// centre of each part (the concentric map keeps area, so each stands for the same solid
    /// angle), each with the |cos θ| it stands for: its own, scaled so that the parts' mean is
    /// the pixel's exact mean |cos θ|. A pixel its rays find uniform then gathers exactly
    /// what a splat covering it would; unscaled, the midpoint rule's error (up to 1e-3 of a
    /// horizon pixel) biased a white furnace by 2 % at ρ = 0.99. Where a traced pixel's rays
    /// go ([`Microbuffer::set_traced`]).
    pub fn pixel_directions(&self, k: usize, m: u32) -> Vec<(Vec3, f32)> {
        let cell = self.cells[self.pixels[k].cell as usize];
        let step = cell.side / m as f32;
        let mut parts: Vec<(Vec3, f32)> = (0..m * m)
            .map(|i| {
                let u = cell.corner + (Vec2::new((i % m) as f32, (i / m) as f32) + 0.5) * step;
                let mut dir = square_to_hemisphere_equal_area(u);
                if cell.lower {
                    dir.z = -dir.z;
                }
                (dir, dir.z.abs())
            })
            .collect();
        let midpoint_mean = parts.iter().map(|p| p.1).sum::<f32>() / parts.len() as f32;
        if midpoint_mean > 0.0 {
            let scale = self.mean_cos(k) / midpoint_mean;
            for p in &mut parts {
                p.1 *= scale;
            }
        }
        parts
    }

    /// Replace pixel `k`'s light by what `count` rays through equal parts of it found
    /// ([`Microbuffer::pixel_directions`]): the sum of the radiance they brought back, the
    /// same weighted by each ray's |cos θ|, and how many hit something. Whatever the cut
    /// splatted there is dropped: the rays resolve the pixel finer than its splats'
    /// coverages can (a small occluder in front of the brightest part of what lies behind).
    pub fn set_traced(
        &mut self,
        k: usize,
        radiance: Rgb,
        cos_radiance: Rgb,
        hits: u32,
        count: u32,
    ) {
        let share = 1.0 / count as f32;
        self.radiance[k] = radiance * share;
        self.cos_radiance[k] = cos_radiance * share;
        self.alpha[k] = hits as f32 * share;
        self.coverage[k] = self.alpha[k];
    }

    /// [`Microbuffer::set_traced`] for each pixel of `traced` from the lookups its rays found:
    /// `(pixel, first, count)`, its rays' finds being `found[first..]` up to the next pixel's
    /// first (each a lookup, its radiance and the |cos θ| of its ray), of `count` rays in all
    /// (the others missed). In a buffer that records links, each such pixel's links become
    /// those lookups, a ray's share each.
    pub(crate) fn set_traced_from(
        &mut self,
        traced: &[(usize, usize, u32)],
        found: &[(Lookup, Rgb, f32)],
    ) {
        // Each traced pixel's rays' finds: found[first..end].
        let ends: Vec<usize> = traced
            .iter()
            .skip(1)
            .map(|t| t.1)
            .chain([found.len()])
            .collect();
        for (&(k, first, count), &end) in traced.iter().zip(&ends) {
            let (mut sum, mut cos_sum) = (Rgb::ZERO, Rgb::ZERO);
            for &(_, l, cos) in &found[first..end] {
                sum += l;
                cos_sum += l * cos;
            }
            self.set_traced(k, sum, cos_sum, (end - first) as u32, count);
        }
        if self.links.is_none() {
            return;
        }
        let sources: Vec<u32> = found.iter().map(|&(l, _, _)| self.source_of(l)).collect();
        let mut replaced = vec![false; self.pixels.len()];
        for &(k, _, _) in traced {
            replaced[k] = true;
        }
        let Some(links) = &mut self.links else { return };
        links.entries.retain(|e| !replaced[e.pixel as usize]);
        for (&(k, first, count), &end) in traced.iter().zip(&ends) {
            let share = 1.0 / count as f32;
            links.entries.extend((first..end).map(|i| PixelLink {
                pixel: k as u32,
                source: sources[i],
                w: share,
                w_cos: share * found[i].2,
            }));
        }
    }

    /// Set every pixel to a uniform, fully covering radiance `l` (a sky).
    pub fn fill(&mut self, l: Rgb) {
        for k in 0..self.pixels.len() {
            self.fill_pixel(k, l);
        }
    }

    /// Outgoing radiance towards the local direction `wo` through `bsdf`: the BSDF at each
    /// pixel's centre (over a lobe pixel, its mean: [`LOBE_QUADRATURE_SHARE`]) times the
    /// pixel's cosine-weighted radiance (Mitsuba's eval includes the centre's cosine, divided
    /// out here).
    pub fn convolve(&self, bsdf: &Bsdf, wo: Vec3) -> Rgb {
        self.convolved_pixels(bsdf, wo)
            .fold(Rgb::ZERO, |a, (_, b)| a + b)
    }

    /// Each pixel's part of [`Microbuffer::convolve`] (pixels that hold no light left out).
    pub fn convolved_pixels<'b>(
        &'b self,
        bsdf: &'b Bsdf,
        wo: Vec3,
    ) -> impl Iterator<Item = (usize, Rgb)> + 'b {
        self.bsdf_factors(bsdf, wo)
            .map(move |(k, f)| (k, self.convolved_term(k, f)))
    }

    /// The BSDF's factor of every pixel that holds light, as [`Microbuffer::convolve`] weighs
    /// it: a caller that changes some pixels' light ([`Microbuffer::set_traced`]) convolves
    /// again with [`Microbuffer::convolve_with`] without evaluating the BSDF again.
    pub fn bsdf_factors<'b>(
        &'b self,
        bsdf: &'b Bsdf,
        wo: Vec3,
    ) -> impl Iterator<Item = (usize, Rgb)> + 'b {
        self.cos_radiance
            .iter()
            .zip(&self.pixels)
            .enumerate()
            .filter(|(_, (l, _))| **l != Rgb::ZERO)
            .map(move |(k, (_, px))| {
                let f = if self.lobe.get(k) == Some(&true) {
                    self.lobe_mean(k, bsdf, wo)
                } else {
                    bsdf.eval(wo, px.dir, TransportMode::Radiance) / px.dir.z.abs()
                };
                (k, f)
            })
    }

    /// [`Microbuffer::convolve`] from the `factors` [`Microbuffer::bsdf_factors`] gave, over
    /// the pixels' light as it is now (which may only have changed where it was not zero):
    /// the same terms, summed in the same order, so the same value to the bit.
    pub fn convolve_with(&self, factors: &[(usize, Rgb)]) -> Rgb {
        factors
            .iter()
            .filter(|&&(k, _)| self.cos_radiance[k] != Rgb::ZERO)
            .fold(Rgb::ZERO, |a, &(k, f)| a + self.convolved_term(k, f))
    }

    /// Pixel `k`'s term of the convolution for its BSDF factor `f`.
    pub(crate) fn convolved_term(&self, k: usize, f: Rgb) -> Rgb {
        self.cos_radiance[k] * f * self.pixels[k].solid_angle
    }

    /// The mean of `bsdf` seen from `wo` (without the cosine Mitsuba's eval includes) over
    /// pixel `k`, weighted by |cos θ| and over the pixel's mean |cos θ|: over
    /// [`LOBE_QUADRATURE`]² equal-area parts ([`Microbuffer::pixel_directions`]). At one part
    /// it is the BSDF at the centre.
    fn lobe_mean(&self, k: usize, bsdf: &Bsdf, wo: Vec3) -> Rgb {
        let parts = self.pixel_directions(k, LOBE_QUADRATURE);
        let sum = parts.iter().fold(Rgb::ZERO, |a, &(d, cos)| {
            a + bsdf.eval(wo, d, TransportMode::Radiance) * (cos / d.z.abs())
        });
        sum / (parts.len() as f32 * self.mean_cos(k))
    }
}

/// The indices `0..n` of items on the pixels of a buffer of `pixels`, grouped by their
/// `pixel` (a counting sort, keeping index order within a pixel), into `order`; `ends[k]` is
/// then the end of pixel k's run, which begins where pixel k − 1's ends.
pub(crate) fn group_by_pixel(
    n: usize,
    pixels: usize,
    pixel: impl Fn(usize) -> u32,
    order: &mut Vec<u32>,
    ends: &mut Vec<u32>,
) {
    ends.clear();
    ends.resize(pixels + 1, 0);
    for i in 0..n {
        ends[pixel(i) as usize + 1] += 1;
    }
    for k in 1..ends.len() {
        ends[k] += ends[k - 1];
    }
    order.clear();
    order.resize(n, 0);
    for i in 0..n {
        let at = &mut ends[pixel(i) as usize];
        order[*at as usize] = i as u32;
        *at += 1;
    }
}

/// The directions at which [`Microbuffer::refine_for_bsdf`] weighs a pixel, as lanes of x, y
/// and z for [`Bsdf::eval_lanes`] (the same values as one [`Bsdf::eval`] at a time), and their
/// values; kept from pixel to pixel.
#[derive(Default)]
struct BsdfLanes {
    xyz: [Vec<f32>; 3],
    values: Vec<Rgb>,
}

impl BsdfLanes {
    /// Pixel `k`'s weight: the largest luminance of `bsdf` seen from `wo` over a 3 × 3 grid
    /// of directions in the pixel and the lobe `centres` that fall in it, times its solid
    /// angle.
    fn weight(
        &mut self,
        mb: &Microbuffer,
        k: usize,
        bsdf: &Bsdf,
        wo: Vec3,
        centres: &[Vec3],
    ) -> f32 {
        let cell = &mb.cells[mb.pixels[k].cell as usize];
        self.xyz.iter_mut().for_each(Vec::clear);
        let mut push = |d: Vec3| {
            for (lane, v) in self.xyz.iter_mut().zip(d.to_array()) {
                lane.push(v);
            }
        };
        for j in 0..3 {
            for i in 0..3 {
                let p = cell.corner + Vec2::new(i as f32 + 0.5, j as f32 + 0.5) * (cell.side / 3.0);
                let mut d = square_to_hemisphere_equal_area(p);
                if cell.lower {
                    d.z = -d.z;
                }
                push(d);
            }
        }
        for &c in centres {
            if mb.local_pixel_of(c) == Some(k) {
                push(c);
            }
        }
        let [x, y, z] = &self.xyz;
        bsdf.eval_lanes(wo, [x, y, z], TransportMode::Radiance, &mut self.values);
        let best = self
            .values
            .iter()
            .fold(0.0f32, |best, &f| best.max(luminance(f)));
        best * mb.pixels[k].solid_angle
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::{Diffuse, Distribution, Microfacet, RoughConductor};

    /// The base pixels' BSDF weights for `bsdf` seen from `wo`, as the refinement weighs them.
    fn base_weights(bsdf: &Bsdf, wo: Vec3) -> Vec<f32> {
        let mb = Microbuffer::new(16, false, Frame::from_normal(Vec3::Z));
        let centres: Vec<Vec3> = bsdf.lobe_centres(wo).into_iter().flatten().collect();
        let mut lanes = BsdfLanes::default();
        (0..mb.pixels.len())
            .map(|k| lanes.weight(&mb, k, bsdf, wo, &centres))
            .collect()
    }

    /// A narrow lobe leaves most of the hemisphere faint and its own direction not; the faint
    /// pixels hold at most [`FAINT_LIGHT`] of the reflected light; a diffuse receiver has
    /// none.
    #[test]
    fn faint_pixels_are_the_directions_a_lobe_hardly_weighs() {
        let wo = Vec3::new(0.5, 0.0, 0.866);
        let glossy = Bsdf::Conductor(RoughConductor {
            distr: Microfacet::new(Distribution::Ggx, 0.05, 0.05),
            eta: Rgb::splat(0.2),
            k: Rgb::splat(3.0),
            specular_reflectance: Rgb::ONE,
        });
        let diffuse = Bsdf::Diffuse(Diffuse {
            reflectance: Rgb::ONE,
        });
        for (bsdf, narrow) in [(glossy, true), (diffuse, false)] {
            let mut mb = Microbuffer::new(16, false, Frame::from_normal(Vec3::Z));
            mb.refine_for_bsdf(&bsdf, wo, 1.0 / 64.0, 5);
            let weights = base_weights(&bsdf, wo);
            let total: f32 = weights.iter().sum();
            let faint: Vec<usize> = (0..256)
                .filter(|&k| mb.faint.get(k) == Some(&true))
                .collect();
            let faint_weight: f32 = faint.iter().map(|&k| weights[k]).sum();
            assert!(
                faint_weight <= FAINT_LIGHT * total,
                "{faint_weight} of {total}"
            );
            let base = Microbuffer::new(16, false, Frame::from_normal(Vec3::Z));
            if narrow {
                assert!(faint.len() > 128, "{} faint pixels", faint.len());
                let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
                let at = mb.locate(mirror).expect("upper hemisphere");
                assert!(!mb.is_faint_at(&at));
            } else {
                // Its faintest 1 % lies in the horizon's ring, each pixel beside a brighter one.
                assert!(faint.is_empty(), "{} faint pixels", faint.len());
            }
            // Every faint pixel is also reported where a direction in it is located.
            for k in 0..256 {
                let at = mb.locate(base.pixels[k].dir).expect("upper hemisphere");
                assert_eq!(mb.is_faint_at(&at), faint.contains(&k), "pixel {k}");
            }
        }
    }
}

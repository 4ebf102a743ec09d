//! Fewer gathers for the same image (issue 20): receivers gather on a sparse grid of pixels,
//! and the receivers between take their light from the grid where it is smooth.
//!
//! Indirect light on a surface varies slowly, except across edges, contacts and the shadows
//! of indirect light; the albedo that multiplies it (a texture) may vary fast. So a tile's
//! receivers are split:
//!
//! - **Layers.** A pixel's receivers are its primary hit and the ends of its specular chains
//!   (through a mirror, into and out of a glass), each with the signature of its chain
//!   ([`Receiver::chain`]: the meshes met and the branches taken). The receivers of one chain
//!   over neighbouring pixels see one surface through the same mirrors and glass, as the
//!   primary hits see it directly: each chain is a layer of the image, interpolated as the
//!   primary layer is.
//! - **Quarters.** An edge pixel (of what is seen directly, or through a mirror or glass)
//!   gathers once per quarter of it; every other pixel once (`render/pixels.rs`). Seen
//!   through a mirror or a clear glass, the receivers of one quarter over the pixels are a
//!   layer too, which takes its corners from the same quarter of its anchors' pixels, else
//!   from whole pixels, else from the first quarter there on its surface.
//! - **Quarters of a geometric edge** (of primary hits) are not interpolated across a cell:
//!   from whole pixels across the edge that cost 4–9 % relMSE at 128² (cbox-rough,
//!   cbox-glossy). In frames of 512 pixels and more (`borrows_light_beside`) they take,
//!   once every whole pixel has its value, the light of the whole pixels within
//!   [`NEIGHBOURS`] of their own on their surface (`SparsePlan::light_beside`): a
//!   quarter lies within a pixel or two of them, where its cell's corners lie up to 8 away.
//!   Three guards: the donors agree to [`CONTRAST`]; at least [`DONORS`] of them; and they
//!   lie within [`REACH`] of the quarter's clearance (`clearance`), the distance to the nearest other
//!   surface around that the quarter lies behind (the ceiling in the gap above a hanging
//!   light's rim, dark beside the lit ceiling: without the guard, cbox-diffuse's relMSE at
//!   256² doubled). A crease or a contact (a wall facing the quarter) does not count: the light
//!   there changes smoothly enough at these sizes. What fails gathers, as before. A primary
//!   hit whose finest cell fails (a corner on another surface or across a contrast) does the
//!   same before it gathers: it feeds no other cell, and the pixels beside it that have their
//!   value by then are its donors.
//! - **Faint receivers** ([`FAINT`]: a weight under 5 % of their pixel, a weak reflection
//!   or refraction off glass, a deep branch of a chain) whose finest cell fails take, before
//!   they gather, the inverse-square mean of their layer's receivers (whole pixels and
//!   quarters) within [`NEIGHBOURS`] of their pixel on their surface, when at least
//!   [`DONORS`] have their value and the spread of what those would put into the pixel is
//!   within [`CONTRAST`] of a lower bound on the pixel (its emission and direct light plus the
//!   darkest donor's share): Lightcuts' rule, an error bound relative to the pixel's light
//!   rather than to the receiver's own (`SparsePlan::light_of_layer`).
//! - **Quarters on one surface.** Where three or four quarters of a geometric edge's pixel lie
//!   on one surface (on each other's mesh and plane, with BSDFs that interpolate: the same
//!   rules as corners, below), the two farthest apart gather, and the others take the nearer
//!   one's value if the two agree to [`CONTRAST`] in luminance; else they gather too. Without
//!   the check (the first quarter's value for the others) cbox-diffuse at 128² was 3× further
//!   from every receiver gathering (relMSE 1.2e-4 against 3.9e-5): an edge pixel whose
//!   quarters all lie on the ceiling, half in the dark gap above the hanging emitter's rim and
//!   half in the light beside it (0.006 against 0.1).
//! - **Eligible** receivers: alone in their pixel's layer and quarter, not a quarter of a
//!   geometric edge.
//! - **What is interpolated.** A diffuse receiver's gather keeps its irradiance E (the
//!   cosine-weighted incident light over π: the outgoing radiance of a white diffuse
//!   surface), which each receiver multiplies by its own albedo, so a texture stays sharp. A
//!   glossy or rough-dielectric receiver's keeps its outgoing radiance towards its viewer,
//!   and takes it only from corners with the very same BSDF (one material, the same texel
//!   values): its lobe, unlike a diffuse albedo, does not factor out. Across a cell of a few
//!   pixels its viewer turns by a fraction of a degree, far less than the narrowest lobe that
//!   gathers (α ≥ 0.03, about 2°), so the reflected light there is as smooth as the
//!   irradiance of a diffuse surface, and the same contrast rule guards its edges.
//! - **Anchors**: the eligible receivers on the grid of every [`coarsest_cell`]-th row and
//!   column of the tile (and its last row and column): every 4th in frames under 512 pixels
//!   on their shorter side, every 8th from 512. They gather. The light's smoothness belongs
//!   to the scene, so the anchors' spacing follows the frame, not the pixel: 8 pixels of a
//!   512² frame span what 4 of a 256² frame span.
//! - The others take their value from the receivers at the corners of their cell,
//!   bilinearly, when all four exist, lie on the receiver's mesh and plane (normals within
//!   18°, offsets from its tangent plane within a tenth of the distance), carry a BSDF that
//!   interpolates with the receiver's (above) and agree with each other to [`CONTRAST`] in
//!   luminance. A corner is the receiver of the same quarter, else that of a whole pixel,
//!   else the first quarter on the receiver's surface.
//! - **Finer cells.** Where a cell fails (an edge or a contact crosses it, a corner is
//!   missing), the receivers on the grid of half its size inside it gather, and the rest
//!   interpolate from the finer cells around them by the same rules, down to cells of 2
//!   pixels; what fails there gathers. An edge through a cell then costs the gathers along
//!   it, not the whole cell.
//!
//! Everything is decided within the tile, in receiver order: the image is the same for any
//! thread count.

use super::primary::Receiver;
use crate::bsdf::Bsdf;
use crate::fast_hash::FastHashMap;
use crate::spectrum::{luminance, max_component, Rgb};
use glam::Vec3;

/// Pixels between the anchors along a row or column in frames under 512 pixels on their
/// shorter side ([`coarsest_cell`]).
pub const ANCHOR_SPACING: u32 = 4;

/// The frame size (shorter side) for which [`ANCHOR_SPACING`] was chosen: the spacing doubles
/// in frames at least twice as large, up to [`WIDEST_CELL`].
pub const ANCHOR_FRAME: u32 = 256;

/// The widest anchor spacing. At 1024², 16 saved 5–9 % more time than 8 but made the MSE
/// 10–19 % worse on cbox-rough and cbox-glossy (docs/render.md).
pub const WIDEST_CELL: u32 = 8;

/// The anchors' spacing in a frame of `width` × `height` pixels: [`ANCHOR_SPACING`], doubled
/// for each doubling of the shorter side past [`ANCHOR_FRAME`], up to [`WIDEST_CELL`]. It
/// depends on the whole frame only, so a crop interpolates as the frame does.
pub fn coarsest_cell(width: u32, height: u32) -> u32 {
    let mut cell = ANCHOR_SPACING;
    let mut frame = ANCHOR_FRAME;
    while cell < WIDEST_CELL && width.min(height) >= 2 * frame {
        cell *= 2;
        frame *= 2;
    }
    cell
}

/// How far (in pixels, along rows and columns) the centre hits lie whose surfaces bound a
/// primary hit's clearance (`clearance`).
pub const CLEARANCE_PIXELS: u32 = 4;

/// How far (in pixels, along rows and columns) a receiver that borrows its light (an edge's
/// quarter, a finest cell's failure) looks for whole pixels on its surface to take it from
/// (`SparsePlan::light_beside`).
pub const NEIGHBOURS: u32 = 2;

/// The farthest a pixel that lends a receiver its light may lie, as a fraction of the
/// receiver's clearance: irradiance caching's records are trusted to about a tenth to a half
/// of the distance to the geometry around.
pub const REACH: f32 = 0.25;

/// A surface point lies in front of a receiver when it lies above the receiver's tangent
/// plane by more than this fraction of its distance.
pub const FRONT: f32 = 0.05;

/// The fewest pixels a receiver borrows its light from: one alone is an extrapolation that
/// no other checks.
pub const DONORS: usize = 2;

/// A receiver whose weight (its path's throughput times its share of the pixel, largest
/// channel) is below this fraction of its pixel is a faint one: a weak reflection or
/// refraction off glass, a deep branch of a specular chain. Where its finest cell fails it
/// borrows from its layer's receivers around it (`SparsePlan::light_of_layer`) under a bound
/// on the error it can put into its pixel, instead of gathering: at 512² such receivers were
/// nearly half of cbox-glossy's, cbox-mirror's and caustic's gathers.
pub const FAINT: f32 = 0.05;

/// The finest cells: 2 pixels, whose receivers are the next pixel over from their corners.
const FINEST_CELL: u32 = 2;

/// The most the brightest corner of a cell may exceed the darkest, relative to it, for the
/// receivers inside to interpolate (see docs/render.md for the measure).
pub const CONTRAST: f32 = 0.3;

/// Normals within this cosine (18°) and tangent-plane offsets within this fraction of the
/// distance make a corner the same surface as the receiver.
const SAME_NORMAL: f32 = 0.95;
const SAME_PLANE: f32 = 0.1;

/// Which of a tile's receivers gather, and how the others are interpolated.
pub(crate) struct SparsePlan {
    /// Per receiver: it gathers in the first pass (anchors, and the ineligible that share no
    /// gather).
    first: Vec<bool>,
    /// Per receiver on a geometric edge: the two quarters of its pixel on its surface whose
    /// gathers it may share (see the module docs).
    lender: Vec<Option<(u32, u32)>>,
    /// Per receiver: its value is its irradiance (see [`SparsePlan::by_irradiance`]).
    irradiance: Vec<bool>,
    /// Every eligible receiver by its place in the tile's layers.
    at: FastHashMap<Key, u32>,
    /// Whether edges' quarters and the finest cells' primary hits that fail take the light of
    /// the pixels beside them ([`borrows_light_beside`]).
    borrow: bool,
    /// The cells' sizes, coarsest first, halving down to [`FINEST_CELL`].
    cell_sizes: Vec<u32>,
    /// The tile's origin in the image, its size, and the image's width.
    origin: (u32, u32),
    size: (u32, u32),
    width: u32,
}

/// A receiver's place in a tile's layers: its pixel's index in the tile (row-major), its
/// chain and its quarter ([`Receiver::chain`], [`Receiver::quarter`]).
type Key = (u32, u64, Option<u8>);

/// Whether a corner with BSDF `corner` can lend its value to a receiver with BSDF `bsdf`: any
/// two diffuse ones (their values are irradiance), otherwise only the very same BSDF (their
/// values are outgoing radiance, which carries the lobe).
fn interpolates_with(corner: &Bsdf, bsdf: &Bsdf) -> bool {
    match bsdf {
        Bsdf::Diffuse(_) => matches!(corner, Bsdf::Diffuse(_)),
        _ => corner == bsdf,
    }
}

/// Whether receiver `c` can lend its value to receiver `r`: it lies on `r`'s mesh and plane
/// (normals within 18°, offset from `r`'s tangent plane within a tenth of the distance) and
/// its BSDF [`interpolates_with`] `r`'s.
fn lends_to(c: &Receiver, r: &Receiver) -> bool {
    on_surface_of(c.mesh, c.p, c.frame.n, r) && interpolates_with(&c.bsdf, &r.bsdf)
}

/// Whether the point `p` with normal `n` on mesh `mesh` lies on receiver `r`'s surface: its
/// mesh, normals within 18°, offset from `r`'s tangent plane within a tenth of the distance.
fn on_surface_of(mesh: u32, p: Vec3, n: Vec3, r: &Receiver) -> bool {
    let offset = p - r.p;
    mesh == r.mesh
        && n.dot(r.frame.n) >= SAME_NORMAL
        && r.frame.n.dot(offset).abs() <= SAME_PLANE * offset.length()
}

/// How far from receiver `r` the nearest of the surface points `around` (the centre hits
/// of the pixels around its own: mesh, point, normal) lies that is another surface than
/// `r`'s (as [`lends_to`] tells surfaces apart) and in front of its tangent plane (above it
/// by [`FRONT`] of the distance): infinite where none is. Irradiance changes over distances
/// of the order of the distance to the geometry around (the split-sphere bound of irradiance
/// caching), so a receiver borrows its light only from pixels much nearer than that.
pub(crate) fn clearance(r: &Receiver, around: impl Iterator<Item = (u32, Vec3, Vec3)>) -> f32 {
    around
        .filter(|&(mesh, p, n)| {
            let offset = p - r.p;
            !on_surface_of(mesh, p, n, r)
                && r.frame.n.dot(offset) > FRONT * offset.length()
                && n.dot(offset) > 0.0
        })
        .map(|(_, p, _)| (p - r.p).length())
        .fold(f32::INFINITY, f32::min)
}

/// Whether values whose luminances range from `lo` to `hi` agree to [`CONTRAST`].
fn agree(lo: f32, hi: f32) -> bool {
    hi <= (1.0 + CONTRAST) * lo
}

/// Whether a geometric edge's quarters, and the primary hits whose finest cell fails, borrow
/// the light of the pixels beside them ([`SparsePlan::light_beside`]) before they gather, in
/// a frame whose anchors lie every `coarsest` pixels
/// ([`coarsest_cell`]): only in frames of [`WIDEST_CELL`] (512 pixels and more on the
/// shorter side). At 256² two pixels span what four span at 512², and it cost cbox-rough
/// and cbox-glossy 2–3 % of relMSE against Mitsuba where at 512² it cost none
/// (docs/render.md).
pub(crate) fn borrows_light_beside(coarsest: u32) -> bool {
    coarsest >= WIDEST_CELL
}

/// Whether receiver `r` is a quarter of a geometric edge's pixel (a primary hit's).
fn on_geometric_edge(r: &Receiver) -> bool {
    r.chain == 0 && r.quarter.is_some()
}

/// Image pixel `pixel`'s coordinates within the tile at `origin`, in an image `width` wide.
fn local(pixel: u32, origin: (u32, u32), width: u32) -> (u32, u32) {
    (pixel % width - origin.0, pixel / width - origin.1)
}

/// Whether tile-local coordinate `c` of a tile `n` pixels wide is on the grid of every
/// `cell`-th line (and the last).
fn on_grid(c: u32, n: u32, cell: u32) -> bool {
    c.is_multiple_of(cell) || c + 1 == n
}

/// The grid lines of that grid around `c`, and where `c` lies between them (0 to 1).
fn cell_of(c: u32, n: u32, cell: u32) -> (u32, u32, f32) {
    let low = c - c % cell;
    let high = (low + cell).min(n - 1);
    let f = if high > low {
        (c - low) as f32 / (high - low) as f32
    } else {
        0.0
    };
    (low, high, f)
}

/// Whether receiver `r` is faint: its weight below [`FAINT`] of its pixel.
fn is_faint(r: &Receiver) -> bool {
    max_component(r.weight) < FAINT
}

/// The receivers a receiver borrows its light from, summed up.
struct Donors {
    /// Their values weighted by the inverse square of their distance to it.
    mean: Rgb,
    /// The least and the most luminance among their values, each times a scale.
    lo: f32,
    hi: f32,
}

impl Donors {
    /// The donors among `candidates` for receiver `r`: those within `farthest` of it that lend
    /// to it ([`lends_to`]) and have their value (`value(j)`); their luminances are taken of
    /// each value times `scale`. `None` with fewer than [`DONORS`], or where the mean passes f32's range (donors
    /// at the very point weigh up to 1/f32::MIN_POSITIVE): the receiver gathers instead of
    /// taking an infinite or a zero value.
    fn of(
        receivers: &[Receiver],
        r: &Receiver,
        candidates: impl Iterator<Item = usize>,
        farthest: f32,
        scale: Rgb,
        value: impl Fn(usize) -> Option<Rgb>,
    ) -> Option<Donors> {
        let (mut sum, mut weights, mut count) = (Rgb::ZERO, 0.0f32, 0);
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        for j in candidates {
            let c = &receivers[j];
            let distance = (c.p - r.p).length();
            if distance > farthest || !lends_to(c, r) {
                continue;
            }
            let Some(e) = value(j) else {
                continue;
            };
            let w = 1.0 / (distance * distance).max(f32::MIN_POSITIVE);
            let l = luminance(e * scale);
            (lo, hi) = (lo.min(l), hi.max(l));
            sum += e * w;
            weights += w;
            count += 1;
        }
        let mean = sum * (1.0 / weights);
        let finite = weights.is_finite() && mean.is_finite();
        (count >= DONORS && finite).then_some(Donors { mean, lo, hi })
    }
}

impl SparsePlan {
    /// The plan for the receivers of the tile at `origin` of `size` pixels, in an image
    /// `width` wide, with anchors every `coarsest` pixels (a power of two, at least
    /// [`FINEST_CELL`]: [`coarsest_cell`]). With `sparse` false every receiver gathers.
    pub fn new(
        receivers: &[Receiver],
        origin: (u32, u32),
        size: (u32, u32),
        width: u32,
        coarsest: u32,
        sparse: bool,
    ) -> SparsePlan {
        let cell_sizes: Vec<u32> =
            std::iter::successors(Some(coarsest.max(FINEST_CELL)), |&c| Some(c / 2))
                .take_while(|&c| c >= FINEST_CELL)
                .collect();
        // Each receiver's tile-local pixel, and its place in the layers.
        let cells: Vec<(u32, u32, Key)> = receivers
            .iter()
            .map(|r| {
                let (x, y) = local(r.pixel, origin, width);
                (x, y, (y * size.0 + x, r.chain, r.quarter))
            })
            .collect();
        let mut count: FastHashMap<Key, u32> = FastHashMap::default();
        if sparse {
            for &(_, _, key) in &cells {
                *count.entry(key).or_default() += 1;
            }
        }
        let eligible: Vec<bool> = receivers
            .iter()
            .zip(&cells)
            .map(|(r, c)| sparse && count.get(&c.2) == Some(&1) && !on_geometric_edge(r))
            .collect();
        // A geometric edge's quarters on one surface: the two farthest apart gather, and the
        // others take the nearer one's value if the two agree (see the module docs).
        let mut lender: Vec<Option<(u32, u32)>> = vec![None; receivers.len()];
        let mut surfaces: FastHashMap<u32, Vec<Vec<usize>>> = FastHashMap::default();
        for (k, r) in receivers.iter().enumerate() {
            if !(sparse && on_geometric_edge(r)) {
                continue;
            }
            let pixel = surfaces.entry(r.pixel).or_default();
            match pixel.iter_mut().find(|g| lends_to(&receivers[g[0]], r)) {
                Some(g) => g.push(k),
                None => pixel.push(vec![k]),
            }
        }
        for group in surfaces.values().flatten().filter(|g| g.len() > 2) {
            let distance =
                |(a, b): (usize, usize)| (receivers[a].p - receivers[b].p).length_squared();
            let mut pair = (group[0], group[1]);
            for (i, &a) in group.iter().enumerate() {
                for &b in &group[i + 1..] {
                    if distance((a, b)) > distance(pair) {
                        pair = (a, b);
                    }
                }
            }
            for &k in group.iter().filter(|&&k| k != pair.0 && k != pair.1) {
                lender[k] = Some((pair.0 as u32, pair.1 as u32));
            }
        }
        let borrow = sparse && borrows_light_beside(coarsest);
        let mut at = FastHashMap::default();
        let first = cells
            .iter()
            .zip(&eligible)
            .zip(&lender)
            .enumerate()
            .map(|(k, ((&(x, y, key), &e), l))| {
                if e {
                    at.insert(key, k as u32);
                }
                let edge = borrow && on_geometric_edge(&receivers[k]);
                l.is_none()
                    && !edge
                    && (!e
                        || (on_grid(x, size.0, cell_sizes[0]) && on_grid(y, size.1, cell_sizes[0])))
            })
            .collect();
        let irradiance = receivers
            .iter()
            .zip(&eligible)
            .map(|(r, &e)| {
                (e || (sparse && on_geometric_edge(r))) && matches!(r.bsdf, Bsdf::Diffuse(_))
            })
            .collect();
        SparsePlan {
            first,
            lender,
            irradiance,
            at,
            borrow,
            cell_sizes,
            origin,
            size,
            width,
        }
    }

    /// Every receiver's value in `value`: the first pass's and each finer grid's receivers
    /// gathered by `gather` (given which receivers, and the values so far, it fills theirs),
    /// the others interpolated between (see the module docs). `clearance(k)` is receiver k's
    /// [`clearance`], asked only of the primary hits that borrow their light; `floor(k)` the
    /// luminance its pixel has without the gather (emission and direct light), asked only of
    /// the faint receivers that borrow theirs. Returns how many interpolated, and how many of
    /// those by their outgoing radiance (not diffuse).
    pub fn run(
        &self,
        receivers: &[Receiver],
        value: &mut [Rgb],
        clearance: impl Fn(usize) -> f32,
        floor: impl Fn(usize) -> f32,
        mut gather: impl FnMut(&[usize], &mut [Rgb]),
    ) -> (usize, usize) {
        // Which receivers have their value yet.
        let mut known = vec![false; receivers.len()];
        let mut gather = |which: &[usize], value: &mut [Rgb], known: &mut [bool]| {
            gather(which, value);
            which.iter().for_each(|&k| known[k] = true);
        };
        let first: Vec<usize> = (0..receivers.len()).filter(|&k| self.first[k]).collect();
        gather(&first, value, &mut known);
        let (mut interpolated, mut by_radiance) = (0, 0);
        let mut count = |k: usize, known: &mut [bool]| {
            interpolated += 1;
            by_radiance += usize::from(!self.irradiance[k]);
            known[k] = true;
        };
        let (mut pending, mut edges, mut lent) = (Vec::new(), Vec::new(), Vec::new());
        for k in (0..receivers.len()).filter(|&k| !self.first[k]) {
            match (self.lender[k], on_geometric_edge(&receivers[k])) {
                (Some(_), _) => lent.push(k),
                (None, true) => edges.push(k),
                (None, false) => pending.push(k),
            }
        }
        for (level, &cell) in self.cell_sizes.iter().enumerate() {
            let finer = self.cell_sizes.get(level + 1).copied();
            let (mut now, mut later) = (Vec::new(), Vec::new());
            for k in pending {
                match self.interpolate(receivers, k, cell, |j| value[j]) {
                    Some(e) => {
                        value[k] = e;
                        count(k, &mut known);
                    }
                    None => match finer {
                        Some(f) if !self.on_grid_of(receivers, k, f) => later.push(k),
                        _ => now.push(k),
                    },
                }
            }
            // The finest cells' failures feed no other cell: a faint receiver among them may
            // take the light of its layer around it, and a primary hit the light of the
            // pixels beside it, as an edge's quarter does.
            if finer.is_none() {
                now.retain(|&k| {
                    let known_value = |j: usize| known[j].then(|| value[j]);
                    let borrowed = if is_faint(&receivers[k]) {
                        self.light_of_layer(receivers, k, floor(k), known_value)
                    } else if self.borrow && receivers[k].chain == 0 {
                        self.light_beside(receivers, k, &clearance, known_value)
                    } else {
                        None
                    };
                    if let Some(e) = borrowed {
                        value[k] = e;
                        count(k, &mut known);
                    }
                    borrowed.is_none()
                });
            }
            gather(&now, value, &mut known);
            pending = later;
        }
        // A geometric edge's quarters, once every whole pixel has its value: from the whole
        // pixels beside them on their surface, else they gather.
        let mut now = Vec::new();
        for k in edges {
            match self.light_beside(receivers, k, &clearance, |j| known[j].then(|| value[j])) {
                Some(e) => {
                    value[k] = e;
                    count(k, &mut known);
                }
                None => now.push(k),
            }
        }
        gather(&now, value, &mut known);
        // Then the quarters that share their pixel's two farthest apart on one surface.
        let mut disagree = Vec::new();
        for k in lent {
            let Some((a, b)) = self.lender[k] else {
                continue;
            };
            let (a, b) = (a as usize, b as usize);
            let (la, lb) = (luminance(value[a]), luminance(value[b]));
            if agree(la.min(lb), la.max(lb)) {
                let p = receivers[k].p;
                let nearer = if (receivers[a].p - p).length_squared()
                    <= (receivers[b].p - p).length_squared()
                {
                    a
                } else {
                    b
                };
                value[k] = value[nearer];
                count(k, &mut known);
            } else {
                disagree.push(k);
            }
        }
        gather(&disagree, value, &mut known);
        (interpolated, by_radiance)
    }

    /// The value of receiver `k` (a primary hit: an edge's quarter, or a whole pixel whose
    /// finest cell failed) from the whole pixels within [`NEIGHBOURS`] pixels of its own (in
    /// the tile) that can lend to it, as a cell's corners must ([`lends_to`]), lie within
    /// [`REACH`] of its clearance (`clearance(k)`, see [`clearance`]) and have their value (`value(j)` for
    /// receiver j, `None` for one that has none yet), weighted by the inverse square of their
    /// distance to it; `None` where fewer than [`DONORS`] do or their luminances disagree by
    /// more than [`CONTRAST`].
    fn light_beside(
        &self,
        receivers: &[Receiver],
        k: usize,
        clearance: impl Fn(usize) -> f32,
        value: impl Fn(usize) -> Option<Rgb>,
    ) -> Option<Rgb> {
        let r = &receivers[k];
        let donors = self.layer_around(r, &[None]).filter(|&j| j != k);
        let farthest = REACH * clearance(k);
        let d = Donors::of(receivers, r, donors, farthest, Rgb::ONE, value)?;
        agree(d.lo, d.hi).then_some(d.mean)
    }

    /// The value of faint receiver `k` ([`is_faint`]) whose finest cell failed, from the
    /// receivers of its layer, whole pixels or quarters, within [`NEIGHBOURS`] pixels of its
    /// own that can lend to it ([`lends_to`]) and have their value (`value(j)`), weighted by
    /// the inverse square of their distance; `None` where fewer than [`DONORS`] do or where
    /// the spread of what they would put into its pixel (their values times its weight and
    /// albedo) exceeds [`CONTRAST`] of the least its pixel then holds: `floor` (the
    /// luminance of its emission and direct light) plus the darkest donor's share. A cell's
    /// corners must agree relative to their own light; a faint receiver's error shows only
    /// relative to its pixel's, so its donors may disagree more where that is bright. This
    /// is Lightcuts' rule (an error bound below a fraction of a lower bound on the pixel).
    fn light_of_layer(
        &self,
        receivers: &[Receiver],
        k: usize,
        floor: f32,
        value: impl Fn(usize) -> Option<Rgb>,
    ) -> Option<Rgb> {
        let r = &receivers[k];
        let quarters = [None, Some(0), Some(1), Some(2), Some(3)];
        let donors = self.layer_around(r, &quarters).filter(|&j| j != k);
        let scale = r.weight * self.albedo_of(k, r);
        let d = Donors::of(receivers, r, donors, f32::INFINITY, scale, value)?;
        (d.hi - d.lo <= CONTRAST * (floor + d.lo)).then_some(d.mean)
    }

    /// The receivers of receiver `r`'s layer (its chain) in the pixels within [`NEIGHBOURS`]
    /// pixels of its own, its own included, in the tile, of the given quarters (`None`: a
    /// whole pixel's).
    fn layer_around<'a>(
        &'a self,
        r: &'a Receiver,
        quarters: &'a [Option<u8>],
    ) -> impl Iterator<Item = usize> + 'a {
        let (x, y) = local(r.pixel, self.origin, self.width);
        let reach = i64::from(NEIGHBOURS);
        let (w, h) = (i64::from(self.size.0), i64::from(self.size.1));
        (-reach..=reach)
            .flat_map(move |dy| (-reach..=reach).map(move |dx| (dx, dy)))
            .map(move |(dx, dy)| (i64::from(x) + dx, i64::from(y) + dy))
            .filter(move |&(nx, ny)| (0..w).contains(&nx) && (0..h).contains(&ny))
            .flat_map(move |(nx, ny)| {
                let pixel = ny as u32 * self.size.0 + nx as u32;
                quarters
                    .iter()
                    .filter_map(move |&q| self.at.get(&(pixel, r.chain, q)).map(|&j| j as usize))
            })
    }

    /// What multiplies receiver `k`'s value into its outgoing radiance: its diffuse albedo
    /// where the value is its irradiance ([`SparsePlan::by_irradiance`]), else one.
    pub fn albedo_of(&self, k: usize, r: &Receiver) -> Rgb {
        match &r.bsdf {
            Bsdf::Diffuse(d) if self.irradiance[k] => d.reflectance,
            _ => Rgb::ONE,
        }
    }

    /// Whether receiver `k`'s value is its irradiance E, which its albedo multiplies
    /// afterwards: a diffuse receiver that is eligible (alone in its pixel's layer and
    /// quarter, not a quarter of a geometric edge) or a quarter of a geometric edge (see the
    /// module docs). Every other value is
    /// the receiver's outgoing radiance.
    pub fn by_irradiance(&self, k: usize) -> bool {
        self.irradiance[k]
    }

    /// Whether receiver `k` lies on the grid of every `cell`-th row and column.
    fn on_grid_of(&self, receivers: &[Receiver], k: usize, cell: u32) -> bool {
        let (x, y) = local(receivers[k].pixel, self.origin, self.width);
        on_grid(x, self.size.0, cell) && on_grid(y, self.size.1, cell)
    }

    /// The receiver at the corner `pixel` (tile-local index) of receiver `r`'s cell: the
    /// eligible receiver of its layer there (see the module docs), on `r`'s surface.
    fn corner(&self, receivers: &[Receiver], r: &Receiver, pixel: u32) -> Option<usize> {
        let others = [None, Some(0), Some(1), Some(2), Some(3)];
        let mut quarters =
            std::iter::once(r.quarter).chain(others.into_iter().filter(|&q| q != r.quarter));
        quarters.find_map(|q| {
            let j = *self.at.get(&(pixel, r.chain, q))? as usize;
            lends_to(&receivers[j], r).then_some(j)
        })
    }

    /// The value of receiver `k` from the corners of its cell on the grid of every
    /// `cell`-th line, given theirs (`value(j)` for receiver j), or `None` where it cannot
    /// interpolate.
    fn interpolate(
        &self,
        receivers: &[Receiver],
        k: usize,
        cell: u32,
        value: impl Fn(usize) -> Rgb,
    ) -> Option<Rgb> {
        let r = &receivers[k];
        let (x, y) = local(r.pixel, self.origin, self.width);
        let (x0, x1, fx) = cell_of(x, self.size.0, cell);
        let (y0, y1, fy) = cell_of(y, self.size.1, cell);
        let corners = [
            ((x0, y0), (1.0 - fx) * (1.0 - fy)),
            ((x1, y0), fx * (1.0 - fy)),
            ((x0, y1), (1.0 - fx) * fy),
            ((x1, y1), fx * fy),
        ];
        let mut sum = Rgb::ZERO;
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        // A receiver on a grid line takes its two corners on that line.
        for ((cx, cy), w) in corners.into_iter().filter(|&(_, w)| w > 0.0) {
            let j = self.corner(receivers, r, cy * self.size.0 + cx)?;
            let e = value(j);
            (lo, hi) = (lo.min(luminance(e)), hi.max(luminance(e)));
            sum += e * w;
        }
        agree(lo, hi).then_some(sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::microfacet::{Distribution, Microfacet};
    use crate::bsdf::{Diffuse, RoughConductor};
    use crate::geometry::frame::Frame;
    use glam::Vec3;

    /// No receiver near another surface: every clearance infinite.
    fn open(receivers: &[Receiver]) -> Vec<f32> {
        vec![f32::INFINITY; receivers.len()]
    }

    /// The plan of an 8 × 8 tile at the image's corner with anchors every 4 pixels.
    fn plan8(receivers: &[Receiver], sparse: bool) -> SparsePlan {
        SparsePlan::new(receivers, (0, 0), (8, 8), 8, ANCHOR_SPACING, sparse)
    }

    /// Receivers on the plane z = 0 (mesh 0), one per pixel of an 8 × 8 tile at the image's
    /// corner, pixel (x, y) at (x, y, 0) facing +z.
    fn plane() -> Vec<Receiver> {
        plane_of(8)
    }

    /// [`plane`] over an `n` × `n` tile.
    fn plane_of(n: u32) -> Vec<Receiver> {
        (0..n * n)
            .map(|pixel| Receiver {
                pixel,
                weight: Rgb::ONE,
                p: Vec3::new((pixel % n) as f32, (pixel / n) as f32, 0.0),
                err: Vec3::ZERO,
                ng: Vec3::Z,
                mesh: 0,
                frame: Frame::from_normal(Vec3::Z),
                bsdf: Bsdf::Diffuse(Diffuse {
                    reflectance: Rgb::splat(0.5),
                }),
                view: Vec3::Z,
                chain: 0,
                quarter: None,
            })
            .collect()
    }

    /// Anchors on every fourth row and column and the last; bilinear interpolation is exact
    /// for irradiance that is bilinear in the pixel (to rounding), and refused where a corner
    /// leaves the receiver's surface (another mesh, a turned normal, a step off its plane) or
    /// the corners disagree by more than [`CONTRAST`].
    #[test]
    fn interpolates_within_a_surface_where_the_corners_agree() {
        let receivers = plane();
        let plan = plan8(&receivers, true);
        let anchors: Vec<u32> = (0..64).filter(|&k| plan.first[k as usize]).collect();
        let expected: Vec<u32> = (0..64)
            .filter(|k| [0, 4, 7].contains(&(k % 8)) && [0, 4, 7].contains(&(k / 8)))
            .collect();
        assert_eq!(anchors, expected);
        // E = 1 + 0.01 x + 0.02 y + 0.001 x y: bilinear, corners within 30 %.
        let e = |k: usize| {
            let (x, y) = ((k % 8) as f32, (k / 8) as f32);
            Rgb::splat(1.0 + 0.01 * x + 0.02 * y + 0.001 * x * y)
        };
        for k in (0..64).filter(|&k| !plan.first[k]) {
            let got = plan
                .interpolate(&receivers, k, ANCHOR_SPACING, e)
                .expect("interpolates");
            assert!(
                (got - e(k)).abs().max_element() < 1e-6,
                "{k}: {got} vs {}",
                e(k)
            );
        }
        // Pixel (5, 5) has corners (4, 4), (7, 4), (4, 7), (7, 7).
        let k = 5 * 8 + 5;
        let corner = 7 * 8 + 7;
        let changed = |f: &dyn Fn(&mut Receiver)| {
            let mut r = receivers.clone();
            f(&mut r[corner]);
            plan8(&r, true).interpolate(&r, k, ANCHOR_SPACING, e)
        };
        assert!(changed(&|r| r.mesh = 1).is_none(), "another mesh");
        let turned = Frame::from_normal(Vec3::new(0.0, 0.4, 1.0).normalize());
        assert!(changed(&|r| r.frame = turned).is_none(), "a turned normal");
        assert!(changed(&|r| r.p.z = 0.5).is_none(), "a step off the plane");
        let bright = |j: usize| if j == corner { e(j) * 1.4 } else { e(j) };
        assert!(
            plan.interpolate(&receivers, k, ANCHOR_SPACING, bright)
                .is_none(),
            "disagreeing corners"
        );
        // A conductor among diffuse corners cannot take their irradiance: it interpolates
        // only from corners with its very BSDF, whose values are its outgoing radiance.
        let gold = |alpha: f32| {
            Bsdf::Conductor(RoughConductor {
                distr: Microfacet::new(Distribution::Ggx, alpha, alpha),
                eta: Rgb::ZERO,
                k: Rgb::ONE,
                specular_reflectance: Rgb::ONE,
            })
        };
        let mut shiny = receivers.clone();
        shiny[k].bsdf = gold(0.3);
        let plan = plan8(&shiny, true);
        assert!(plan.interpolate(&shiny, k, ANCHOR_SPACING, e).is_none());
        for r in shiny.iter_mut() {
            r.bsdf = gold(0.3);
        }
        let plan = plan8(&shiny, true);
        let got = plan
            .interpolate(&shiny, k, ANCHOR_SPACING, e)
            .expect("interpolates");
        assert!((got - e(k)).abs().max_element() < 1e-6);
        assert!(
            !plan.by_irradiance(k),
            "a conductor's value is its radiance"
        );
        let diffuse = plan8(&receivers, true);
        assert!(
            diffuse.by_irradiance(k),
            "a diffuse one's is its irradiance"
        );
        shiny[corner].bsdf = gold(0.31);
        let plan = plan8(&shiny, true);
        assert!(
            plan.interpolate(&shiny, k, ANCHOR_SPACING, e).is_none(),
            "a corner of another roughness"
        );
        // Off, everyone gathers.
        let dense = plan8(&receivers, false);
        assert!((0..64).all(|k| dense.first[k]));
    }

    /// E = 1 + 0.01 x + 0.02 y + 0.001 x y at pixel (x, y) of a tile `side` wide: bilinear,
    /// with corners within [`CONTRAST`] of each other.
    fn bilinear(p: Vec3) -> Rgb {
        Rgb::splat(1.0 + 0.01 * p.x + 0.02 * p.y + 0.001 * p.x * p.y)
    }

    /// Interpolate a tile as the render does ([`SparsePlan::run`]), with every gather
    /// returning `bilinear` at the receiver; returns each receiver's value and whether it
    /// gathered.
    fn passes(receivers: &[Receiver], size: (u32, u32)) -> Vec<(Rgb, bool)> {
        passes_with(receivers, size, ANCHOR_SPACING, 0.0, bilinear)
    }

    /// [`passes`] with anchors every `coarsest` pixels, every pixel's direct light of
    /// luminance `floor`, and every gather returning `light` at the receiver.
    fn passes_with(
        receivers: &[Receiver],
        size: (u32, u32),
        coarsest: u32,
        floor: f32,
        light: impl Fn(Vec3) -> Rgb,
    ) -> Vec<(Rgb, bool)> {
        let plan = SparsePlan::new(receivers, (0, 0), size, size.0, coarsest, true);
        let mut value = vec![Rgb::splat(f32::NAN); receivers.len()];
        let mut gathered = vec![false; receivers.len()];
        let open = |_| f32::INFINITY;
        let (interpolated, _) = plan.run(
            receivers,
            &mut value,
            open,
            |_| floor,
            |which, value| {
                for &k in which {
                    assert!(!gathered[k], "{k} gathers twice");
                    gathered[k] = true;
                    value[k] = light(receivers[k].p);
                }
            },
        );
        assert_eq!(interpolated, gathered.iter().filter(|g| !**g).count());
        value.into_iter().zip(gathered).collect()
    }

    /// A cell with a corner on another surface: the finer grid inside it gathers, and the
    /// receivers between interpolate from the finer cells that stay on the surface (exactly,
    /// for bilinear E); only the pixels next to the foreign corner gather besides.
    #[test]
    fn a_failed_cell_interpolates_from_finer_cells() {
        let mut receivers = plane();
        let corner = 7 * 8 + 7;
        receivers[corner].mesh = 1;
        let out = passes(&receivers, (8, 8));
        for (k, &(e, _)) in out.iter().enumerate() {
            let want = bilinear(receivers[k].p);
            assert!((e - want).abs().max_element() < 1e-6, "{k}: {e} vs {want}");
        }
        let gathered: Vec<usize> = (0..64).filter(|&k| out[k].1).collect();
        // Besides the coarse grid, only the finer grid's pixels whose coarse cell failed gather:
        // (6, 6), (7, 6) and (6, 7). The other five of the failed cell's eight, (5, 5),
        // (5, 6), (6, 5), (7, 5) and (5, 7), interpolate from finer cells clear of (7, 7).
        let coarse = [0, 4, 7, 32, 36, 39, 56, 60, 63];
        let more: Vec<usize> = gathered
            .iter()
            .copied()
            .filter(|k| !coarse.contains(k))
            .collect();
        assert_eq!(more, [6 * 8 + 6, 6 * 8 + 7, 7 * 8 + 6]);
        assert!(!out[5 * 8 + 5].1, "(5, 5) interpolates from its finer cell");
    }

    /// Each chain is a layer: the receivers seen through a mirror (another chain, another
    /// surface) interpolate from their own layer's anchors, not from the primary hits of the
    /// same pixels; the four quarters of a mirror's pixel of many samples interpolate each from
    /// the corners' whole pixels. The quarters of a pixel on a geometric edge (primary hits)
    /// gather, and so do two receivers of one chain in one pixel.
    #[test]
    fn chains_and_quarters_are_layers_of_their_own() {
        let primary = plane();
        let mirrored: Vec<Receiver> = primary
            .iter()
            .map(|r| Receiver {
                p: r.p + Vec3::new(100.0, 50.0, -10.0),
                mesh: 3,
                chain: 42,
                ..r.clone()
            })
            .collect();
        let mut receivers: Vec<Receiver> = primary.into_iter().chain(mirrored).collect();
        // Pixel (5, 5) of the mirrored layer becomes four quarters.
        let centre = 64 + 5 * 8 + 5;
        let quarter = |q: u8| Receiver {
            quarter: Some(q),
            ..receivers[centre].clone()
        };
        let quarters: Vec<Receiver> = (1..4).map(quarter).collect();
        receivers[centre] = quarter(0);
        receivers.extend(quarters);
        let out = passes(&receivers, (8, 8));
        for (k, &(e, gathered)) in out.iter().enumerate() {
            let want = bilinear(receivers[k].p);
            assert!((e - want).abs().max_element() < 1e-5, "{k}: {e} vs {want}");
            let (x, y) = (receivers[k].pixel % 8, receivers[k].pixel / 8);
            let anchor = [0, 4, 7].contains(&x) && [0, 4, 7].contains(&y);
            assert_eq!(gathered, anchor, "{k} at ({x}, {y})");
        }
        // The same quarters on the primary layer: an edge pixel's, which do not interpolate
        // from other pixels; on one surface, two of them gather and the others may share
        // their gathers (see `quarters_on_one_surface_share_the_farthest_two`).
        let mut edge = receivers.clone();
        for r in edge.iter_mut().filter(|r| r.quarter.is_some()) {
            r.chain = 0;
            r.mesh = 0;
        }
        let plan = plan8(&edge, true);
        let quarters: Vec<usize> = (0..edge.len())
            .filter(|&k| edge[k].quarter.is_some())
            .collect();
        assert_eq!(quarters.iter().filter(|&&k| plan.first[k]).count(), 2);
        assert!(quarters
            .iter()
            .all(|&k| plan.first[k] != plan.lender[k].is_some()));
        // Two receivers of one chain in one pixel (not told apart by quarter) gather.
        let pixel = 64 + 5 * 8 + 6;
        let mut twice = receivers.clone();
        twice.push(twice[pixel].clone());
        let plan = plan8(&twice, true);
        assert!(plan.first[pixel] && plan.first[twice.len() - 1]);
    }

    /// The four quarters of a geometric edge's pixel on one surface: the two farthest apart
    /// (diagonal) gather, and the other two take the nearer one's value (both equally near:
    /// the first) where the two agree to [`CONTRAST`]; where they do not (a step of 2× in
    /// the light between them), all four gather.
    #[test]
    fn quarters_on_one_surface_share_the_farthest_two() {
        let mut receivers = plane();
        let centre = 5 * 8 + 5;
        let quarters: Vec<Receiver> = (0..4u8)
            .map(|q| {
                let (dx, dy) = (f32::from(q % 2) - 0.5, f32::from(q / 2) - 0.5);
                Receiver {
                    quarter: Some(q),
                    p: receivers[centre].p + Vec3::new(0.5 * dx, 0.5 * dy, 0.0),
                    ..receivers[centre].clone()
                }
            })
            .collect();
        receivers[centre] = quarters[0].clone();
        receivers.extend(quarters[1..].iter().cloned());
        let [q0, q1, q2, q3] = [centre, 64, 65, 66];
        let out = passes(&receivers, (8, 8));
        assert!(out[q0].1 && out[q3].1 && !out[q1].1 && !out[q2].1);
        assert_eq!(out[q1].0, out[q0].0);
        assert_eq!(out[q2].0, out[q0].0);
        let step = |p: Vec3| Rgb::splat(if p.x > 5.0 { 2.0 } else { 1.0 });
        let out = passes_with(&receivers, (8, 8), ANCHOR_SPACING, 0.0, step);
        assert!([q0, q1, q2, q3].iter().all(|&q| out[q].1));
        assert_eq!(out[q1].0, step(receivers[q1].p));
    }

    /// Pixel (7, 7) of a 16 × 16 tile on the plane made a geometric edge's four quarters (on
    /// the plane too), each 0.25 pixel off the centre.
    fn edge_quarters() -> (Vec<Receiver>, [usize; 4]) {
        let mut receivers = plane_of(16);
        let centre = 7 * 16 + 7;
        let quarter = |q: u8| {
            let (dx, dy) = (f32::from(q % 2) - 0.5, f32::from(q / 2) - 0.5);
            Receiver {
                quarter: Some(q),
                p: receivers[centre].p + Vec3::new(0.5 * dx, 0.5 * dy, 0.0),
                ..receivers[centre].clone()
            }
        };
        let quarters: Vec<Receiver> = (0..4).map(quarter).collect();
        receivers[centre] = quarters[0].clone();
        receivers.extend(quarters[1..].iter().cloned());
        (receivers, [centre, 256, 257, 258])
    }

    /// Which receivers gather, and every value, for a tile of 16 pixels with anchors every
    /// `coarsest`, the given clearances and `light` at each receiver.
    fn edge_passes(
        receivers: &[Receiver],
        coarsest: u32,
        clearance: &[f32],
        light: impl Fn(Vec3) -> Rgb,
    ) -> Vec<(Rgb, bool)> {
        let plan = SparsePlan::new(receivers, (0, 0), (16, 16), 16, coarsest, true);
        let mut value = vec![Rgb::splat(f32::NAN); receivers.len()];
        let mut gathered = vec![false; receivers.len()];
        plan.run(
            receivers,
            &mut value,
            |k| clearance[k],
            |_| 0.0,
            |which, value| {
                for &k in which {
                    gathered[k] = true;
                    value[k] = light(receivers[k].p);
                }
            },
        );
        value.into_iter().zip(gathered).collect()
    }

    /// In a frame of 512 pixels or more (anchors every 8), a geometric edge's quarters take
    /// the light of the whole pixels within two of theirs on their surface, weighted by the
    /// inverse square of the distance: under constant light it (to rounding), under linear light
    /// within the slope times the farthest donor's reach. They gather instead where the
    /// donors disagree by more than [`CONTRAST`], where another surface lies near in front
    /// (their clearance under 1/[`REACH`] of the donors' distance), and in smaller frames.
    #[test]
    fn edge_quarters_take_their_neighbours_light_where_clear() {
        let (receivers, quarters) = edge_quarters();
        let clear = open(&receivers);
        let flat = |_: Vec3| Rgb::splat(0.7);
        let out = edge_passes(&receivers, WIDEST_CELL, &clear, flat);
        for q in quarters {
            assert!(!out[q].1, "{q} gathered");
            assert!((out[q].0 - Rgb::splat(0.7)).abs().max_element() < 1e-6);
        }
        let slope = |p: Vec3| Rgb::splat(1.0 + 0.01 * p.x + 0.02 * p.y);
        let out = edge_passes(&receivers, WIDEST_CELL, &clear, slope);
        for q in quarters {
            let want = slope(receivers[q].p);
            assert!(!out[q].1);
            // A weighted mean of f over the donors differs from f at the quarter by at most
            // f's largest change to a donor: 0.01 |dx| + 0.02 |dy| with |dx|, |dy| at most
            // NEIGHBOURS plus the quarter's 0.25 off its pixel's centre.
            let bound = 0.03 * (NEIGHBOURS as f32 + 0.25);
            assert!((out[q].0 - want).abs().max_element() < bound, "{q}");
        }
        // A step of 2× through the pixel: its neighbours disagree, so the quarters gather.
        let step = |p: Vec3| Rgb::splat(if p.x > 7.0 { 2.0 } else { 1.0 });
        let out = edge_passes(&receivers, WIDEST_CELL, &clear, step);
        assert!(quarters.iter().all(|&q| out[q].1));
        // Another surface half a pixel in front: only donors within an eighth of a pixel
        // would do, and none is that near. The two farthest apart gather, and the others,
        // on their surface, share their gathers (`quarters_on_one_surface_share_the_farthest_two`).
        let mut near = clear.clone();
        for q in quarters {
            near[q] = 0.5;
        }
        let out = edge_passes(&receivers, WIDEST_CELL, &near, flat);
        let [q0, q1, q2, q3] = quarters;
        assert!(out[q0].1 && out[q3].1 && !out[q1].1 && !out[q2].1);
        // Anchors every 4 pixels (frames under 512): the two gather as before.
        let out = edge_passes(&receivers, ANCHOR_SPACING, &clear, flat);
        assert!(out[q0].1 && out[q3].1 && !out[q1].1 && !out[q2].1);
    }

    /// In the same frames, a primary hit whose finest cell (2 pixels) fails, here for a corner
    /// on another mesh, takes the light of the pixels beside it rather than gathering, where
    /// its clearance allows: under constant light every value is that light, and the
    /// receivers that no longer gather are all off the grid of 2 (they feed no other cell).
    #[test]
    fn the_finest_cells_failures_borrow_too() {
        let mut receivers = plane_of(16);
        receivers[8 * 16 + 8].mesh = 1;
        let flat = |_: Vec3| Rgb::splat(0.7);
        let clear = open(&receivers);
        let closed = vec![0.0; receivers.len()];
        let borrowed = edge_passes(&receivers, WIDEST_CELL, &clear, flat);
        let gathering = edge_passes(&receivers, WIDEST_CELL, &closed, flat);
        for (e, _) in &borrowed {
            assert!((*e - Rgb::splat(0.7)).abs().max_element() < 1e-6);
        }
        let saved: Vec<usize> = (0..receivers.len())
            .filter(|&k| gathering[k].1 && !borrowed[k].1)
            .collect();
        assert!(!saved.is_empty());
        assert!((0..receivers.len()).all(|k| !borrowed[k].1 || gathering[k].1));
        for k in saved {
            let (x, y) = (k % 16, k / 16);
            assert!(x % 2 == 1 && x != 15 || y % 2 == 1 && y != 15, "({x}, {y})");
        }
    }

    /// Donors at the very point of the quarter weigh 1/f32::MIN_POSITIVE each: where their
    /// light then takes the sums past f32's range, the quarters gather rather than lend an
    /// infinite value, and no value anywhere is NaN or infinite.
    #[test]
    fn borrowing_never_lends_an_infinite_value() {
        let (mut receivers, quarters) = edge_quarters();
        // Two of them: their weights still sum within f32's range, their light does not.
        for k in [6 * 16 + 7, 8 * 16 + 7] {
            receivers[k].p = receivers[quarters[0]].p;
        }
        let bright = |_: Vec3| Rgb::splat(1e30);
        let out = edge_passes(&receivers, WIDEST_CELL, &open(&receivers), bright);
        assert!(out[quarters[0]].1, "the quarter gathers");
        assert!(out.iter().all(|(e, _)| e.is_finite()));
    }

    /// A receiver's clearance counts the other surfaces in front of its tangent plane that
    /// it lies behind (a lid over it, the back of a hanging light), not a wall facing it (a
    /// crease), nor what is behind its plane or on it.
    #[test]
    fn clearance_counts_the_surfaces_a_receiver_lies_behind() {
        let r = &plane()[0];
        let lid = (1, Vec3::new(0.3, 0.0, 1.0), Vec3::Z);
        let wall = (
            2,
            Vec3::new(0.2, 0.0, 0.2),
            Vec3::new(-1.0, 0.0, 1.0).normalize(),
        );
        let below = (1, Vec3::new(0.0, 0.0, -0.1), Vec3::Z);
        let same = (0, Vec3::new(0.1, 0.0, 0.0), Vec3::Z);
        let around = [lid, wall, below, same];
        assert_eq!(clearance(r, around.into_iter()), lid.1.length());
        assert_eq!(clearance(r, [wall, below, same].into_iter()), f32::INFINITY);
    }

    /// The anchors' spacing doubles with the frame's shorter side from 512 pixels, up to 8,
    /// and a crop's spacing is its frame's (the argument is the frame).
    #[test]
    fn anchor_spacing_follows_the_frame() {
        for ((w, h), cell) in [
            ((64, 64), 4),
            ((256, 256), 4),
            ((511, 4096), 4),
            ((4096, 511), 4),
            ((512, 512), 8),
            ((1920, 1080), 8),
            ((16384, 16384), 8),
        ] {
            assert_eq!(coarsest_cell(w, h), cell, "{w} × {h}");
        }
    }

    /// Anchors every 8 pixels in a 16 × 16 tile: only the 3 × 3 grid (0, 8 and the last line)
    /// gathers on a plane lit bilinearly (half [`bilinear`]'s slopes, so that corners 8 pixels
    /// apart agree to [`CONTRAST`]), and the rest interpolates exactly. With a corner
    /// of the grid on another mesh, the cells refine through 4 to 2 pixels around it: the
    /// failed cell's grid of 4 gathers, then only the pixels next to the foreign corner.
    #[test]
    fn coarser_anchors_refine_down_to_pairs() {
        let n = 16;
        let light = |p: Vec3| bilinear(0.5 * p);
        let run = |receivers: &[Receiver]| -> Vec<u32> {
            let out = passes_with(receivers, (n, n), 8, 0.0, light);
            for (k, &(e, _)) in out.iter().enumerate() {
                let want = light(receivers[k].p);
                assert!((e - want).abs().max_element() < 1e-5, "{k}: {e} vs {want}");
            }
            (0..n * n).filter(|&k| out[k as usize].1).collect()
        };
        let on = |lines: &[u32]| -> Vec<u32> {
            (0..n * n)
                .filter(|k| lines.contains(&(k % n)) && lines.contains(&(k / n)))
                .collect()
        };
        let mut receivers = plane_of(n);
        assert_eq!(run(&receivers), on(&[0, 8, 15]));
        let corner = 15 * n + 15;
        receivers[corner as usize].mesh = 1;
        // The failed cell (8..15)²: its grid of 4 gathers where no grid line of 8 clear of
        // (15, 15) holds it ((12, 8) and (8, 12) take their line's two corners), then the
        // failed cell of 4 (12..15)²'s grid of 2 beside the foreign corner.
        let mut want: Vec<u32> = on(&[0, 8, 15]);
        want.extend(
            [(12, 12), (15, 12), (12, 15), (14, 14), (15, 14), (14, 15)]
                .iter()
                .map(|&(x, y)| y * n + x),
        );
        want.sort_unstable();
        assert_eq!(run(&receivers), want);
    }

    /// A tile narrower than a cell past a grid line (5 pixels: columns 0, 4 on the grid, 4 the
    /// last) interpolates finitely: a cell of zero width takes its one line.
    #[test]
    fn narrow_tiles_interpolate_finitely() {
        let receivers: Vec<Receiver> = plane()
            .into_iter()
            .filter(|r| r.pixel % 8 < 5)
            .map(|r| Receiver {
                pixel: (r.pixel / 8) * 5 + r.pixel % 8,
                ..r
            })
            .collect();
        let out = passes(&receivers, (5, 8));
        for (k, &(e, _)) in out.iter().enumerate() {
            let want = bilinear(receivers[k].p);
            assert!((e - want).abs().max_element() < 1e-6, "{k}: {e} vs {want}");
        }
    }

    /// A faint receiver (a chain's end at 1 % of its pixel) whose finest cell fails (a corner
    /// missing) takes the inverse-square mean of its layer's receivers around it where what
    /// their spread would put into its pixel is within [`CONTRAST`] of the pixel's floor plus
    /// the darkest donor's share; else it gathers. A receiver of full weight in the same place
    /// gathers whatever its pixel's floor.
    #[test]
    fn faint_receivers_borrow_within_a_bound_on_their_pixel() {
        // E = 1 + 0.12 x: cells of 4 span 48 % and fail, cells of 2 span 24 % and interpolate;
        // the donors within two pixels of x = 1 span x = 0..3, 36 %.
        let light = |p: Vec3| Rgb::splat(1.0 + 0.12 * p.x);
        let layer = |weight: f32| -> Vec<Receiver> {
            plane()
                .into_iter()
                .filter(|r| r.pixel != 2 * 8 + 2)
                .map(|r| Receiver {
                    weight: Rgb::splat(weight),
                    chain: 7,
                    ..r
                })
                .collect()
        };
        let at = |receivers: &[Receiver], x: u32, y: u32| {
            receivers.iter().position(|r| r.pixel == y * 8 + x).unwrap()
        };
        let faint = layer(0.01);
        let k = at(&faint, 1, 1);
        // Dark pixel: the spread, 0.36 × 0.01 × 0.5 = 0.0018, exceeds 0.3 × 0.005.
        let dark = passes_with(&faint, (8, 8), ANCHOR_SPACING, 0.0, light);
        assert!(
            dark[k].1,
            "borrowed where its donors disagree in a dark pixel"
        );
        assert_eq!(dark[k].0, light(faint[k].p));
        // Lit pixel: 0.0018 ≤ 0.3 × (0.01 + 0.005).
        let lit = passes_with(&faint, (8, 8), ANCHOR_SPACING, 0.01, light);
        assert!(!lit[k].1, "gathered where its donors may lend");
        let (e, truth) = (lit[k].0.x, light(faint[k].p).x);
        // The donors' inverse-square mean around x = 1: within their range, near the truth.
        assert!((1.0..=1.36).contains(&e), "borrowed {e}");
        assert!((e - truth).abs() < 0.05, "borrowed {e}, truth {truth}");
        // Full weight: no bound on its pixel lets it borrow.
        let full = layer(1.0);
        let out = passes_with(&full, (8, 8), ANCHOR_SPACING, 1e6, light);
        assert!(out[at(&full, 1, 1)].1);
    }
}

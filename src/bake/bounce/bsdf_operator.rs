//! A BSDF as a sparse 4D Haar operator: the outgoing radiance of a surfel for all directions at
//! once from the wavelets of its incoming radiance (docs/method.md §8.2, refraction §8.6).
//!
//! Both the incoming and the outgoing directions are texels of an n × n equal-area grid per
//! hemisphere of the local frame (the microbuffer's grid, docs/design.md §5.3): one hemisphere for
//! reflecting BSDFs, two (upper, then lower) for `roughdielectric`. With `x[i]` the mean
//! incoming radiance of texel i and `L[o]` the mean outgoing radiance of texel o,
//!
//! ```text
//! L[o] = Σ_i K[o][i] x[i],   K[o][i] = mean over ω_o in o of ∫_{texel i} f(ω_o, ω) cos θ dω.
//! ```
//!
//! With W the orthonormal non-standard 2D Haar matrix per hemisphere, C = W x, V = W K Wᵀ and
//! D = V C = W L, so L = Wᵀ D (the thesis's Eq. 5.2; the four hemisphere blocks of docs/method.md §8.6 are the blocks
//! of K). V and C are thresholded; by the triangle and Cauchy–Schwarz inequalities and
//! Parseval, the error of L in the L2 norm over texels is at most
//! ‖E_V‖_F ‖C‖ + ‖V_kept‖_F ‖E_C‖ (E the dropped coefficients), which
//! [`BsdfOperator::error_bound`] states.
//!
//! Decisions where the thesis is open:
//! - The cosine is folded into K, not into x (the thesis folds it into x). Each column of K (the
//!   light arriving through one texel) is scaled, its reflected and its transmitted part
//!   separately, so that the flux it sends out equals what importance sampling of the BSDF
//!   from that texel gives (Mitsuba's sampling weights, at most 1 together). Lobes narrower
//!   than a texel (α = 0.02 at 32²) then neither lose energy nor create it, which point
//!   sampling at texel centres would (measured: a column sending 2.7× its flux at α = 0.02).
//! - K is integrated with s × s points per incoming texel and (s/2)² per outgoing texel; the
//!   sampling of each column is seeded by its index, so the operator is the same for any
//!   thread count.
//! - Thresholding (NLA) of V: each column keeps its largest coefficients and drops at most
//!   `tau` of its L2 norm (so ‖E_V‖_F ≤ tau ‖V‖_F). A cut of single coefficients against the
//!   global norm wiped out the columns of dim incoming directions. Measured at tau = 1e-2
//!   (tests/bsdf_operator.rs): V keeps 4 % of its coefficients at α = 0.02 (32²), 22 % at
//!   0.1 (16²), 74 % at 0.5 (8²), and the product is within 1 % (L2) of the dense sum.
//! - Lobes far narrower than a texel fill every Haar level of V's columns, while K's stay a
//!   few texels wide (α = 0.001 at 32², for the same error: 9.8 entries per column of K
//!   against 20.6 of V for a conductor, 15.6 against 36.4 for a dielectric). Such an
//!   operator is held as K in the texel basis ([`Basis`]), thresholded by the same rule at a
//!   quarter of the threshold ([`TEXEL_TAU_FACTOR`]), and its product is K x, with no
//!   transforms: 2.3× faster at α = 0.001. W being orthonormal, the bound above holds in
//!   either basis.
//! - [`BsdfOperator::outgoing`] drops the negative values thresholding leaves and scales the
//!   outgoing flux to what the albedo lets through, so thresholding neither creates energy (a
//!   stiff scene's bounces would diverge) nor loses it (they would fall short).
//! - RGB: V holds RGB coefficients (a conductor's Fresnel is coloured), and D\[b\] = Σ_a C\[a\] ⊙
//!   V\[b\]\[a\] channel by channel.
//! - Few operators for textured materials ([`Operators`]): an operator is built for the BSDF
//!   without its tints ([`Bsdf::untinted`]), and the tints of reflection and transmission
//!   scale V's blocks in the product (K is linear in them, block by block), so a textured
//!   base colour shares one operator. A textured roughness snaps to
//!   [`ROUGHNESS_LEVELS_PER_OCTAVE`] levels per octave of α ([`quantised_alpha`]), chosen by
//!   the bake ([`crate::bake::pipeline::surfel_bsdf`]): at most 9 % from the texel's α, and
//!   the operator of the nearest level is within [`QUANTISATION_ERROR`] of the exact one
//!   (tests/bsdf_operator.rs).

use crate::bsdf::microfacet::MIN_ALPHA;
use crate::bsdf::{Bsdf, TransportMode};
use crate::gather::microbuffer::Microbuffer;
use crate::geometry::frame::Frame;
use crate::geometry::warp::square_to_hemisphere_equal_area;
use crate::haar::{texel_directions, Haar2d};
use crate::sampler::{sobol02, Sampler};
use crate::spectrum::Rgb;
use glam::{Vec2, Vec3, Vec3A};
use rayon::prelude::*;
use std::sync::Arc;

/// BSDF samples per incoming texel for the flux each column of K is scaled to.
pub(crate) const ALBEDO_SAMPLES: u32 = 256;

/// Incoming coefficients below this fraction of their norm are dropped before D = V·C.
pub const INCOMING_TAU: f32 = 1e-3;

/// Tints that leave an operator as built: `[reflected, transmitted]` (see [`Bsdf::untinted`]).
pub const UNTINTED: [Rgb; 2] = [Rgb::ONE; 2];

/// Levels per octave (factor of 2) of α that a textured roughness snaps to.
pub const ROUGHNESS_LEVELS_PER_OCTAVE: f32 = 4.0;

/// The largest relative L2 error (over texels) of the outgoing radiance of a roughness level's
/// operator against the exact α's: 7.8 % measured (tests/bsdf_operator.rs, α from 0.03 to 1,
/// largest near α = 1), for a snap of at most 9 % in α, 4.4 % in glTF's roughness √α.
pub const QUANTISATION_ERROR: f32 = 0.08;

/// The level of the roughness grid nearest `alpha`: 2^(−k/4) for the nearest integer k, so
/// within a factor 2^(1/8) (9 %) of `alpha`. A textured roughness is snapped to it, so that
/// a bake builds one operator per level, not one per surfel.
pub fn quantised_alpha(alpha: f32) -> f32 {
    let k = (-alpha.max(MIN_ALPHA).log2() * ROUGHNESS_LEVELS_PER_OCTAVE).round();
    (-k / ROUGHNESS_LEVELS_PER_OCTAVE).exp2()
}

/// A texel of a surfel's sphere map that no texel of its operator's grid feeds (below a
/// reflecting BSDF's horizon), see [`BsdfOperator::map_texels`].
pub const NO_TEXEL: u16 = u16::MAX;

/// The operator grid for a BSDF: fine enough for its lobe, as the surfel maps' resolution.
pub fn operator_side(bsdf: &Bsdf) -> u32 {
    match bsdf.alpha() {
        Some(a) if a < 0.08 => 32,
        Some(a) if a < 0.3 => 16,
        _ => 8,
    }
}

/// The operators a bake has built, one per distinct untinted BSDF and threshold: the direct
/// light builds those of near-specular BSDFs, the bounces the rest (and reuse the direct
/// light's). A bake handed the operators of an earlier one ([`Operators::with_kept`]: a
/// relight's, from the transport file) takes each whose [`OperatorKey`] it would build
/// instead of building it: the same operator bit for bit, without the build (0.13 of
/// cbox-rough's 2.1 s relight, 0.46 of cbox-glossy's 5.3 s).
#[derive(Debug, Default)]
pub struct Operators {
    built: Vec<(Bsdf, f32, KeyedOperator)>,
    /// Operators of an earlier bake not yet asked for.
    kept: Vec<KeyedOperator>,
    /// How many of `built` came from `kept`.
    reused: usize,
}

/// An operator with the key of what it was built from.
pub type KeyedOperator = (OperatorKey, Arc<BsdfOperator>);

/// The hash of everything an operator is built from: the untinted BSDF's parameters (as
/// `Debug` writes them, as [`material_hash`](crate::cache::store::material_hash) hashes a
/// material: two BSDFs that print alike are equal), its grid side and its threshold. The build
/// itself is part of the transport file's format: a change to it changes
/// [`VERSION`](super::kept::VERSION), so that no file keeps operators another build made.
pub type OperatorKey = [u8; 16];

/// The [`OperatorKey`] of `untinted` on an `n × n` grid at threshold `tau`.
pub fn operator_key(untinted: &Bsdf, n: u32, tau: f32) -> OperatorKey {
    let mut h = xxhash_rust::xxh3::Xxh3::new();
    h.update(format!("{untinted:?}").as_bytes());
    // Fixed-size fields after the only variable one: no two inputs give the same bytes.
    h.update(&n.to_le_bytes());
    h.update(&tau.to_bits().to_le_bytes());
    h.digest128().to_le_bytes()
}

/// A surfel's operator: its BSDF's untinted operator, shared, and its tints.
#[derive(Clone, Debug)]
pub struct SurfelOperator {
    /// The untinted operator of its BSDF (shared by every surfel with the same lobe shape).
    pub shared: Arc<BsdfOperator>,
    /// `[reflected, transmitted]`, see [`Bsdf::untinted`].
    pub tints: [Rgb; 2],
}

impl SurfelOperator {
    /// [`BsdfOperator::sphere_map`] with this surfel's tints.
    pub fn sphere_map(&self, incident: &[Rgb], map_texels: &[u16]) -> Vec<Rgb> {
        self.shared.sphere_map(incident, map_texels, self.tints)
    }
}

impl Operators {
    /// No operators built yet, those of `kept` (an earlier bake's
    /// [`Operators::keyed`]) to be taken instead of built where their keys are asked for.
    pub fn with_kept(kept: Vec<KeyedOperator>) -> Operators {
        Operators {
            kept,
            ..Operators::default()
        }
    }

    /// The operator of `bsdf` thresholded at `tau` (see [`BsdfOperator::new`]): its untinted
    /// BSDF's, built (or taken from the kept ones) on first use, with its tints.
    pub fn get(&mut self, bsdf: &Bsdf, tau: f32) -> SurfelOperator {
        let (untinted, tints) = bsdf.untinted();
        let found = self
            .built
            .iter()
            .find(|(b, t, _)| *b == untinted && *t == tau);
        let shared = match found {
            Some((_, _, (_, op))) => op.clone(),
            None => {
                let n = operator_side(&untinted);
                let key = operator_key(&untinted, n, tau);
                let hemispheres = if untinted.is_two_sided() { 2 } else { 1 };
                // A kept operator of another grid (a file made to collide) is not taken.
                let kept = self
                    .kept
                    .iter()
                    .position(|(k, op)| *k == key && op.n == n && op.hemispheres == hemispheres)
                    .map(|i| self.kept.swap_remove(i).1);
                self.reused += usize::from(kept.is_some());
                let op = kept.unwrap_or_else(|| Arc::new(BsdfOperator::new(&untinted, n, tau)));
                self.built.push((untinted, tau, (key, op.clone())));
                op
            }
        };
        SurfelOperator { shared, tints }
    }

    /// Every operator built (or taken), with its key: what a transport file keeps.
    pub fn keyed(&self) -> Vec<KeyedOperator> {
        self.built.iter().map(|(_, _, k)| k.clone()).collect()
    }

    /// How many of the operators were taken from the kept ones rather than built.
    pub fn reused(&self) -> usize {
        self.reused
    }

    /// The operator (at `tau`) of each BSDF of `bsdfs` (one per surfel) that is `wanted`,
    /// `None` for the others.
    pub fn of_each(
        &mut self,
        bsdfs: &[Bsdf],
        tau: f32,
        wanted: impl Fn(&Bsdf) -> bool,
    ) -> Vec<Option<SurfelOperator>> {
        bsdfs
            .iter()
            .map(|b| wanted(b).then(|| self.get(b, tau)))
            .collect()
    }

    /// How many operators have been built.
    pub fn len(&self) -> usize {
        self.built.len()
    }

    /// Whether none has been built.
    pub fn is_empty(&self) -> bool {
        self.built.is_empty()
    }
}

/// A BSDF's sparse operator: V = W K Wᵀ in the 4D Haar basis, or K itself in the texel
/// basis, whichever is cheaper to multiply by ([`Basis::cheaper`]).
#[derive(Clone, Debug, PartialEq)]
pub struct BsdfOperator {
    /// Texels per side of each hemisphere's grid (a power of two).
    pub n: u32,
    /// 1 (reflection) or 2 (upper and lower hemispheres).
    pub hemispheres: u32,
    basis: Basis,
    /// Column a (incoming coefficient or texel a) is `entries[starts[a]..starts[a + 1]]`,
    /// pairs of (outgoing coefficient or texel b, V\[b\]\[a\] or K\[b\]\[a\]).
    starts: Vec<u32>,
    /// Column a's entries into the other hemisphere (b ≥ n², scaled by the other tint) start
    /// at `lower_starts[a]`: found once here, not searched for in every product (the search
    /// was a third of [`BsdfOperator::apply`]'s time).
    lower_starts: Vec<u32>,
    entries: Entries,
    /// ‖V_kept‖_F and ‖E_V‖_F, each coefficient measured by its largest channel.
    kept_norm: f32,
    dropped_norm: f32,
    /// See [`Kernel`].
    albedo: Vec<[Rgb; 2]>,
    cosines: Vec<f32>,
}

/// The basis an operator's columns are held in. Both are orthonormal (W is), so a column
/// thresholded in either loses the same share of its L2 norm and [`BsdfOperator::error_bound`]
/// holds for both.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Basis {
    /// V = W K Wᵀ: the product transforms the incoming texels, drops their small
    /// coefficients ([`INCOMING_TAU`]) and transforms the result back. Sparse for lobes wider
    /// than a few texels, where K is dense.
    Haar,
    /// K: the product is one sparse matrix-vector product over the texels. Sparse for lobes
    /// narrower than a texel, whose Haar columns fill every level (α = 0.001: 5.4 kept
    /// entries per column of K against 20.6 of V for a conductor, 7.0 against 36.4 for a
    /// dielectric).
    Texels,
}

impl Basis {
    /// The basis to hold an operator in, for `texels` and `haar` entries kept of its columns
    /// (K's at [`TEXEL_TAU_FACTOR`] times V's threshold): the texel basis where K keeps at
    /// most half of what V keeps. Measured under the noisy lighting of
    /// tests/bsdf_operator.rs: at α = 0.001 (K keeping 0.43–0.48 of V's entries) the texel
    /// basis's product took 0.44× the Haar basis's time, at the same error; at α = 0.02 (K
    /// keeping 0.6–0.8 of V) 0.62–0.65× the time, but a conductor's texels under uniform
    /// light strayed 2.2 % above its albedo against 1.5 % (thresholding a texel column drops
    /// the lobe's tails texel by texel), so it stays in the Haar basis.
    pub fn cheaper(texels: usize, haar: usize) -> Basis {
        if 2 * texels <= haar {
            Basis::Texels
        } else {
            Basis::Haar
        }
    }
}

/// The texel basis's threshold, as a fraction of the Haar basis's: at the same threshold,
/// its outgoing radiance under a noisy light erred 2–2.5 times as much (0.0228 against
/// 0.0094 of the L2 norm for a α = 0.001 conductor); at a quarter of it, as much (0.0096
/// against 0.0094; 0.0076 against 0.0106 for the dielectric).
pub const TEXEL_TAU_FACTOR: f32 = 0.25;

/// An operator's thresholded columns, in either basis.
struct Columns {
    starts: Vec<u32>,
    entries: Vec<(u32, Rgb)>,
    /// ‖kept‖_F and ‖dropped‖_F, each entry measured by its largest channel.
    kept_norm: f32,
    dropped_norm: f32,
}

impl Columns {
    /// `columns` with each one's smallest entries dropped while their energy stays below
    /// `tau`² of the column's. A cut of each coefficient against a global norm wiped out the
    /// columns of dim incoming directions (a grazing texel of a α = 0.02 conductor then sent
    /// out 5× its flux), and one against the column's norm still let a column's many small
    /// coefficients add up (11 % extra flux through one texel of α = 0.02 glass).
    fn thresholded(columns: &[Vec<Rgb>], tau: f32) -> Columns {
        let energy = |v: &Rgb| f64::from(v.abs().max_element()).powi(2);
        // Per column, in parallel: its kept entries and the energy dropped.
        let per_column: Vec<(Vec<(u32, Rgb)>, f64)> = columns
            .par_iter()
            .map(|column| {
                let energies: Vec<f64> = column.iter().map(energy).collect();
                let norm2: f64 = energies.iter().sum();
                // Smallest first, ties by index: every key is distinct.
                let mut order: Vec<(f64, u32)> = energies
                    .iter()
                    .enumerate()
                    .map(|(b, &e)| (e, b as u32))
                    .collect();
                order.sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
                let budget = f64::from(tau).powi(2) * norm2;
                let mut keep = vec![true; column.len()];
                let mut lost = 0.0f64;
                for &(e, b) in &order {
                    if lost + e > budget {
                        break;
                    }
                    lost += e;
                    keep[b as usize] = false;
                }
                let entries = column
                    .iter()
                    .enumerate()
                    .filter(|&(b, v)| keep[b] && *v != Rgb::ZERO)
                    .map(|(b, v)| (b as u32, *v))
                    .collect();
                (entries, lost)
            })
            .collect();
        // The norms summed in column order, as one pass over the columns would.
        let mut starts = Vec::with_capacity(columns.len() + 1);
        starts.push(0);
        let mut entries = Vec::with_capacity(per_column.iter().map(|(e, _)| e.len()).sum());
        let (mut kept, mut dropped) = (0.0f64, 0.0f64);
        for (column, lost) in per_column {
            dropped += lost;
            for (_, v) in &column {
                kept += energy(v);
            }
            entries.extend_from_slice(&column);
            starts.push(entries.len() as u32);
        }
        Columns {
            starts,
            entries,
            kept_norm: kept.sqrt() as f32,
            dropped_norm: dropped.sqrt() as f32,
        }
    }
}

/// V's coefficients: RGB, or one value for all three channels where every coefficient is
/// grey (a dielectric's Fresnel, a white conductor's), which the product reads at a third
/// of the bytes (it is bound by reading V: glass took a fifth of a later bounce) and
/// multiplies to the same bits.
#[derive(Clone, Debug, PartialEq)]
enum Entries {
    Rgb(Vec<(u32, Rgb)>),
    Grey(Vec<(u32, f32)>),
}

impl Entries {
    /// `entries` as grey ones where every one is.
    fn of(entries: Vec<(u32, Rgb)>) -> Entries {
        if entries.iter().all(|(_, v)| v.x == v.y && v.y == v.z) {
            Entries::Grey(entries.into_iter().map(|(b, v)| (b, v.x)).collect())
        } else {
            Entries::Rgb(entries)
        }
    }

    fn len(&self) -> usize {
        match self {
            Entries::Rgb(e) => e.len(),
            Entries::Grey(e) => e.len(),
        }
    }
}

/// Per column of `starts` and `entries` (sorted by outgoing index within each column), where
/// its entries into the lower hemisphere (index ≥ `block`) start.
fn lower_starts<V>(starts: &[u32], entries: &[(u32, V)], block: u32) -> Vec<u32> {
    starts
        .windows(2)
        .map(|w| {
            let column = &entries[w[0] as usize..w[1] as usize];
            w[0] + column.partition_point(|(b, _)| *b < block) as u32
        })
        .collect()
}

/// An operator as numbers, for a file to hold ([`BsdfOperator::parts`]) and to give back
/// ([`BsdfOperator::from_parts`], which checks them).
#[derive(Clone, Debug, PartialEq)]
pub struct OperatorParts {
    /// Texels per side of each hemisphere's grid.
    pub n: u32,
    /// 1 or 2.
    pub hemispheres: u32,
    /// The basis the columns are in.
    pub basis: Basis,
    /// Column a is entries `starts[a]..starts[a + 1]`.
    pub starts: Vec<u32>,
    /// Each entry's outgoing coefficient or texel.
    pub rows: Vec<u32>,
    /// Each entry's value: one number where `grey`, else three (RGB).
    pub values: Vec<f32>,
    /// Whether every entry is grey (one number).
    pub grey: bool,
    /// ‖V_kept‖_F and ‖E_V‖_F.
    pub norms: [f32; 2],
    /// Per incoming texel, its own side's then the other side's flux fractions (RGB each).
    pub albedo: Vec<f32>,
    /// Per texel, its mean |cos θ|.
    pub cosines: Vec<f32>,
}

/// `d[b] += weight · v` over the `(b, v)` of a column's two parts (its entries into the
/// upper hemisphere, then the lower), the first adding `weights[0]`, the second `weights[1]`.
fn add_column<V: Copy>(
    d: &mut [Vec3A],
    parts: [&[(u32, V)]; 2],
    weights: [Vec3A; 2],
    scaled: impl Fn(Vec3A, V) -> Vec3A,
) {
    for (part, weight) in parts.into_iter().zip(weights) {
        for &(b, v) in part {
            d[b as usize] += scaled(weight, v);
        }
    }
}

/// The local direction through point `u` of hemisphere `h`'s unit square.
fn direction(h: u32, u: Vec2) -> Vec3 {
    let d = square_to_hemisphere_equal_area(u);
    if h == 1 {
        Vec3::new(d.x, d.y, -d.z)
    } else {
        d
    }
}

/// The sample points of texel `t` (of `hemispheres × n × n`, row-major per hemisphere) on an
/// `s × s` grid.
fn texel_points(t: u32, n: u32, s: u32) -> impl Iterator<Item = Vec3> {
    let (h, y, x) = (t / (n * n), (t / n) % n, t % n);
    (0..s * s).map(move |k| {
        let sub = Vec2::new((k % s) as f32 + 0.5, (k / s) as f32 + 0.5) / s as f32;
        direction(h, (Vec2::new(x as f32, y as f32) + sub) / n as f32)
    })
}

/// The texel of a local direction, or `None` below the horizon of a one-hemisphere grid.
fn texel_of(w: Vec3, n: u32, hemispheres: u32) -> Option<u32> {
    let h = u32::from(w.z < 0.0);
    if h >= hemispheres {
        return None;
    }
    let p = crate::geometry::warp::hemisphere_equal_area_to_square(Vec3::new(w.x, w.y, w.z.abs()));
    let x = ((p.x * n as f32) as u32).min(n - 1);
    let y = ((p.y * n as f32) as u32).min(n - 1);
    Some((h * n + y) * n + x)
}

/// The orthonormal 2D Haar coefficients (W x) of a vector of texels, hemisphere by hemisphere,
/// flattened as [scale, details level by level].
pub fn forward(texels: &[Rgb], n: u32) -> Vec<Rgb> {
    let block = (n * n) as usize;
    let mut out = Vec::with_capacity(texels.len());
    for h in texels.chunks(block) {
        // Haar2d is orthonormal for functions on the unit square, W for texel vectors: W = n T.
        let c = Haar2d::forward(h, n as usize);
        out.push(c.scale * n as f32);
        out.extend(
            c.details
                .iter()
                .flat_map(|d| d.iter().map(|&v| v * n as f32)),
        );
    }
    out
}

/// The texels of flattened coefficients (Wᵀ D), the inverse of [`forward`].
pub fn inverse(coefficients: &[Rgb], n: u32) -> Vec<Rgb> {
    let block = (n * n) as usize;
    let mut out = Vec::with_capacity(coefficients.len());
    for c in coefficients.chunks(block) {
        let h = Haar2d {
            levels: n.trailing_zeros(),
            scale: c[0] * (1.0 / n as f32),
            details: c[1..]
                .chunks(3)
                .map(|d| {
                    [
                        d[0] * (1.0 / n as f32),
                        d[1] * (1.0 / n as f32),
                        d[2] * (1.0 / n as f32),
                    ]
                })
                .collect(),
        };
        out.extend(h.inverse());
    }
    out
}

/// The dense kernel K (rows: outgoing texels; columns: incoming texels) of `bsdf` on the
/// `n × n` grid per hemisphere, each column's reflected and transmitted parts scaled to the
/// flux that BSDF sampling from the column's directions sends that way.
pub fn kernel(bsdf: &Bsdf, n: u32) -> Kernel {
    let hemispheres = if bsdf.is_two_sided() { 2 } else { 1 };
    let texels = hemispheres * n * n;
    let solid_angle = std::f32::consts::TAU / (n * n) as f32;
    // Incoming texels take s × s points, outgoing ones (s/2)²: the columns are scaled to the
    // right energy anyway.
    let s = if n >= 32 { 2 } else { 4 };
    let so = (s / 2).max(1);
    // Every incoming point of every texel as lanes (x, y, z), texel by texel: each outgoing
    // point is evaluated against all of them at once (`Bsdf::eval_lanes`, the same values
    // bit for bit as one by one), and the sums below take them in the same order as before.
    let per_texel = (s * s) as usize;
    let mut lanes = [Vec::new(), Vec::new(), Vec::new()];
    for i in 0..texels {
        for wi in texel_points(i, n, s) {
            for (lane, v) in lanes.iter_mut().zip(wi.to_array()) {
                lane.push(v);
            }
        }
    }
    let lanes = [&lanes[0][..], &lanes[1][..], &lanes[2][..]];
    let mut k: Vec<Vec<Rgb>> = (0..texels)
        .into_par_iter()
        .map(|o| {
            // Mitsuba's convention: eval(towards the viewer, towards the light).
            let values: Vec<Vec<Rgb>> = texel_points(o, n, so)
                .map(|wo| {
                    let mut out = Vec::new();
                    bsdf.eval_lanes(wo, lanes, TransportMode::Radiance, &mut out);
                    out
                })
                .collect();
            (0..texels as usize)
                .map(|i| {
                    let mut sum = Rgb::ZERO;
                    for p in i * per_texel..(i + 1) * per_texel {
                        for v in &values {
                            sum += v[p];
                        }
                    }
                    sum * (solid_angle / (s * s * so * so) as f32)
                })
                .collect()
        })
        .collect();
    let cosines = mean_cosines(n, hemispheres);
    let targets: Vec<[Rgb; 2]> = (0..texels)
        .into_par_iter()
        .map(|i| sampled_flux(bsdf, i, n, hemispheres))
        .collect();
    // Per column and side: the flux the quadrature sends, Σ_o K[o][i] cos_o / cos_i.
    let block = (n * n) as usize;
    let mut flux = vec![[Rgb::ZERO; 2]; texels as usize];
    for (o, row) in k.iter().enumerate() {
        for (i, v) in row.iter().enumerate() {
            let side = usize::from(o / block != i / block);
            flux[i][side] += *v * (cosines[o] / cosines[i]);
        }
    }
    for (o, row) in k.iter_mut().enumerate() {
        for (i, v) in row.iter_mut().enumerate() {
            let side = usize::from(o / block != i / block);
            let (have, want) = (flux[i][side], targets[i][side]);
            for c in 0..3 {
                v[c] *= if have[c] > 0.0 {
                    want[c] / have[c]
                } else {
                    0.0
                };
            }
        }
    }
    Kernel {
        rows: k,
        albedo: targets,
        cosines,
    }
}

/// A BSDF's dense kernel on the texel grid.
pub struct Kernel {
    /// K\[o\]\[i\].
    pub rows: Vec<Vec<Rgb>>,
    /// Per incoming texel, the fractions of its flux the BSDF sends to its own side and to
    /// the other.
    pub albedo: Vec<[Rgb; 2]>,
    /// Per texel, the mean |cos θ|.
    pub cosines: Vec<f32>,
}

/// The exact mean |cos θ| of every texel (the microbuffer's closed form).
pub fn mean_cosines(n: u32, hemispheres: u32) -> Vec<f32> {
    let grid = Microbuffer::new(n, hemispheres == 2, Frame::from_normal(Vec3::Z));
    grid.pixels
        .iter()
        .map(|p| p.dir.z.abs() * p.cos_weight)
        .collect()
}

/// The fractions of the flux arriving through texel `i` that leave on its own side and on
/// the other, by importance sampling (Mitsuba's weights are these fractions: at most 1
/// together).
fn sampled_flux(bsdf: &Bsdf, i: u32, n: u32, hemispheres: u32) -> [Rgb; 2] {
    let ins: Vec<Vec3> = texel_points(i, n, 4).collect();
    let mut sampler = Sampler::new(0x0b5d_f00d, u64::from(i), 0);
    let scramble = sampler.next_scramble();
    let per = ALBEDO_SAMPLES / ins.len() as u32;
    let mut out = [Rgb::ZERO; 2];
    for (j, &w) in ins.iter().enumerate() {
        for k in 0..per {
            let index = j as u32 * per + k;
            let u0 = (index as f32 + 0.5) / ALBEDO_SAMPLES as f32;
            let Some(bs) = bsdf.sample(w, u0, sobol02(index, scramble), TransportMode::Importance)
            else {
                continue;
            };
            if texel_of(bs.wo, n, hemispheres).is_none() || !bs.weight.is_finite() {
                continue;
            }
            out[usize::from((bs.wo.z < 0.0) != (w.z < 0.0))] += bs.weight;
        }
    }
    let count = (per * ins.len() as u32) as f32;
    out.map(|v| v / count)
}

impl BsdfOperator {
    /// The operator of `bsdf` on an `n × n` grid per hemisphere; each column keeps its
    /// largest coefficients, dropping at most `tau` of its L2 norm (in the texel basis
    /// [`TEXEL_TAU_FACTOR`] times `tau`). Held in the basis whose product costs less
    /// ([`Basis::cheaper`]).
    pub fn new(bsdf: &Bsdf, n: u32, tau: f32) -> Self {
        Self::build(bsdf, n, tau, None)
    }

    /// [`BsdfOperator::new`] held in `basis`, whatever it costs (to compare the two).
    pub fn in_basis(bsdf: &Bsdf, n: u32, tau: f32, basis: Basis) -> Self {
        Self::build(bsdf, n, tau, Some(basis))
    }

    fn build(bsdf: &Bsdf, n: u32, tau: f32, basis: Option<Basis>) -> Self {
        assert!(
            n.is_power_of_two() && n >= 2,
            "grid side must be a power of two"
        );
        let hemispheres = if bsdf.is_two_sided() { 2 } else { 1 };
        let size = (hemispheres * n * n) as usize;
        let Kernel {
            rows: k,
            albedo,
            cosines,
        } = kernel(bsdf, n);
        // K's columns (incoming texel a) for the texel basis; for the Haar basis M = rows
        // transformed over the incoming texels, then V = columns of M transformed over the
        // outgoing texels.
        let in_texels = || -> Vec<Vec<Rgb>> {
            (0..size)
                .into_par_iter()
                .map(|a| k.iter().map(|row| row[a]).collect())
                .collect()
        };
        let in_haar = || -> Vec<Vec<Rgb>> {
            let m: Vec<Vec<Rgb>> = k.par_iter().map(|row| forward(row, n)).collect();
            (0..size)
                .into_par_iter()
                .map(|a| {
                    let column: Vec<Rgb> = m.iter().map(|row| row[a]).collect();
                    forward(&column, n)
                })
                .collect()
        };
        let texel_tau = tau * TEXEL_TAU_FACTOR;
        let (basis, columns) = match basis {
            Some(Basis::Texels) => (Basis::Texels, Columns::thresholded(&in_texels(), texel_tau)),
            Some(Basis::Haar) => (Basis::Haar, Columns::thresholded(&in_haar(), tau)),
            None => {
                let texels = Columns::thresholded(&in_texels(), texel_tau);
                let haar = Columns::thresholded(&in_haar(), tau);
                match Basis::cheaper(texels.entries.len(), haar.entries.len()) {
                    Basis::Texels => (Basis::Texels, texels),
                    Basis::Haar => (Basis::Haar, haar),
                }
            }
        };
        let lower_starts = lower_starts(&columns.starts, &columns.entries, n * n);
        BsdfOperator {
            n,
            hemispheres,
            basis,
            lower_starts,
            starts: columns.starts,
            entries: Entries::of(columns.entries),
            kept_norm: columns.kept_norm,
            dropped_norm: columns.dropped_norm,
            albedo,
            cosines,
        }
    }

    /// The basis the operator is held in.
    pub fn basis(&self) -> Basis {
        self.basis
    }

    /// The operator as numbers ([`OperatorParts`]).
    pub fn parts(&self) -> OperatorParts {
        let (rows, values, grey) = match &self.entries {
            Entries::Rgb(e) => (
                e.iter().map(|(b, _)| *b).collect(),
                e.iter().flat_map(|(_, v)| v.to_array()).collect(),
                false,
            ),
            Entries::Grey(e) => (
                e.iter().map(|(b, _)| *b).collect(),
                e.iter().map(|(_, v)| *v).collect(),
                true,
            ),
        };
        OperatorParts {
            n: self.n,
            hemispheres: self.hemispheres,
            basis: self.basis,
            starts: self.starts.clone(),
            rows,
            values,
            grey,
            norms: [self.kept_norm, self.dropped_norm],
            albedo: self
                .albedo
                .iter()
                .flat_map(|[own, other]| own.to_array().into_iter().chain(other.to_array()))
                .collect(),
            cosines: self.cosines.clone(),
        }
    }

    /// The operator whose [`BsdfOperator::parts`] are `parts`, the same bit for bit; the
    /// reason in words where they are not an operator's (a grid of another size than its
    /// columns, a column out of order or past the entries, an index off the grid), so that
    /// none makes a product read out of bounds.
    pub fn from_parts(parts: OperatorParts) -> std::result::Result<BsdfOperator, String> {
        let OperatorParts {
            n,
            hemispheres,
            basis,
            starts,
            rows,
            values,
            grey,
            norms,
            albedo,
            cosines,
        } = parts;
        if !(2..=32).contains(&n) || !n.is_power_of_two() || !(1..=2).contains(&hemispheres) {
            return Err(format!(
                "an operator has a grid of {n}² texels and {hemispheres} hemispheres"
            ));
        }
        let size = (hemispheres * n * n) as usize;
        let per = if grey { 1 } else { 3 };
        if starts.len() != size + 1
            || starts[0] != 0
            || starts.windows(2).any(|w| w[0] > w[1])
            || starts[size] as usize != rows.len()
            || values.len() != per * rows.len()
            || albedo.len() != 6 * size
            || cosines.len() != size
        {
            return Err("an operator's columns are not of its grid's size".into());
        }
        let in_order = starts.windows(2).all(|w| {
            let column = &rows[w[0] as usize..w[1] as usize];
            column.windows(2).all(|b| b[0] < b[1])
                && column.last().is_none_or(|&b| (b as usize) < size)
        });
        if !in_order {
            return Err("an operator's entries are out of order or off its grid".into());
        }
        let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
        if !finite(&values) || !finite(&albedo) || !finite(&cosines) || !finite(&norms) {
            return Err("an operator holds a value that is not a number".into());
        }
        let block = n * n;
        let (entries, lower) = if grey {
            let e: Vec<(u32, f32)> = rows.into_iter().zip(values).collect();
            let lower = lower_starts(&starts, &e, block);
            (Entries::Grey(e), lower)
        } else {
            let e: Vec<(u32, Rgb)> = rows
                .into_iter()
                .zip(values.chunks_exact(3))
                .map(|(b, v)| (b, Rgb::new(v[0], v[1], v[2])))
                .collect();
            let lower = lower_starts(&starts, &e, block);
            (Entries::Rgb(e), lower)
        };
        let rgb = |c: &[f32]| Rgb::new(c[0], c[1], c[2]);
        Ok(BsdfOperator {
            n,
            hemispheres,
            basis,
            starts,
            lower_starts: lower,
            entries,
            kept_norm: norms[0],
            dropped_norm: norms[1],
            albedo: albedo
                .chunks_exact(6)
                .map(|c| [rgb(&c[..3]), rgb(&c[3..])])
                .collect(),
            cosines,
        })
    }

    /// Texels (and coefficients) per direction set.
    pub fn size(&self) -> usize {
        (self.hemispheres * self.n * self.n) as usize
    }

    /// The texel of local direction `w`, or `None` below a one-hemisphere grid's horizon.
    pub fn texel_of(&self, w: Vec3) -> Option<u32> {
        texel_of(w, self.n, self.hemispheres)
    }

    /// Per texel of a surfel's global sphere map (`2^levels` texels per side), the texel of
    /// this operator's grid in the surfel's `frame` that feeds it, by nearest texel (the
    /// thesis leaves the filter open, docs/method.md §8.2), or [`NO_TEXEL`]. A grid has at most 2 × 32² texels
    /// ([`operator_side`]), well within `u16`.
    pub fn map_texels(&self, frame: Frame, levels: u32) -> Vec<u16> {
        texel_directions(levels)
            .iter()
            .map(|&w| {
                self.texel_of(frame.to_local(w))
                    .and_then(|t| u16::try_from(t).ok())
                    .unwrap_or(NO_TEXEL)
            })
            .collect()
    }

    /// The texels of a surfel's sphere map (as many as `map_texels`, its
    /// [`BsdfOperator::map_texels`]) of the light leaving it for `incident` radiance per texel
    /// of the grid: D = V·C ([`BsdfOperator::outgoing`], incoming coefficients thresholded at
    /// [`INCOMING_TAU`]) read by nearest texel, zero where [`NO_TEXEL`]. The one step from
    /// incident light to a map, for the bounces and the near-specular direct light alike.
    pub fn sphere_map(&self, incident: &[Rgb], map_texels: &[u16], tints: [Rgb; 2]) -> Vec<Rgb> {
        let local = self.outgoing(incident, INCOMING_TAU, tints);
        map_texels
            .iter()
            .map(|&t| local.get(t as usize).copied().unwrap_or(Rgb::ZERO))
            .collect()
    }

    /// The incoming radiance per texel of the grid from samples of an estimator: each a local
    /// unit direction and what it carries, radiance times solid angle (Lₑ/(p K) for one of K
    /// emitter samples). A texel's value is the radiance that, weighted by the texel's mean
    /// |cos θ| as the operator weights it ([`kernel`]), carries the flux its samples bring:
    /// their cosine-weighted sum over the texel's solid angle (2π/n², the grid is equal-area)
    /// and mean cosine. A plain mean would give a light near the texel's horizon edge the
    /// texel's mean cosine, several times its own. Samples below a reflecting BSDF's horizon
    /// are dropped.
    pub fn incident(&self, samples: impl Iterator<Item = (Vec3, Rgb)>) -> Vec<Rgb> {
        let texel_solid_angle = 2.0 * std::f32::consts::PI / (self.n * self.n) as f32;
        let mut x = vec![Rgb::ZERO; self.size()];
        for (w, value) in samples {
            if let Some(t) = self.texel_of(w) {
                let t = t as usize;
                x[t] += value * (w.z.abs() / (self.cosines[t] * texel_solid_angle));
            }
        }
        x
    }

    /// Stored coefficients of V.
    pub fn nonzeros(&self) -> usize {
        self.entries.len()
    }

    /// D = V C for the coefficients `c` of the incoming radiance (in the texel basis, K x for
    /// its texels), the blocks from one hemisphere to the same scaled by `tints[0]`
    /// (reflection), to the other by `tints[1]` (transmission). Coefficients and texels are
    /// hemisphere by hemisphere, so an entry's hemisphere is its index over n².
    pub fn apply(&self, c: &[Rgb], tints: [Rgb; 2]) -> Vec<Rgb> {
        let block = self.n * self.n;
        // Summed in SIMD lanes (the same products and sums as Rgb's, channel by channel).
        let mut d = vec![Vec3A::ZERO; self.size()];
        let tints = tints.map(Vec3A::from);
        for (a, &ca) in c.iter().enumerate() {
            let ca = Vec3A::from(ca);
            if ca == Vec3A::ZERO {
                continue;
            }
            // A column's entries are in order of b: the upper hemisphere's, then the lower's.
            let (start, lower, end) = (
                self.starts[a] as usize,
                self.lower_starts[a] as usize,
                self.starts[a + 1] as usize,
            );
            let (same, other) = (ca * tints[0], ca * tints[1]);
            let weights = if (a as u32) < block {
                [same, other]
            } else {
                [other, same]
            };
            match &self.entries {
                Entries::Rgb(e) => add_column(
                    &mut d,
                    [&e[start..lower], &e[lower..end]],
                    weights,
                    |w, v| w * Vec3A::from(v),
                ),
                Entries::Grey(e) => add_column(
                    &mut d,
                    [&e[start..lower], &e[lower..end]],
                    weights,
                    |w, v| w * v,
                ),
            }
        }
        d.into_iter().map(Rgb::from).collect()
    }

    /// The product L = Wᵀ V C for the incoming radiance per texel `radiance`, with the
    /// incoming coefficients below `tau_c` times their norm dropped and V tinted by `tints`
    /// (see [`BsdfOperator::apply`]); in the texel basis L = K x, which drops nothing
    /// incoming. Also the bound on its L2 error (over texels, largest channel) that
    /// thresholding can cause, for an untinted operator.
    pub fn product(&self, radiance: &[Rgb], tau_c: f32, tints: [Rgb; 2]) -> (Vec<Rgb>, f32) {
        if self.basis == Basis::Texels {
            // K x: nothing to transform, and every texel is read (no incoming threshold).
            let norm = radiance
                .iter()
                .map(|x| f64::from(x.abs().max_element()).powi(2))
                .sum::<f64>()
                .sqrt() as f32;
            return (self.apply(radiance, tints), self.error_bound(norm, 0.0));
        }
        let mut c = forward(radiance, self.n);
        let magnitude = |x: &Rgb| f64::from(x.abs().max_element());
        let full = c.iter().map(|x| magnitude(x).powi(2)).sum::<f64>().sqrt() as f32;
        let cut = tau_c * full;
        let mut dropped = 0.0f64;
        for v in c.iter_mut() {
            let m = magnitude(v);
            if m < f64::from(cut) {
                dropped += m * m;
                *v = Rgb::ZERO;
            }
        }
        let bound = self.error_bound(full, dropped.sqrt() as f32);
        (inverse(&self.apply(&c, tints), self.n), bound)
    }

    /// The outgoing radiance per texel for the incoming radiance per texel `radiance`: the
    /// [`BsdfOperator::product`], without the negative values thresholding leaves and, per
    /// channel, scaled so that its flux is what the BSDF's albedo lets out of the incoming
    /// flux, as the unthresholded operator's is. Thresholding then moves light between
    /// directions but neither creates nor loses it: a stiff scene's bounces (albedo near 1)
    /// amplify any loss per bounce (a 0.17 % loss left a closed glossy room at ρ = 0.99 3 %
    /// dark), and would diverge on any gain. `tints` as in [`BsdfOperator::apply`].
    pub fn outgoing(&self, radiance: &[Rgb], tau_c: f32, tints: [Rgb; 2]) -> Vec<Rgb> {
        // The product without its error bound (whose norm the texel basis would compute for
        // nothing: this runs for every directional receiver in every bounce).
        let mut out = match self.basis {
            Basis::Texels => self.apply(radiance, tints),
            Basis::Haar => self.product(radiance, tau_c, tints).0,
        };
        for v in out.iter_mut() {
            *v = v.max(Rgb::ZERO);
        }
        let flux = |v: &[Rgb], weight: &dyn Fn(usize) -> Rgb| {
            v.iter()
                .enumerate()
                .fold(Rgb::ZERO, |s, (t, x)| s + *x * weight(t))
        };
        let albedo = |t: usize| self.albedo[t][0] * tints[0] + self.albedo[t][1] * tints[1];
        let allowed = flux(radiance, &|t| albedo(t) * self.cosines[t]);
        let sent = flux(&out, &|t| Rgb::splat(self.cosines[t]));
        let scale = Rgb::select(sent.cmpgt(Rgb::ZERO), allowed / sent, Rgb::ZERO);
        for v in out.iter_mut() {
            *v *= scale;
        }
        out
    }

    /// The bound ‖E_V‖_F ‖C‖ + ‖V_kept‖_F ‖E_C‖ on the L2 error of the outgoing texels, for
    /// incoming coefficients of norm `c_norm` of which `dropped_c` was dropped.
    pub fn error_bound(&self, c_norm: f32, dropped_c: f32) -> f32 {
        // Per channel the Frobenius norms are at most the largest-channel ones used here.
        self.dropped_norm * c_norm + self.kept_norm * dropped_c
    }
}

//! The orthonormal non-standard 2D Haar transform of an N × N image, N = 2^J (docs/method.md §4.2).
//!
//! Texel values are read as a piecewise-constant function f on the unit square. Its coefficients
//! are the inner products with the orthonormal basis: one scaling coefficient `⟨f, 1⟩` and, for
//! each level l = 0 … J−1 and cell (i, j) of the 2^l × 2^l grid, three details for the wavelets
//! `2^l ψ(x)φ(y)`, `2^l φ(x)ψ(y)` and `2^l ψ(x)ψ(y)` on that cell (ψ = +1 on the cell's lower half
//! in that coordinate, −1 on the upper). Each level's step is the orthogonal 4 × 4 butterfly with
//! entries ±½, so the transform preserves energy (Parseval) and inverts exactly.
//!
//! Details are stored level by level, cells row-major: cell (l, i, j) is at
//! [`detail_index`]`(l, i, j)`, and its four children are the cells (l+1, 2i+a, 2j+b). That is a
//! complete quadtree in breadth-first order, the layout the sparse trees are cut from.

use std::ops::{Add, Mul, Sub};

/// What a coefficient can be: a scalar or an RGB triple.
pub trait Coefficient:
    Copy + Default + PartialEq + Add<Output = Self> + Sub<Output = Self> + Mul<f32, Output = Self>
{
    /// Floats per coefficient in the cache encoding.
    const FLOATS: usize;

    /// The size that thresholding compares: |c| for a scalar, the largest |component| for RGB.
    fn magnitude(self) -> f32;

    /// Append the little-endian floats.
    fn write_le(self, out: &mut Vec<u8>);

    /// Build from `FLOATS` floats.
    fn from_floats(f: &[f32]) -> Self;
}

impl Coefficient for f32 {
    const FLOATS: usize = 1;

    #[inline]
    fn magnitude(self) -> f32 {
        self.abs()
    }

    fn write_le(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }

    fn from_floats(f: &[f32]) -> Self {
        f[0]
    }
}

impl Coefficient for glam::Vec3 {
    const FLOATS: usize = 3;

    #[inline]
    fn magnitude(self) -> f32 {
        self.abs().max_element()
    }

    fn write_le(self, out: &mut Vec<u8>) {
        for x in self.to_array() {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }

    fn from_floats(f: &[f32]) -> Self {
        glam::Vec3::new(f[0], f[1], f[2])
    }
}

/// The three details of one cell: `[ψφ (varies along x), φψ (along y), ψψ]`.
pub type Details<T> = [T; 3];

/// The full Haar decomposition of an image.
#[derive(Clone, Debug, PartialEq)]
pub struct Haar2d<T> {
    /// log2 of the image side.
    pub levels: u32,
    /// ⟨f, 1⟩, the mean of f over the unit square.
    pub scale: T,
    /// `(4^J − 1) / 3` detail triples, breadth-first (see the module docs).
    pub details: Vec<Details<T>>,
}

/// Where the point `(x, y)` of the unit square falls at level `l`: its cell `(i, j)`, and the
/// quadrant of that cell (0 to 3, x varying first), which is also the child cell one level finer.
#[inline]
pub(crate) fn locate(x: f32, y: f32, l: u32) -> (u32, u32, usize) {
    let cells = 1u32 << l;
    // Position in units of half-cells at this level: the cell, and the half within it.
    let hx = ((x * 2.0 * cells as f32) as u32).min(2 * cells - 1);
    let hy = ((y * 2.0 * cells as f32) as u32).min(2 * cells - 1);
    (hx >> 1, hy >> 1, ((hx & 1) + 2 * (hy & 1)) as usize)
}

/// The value of a level-`l` cell's three wavelets at a point in `quadrant` of the cell: each is
/// ±2^l, + on the lower half of the cell in its varying coordinate.
#[inline]
pub(crate) fn detail_value<T: Coefficient>(d: Details<T>, quadrant: usize, l: u32) -> T {
    let sx = if quadrant & 1 == 0 { 1.0 } else { -1.0 };
    let sy = if quadrant & 2 == 0 { 1.0 } else { -1.0 };
    let [dx, dy, dxy] = d;
    (dx * sx + dy * sy + dxy * (sx * sy)) * (1u32 << l) as f32
}

/// Where the details of cell `(i, j)` (x, y) of level `l` are stored.
#[inline]
pub fn detail_index(l: u32, i: u32, j: u32) -> usize {
    let first = ((1usize << (2 * l)) - 1) / 3;
    first + ((j as usize) << l) + i as usize
}

impl<T: Coefficient> Haar2d<T> {
    /// Decompose the `n × n` image `texels` (row-major, `texels[y·n + x]`); `n` must be a power
    /// of two (≥ 1).
    pub fn forward(texels: &[T], n: usize) -> Self {
        assert!(
            n.is_power_of_two() && texels.len() == n * n,
            "image must be 2^J × 2^J"
        );
        let levels = n.trailing_zeros();
        // Scaling coefficients of the finest level: ⟨f, N·1_texel⟩ = value / N.
        let mut s: Vec<T> = texels.iter().map(|&v| v * (1.0 / n as f32)).collect();
        let mut details = vec![[T::default(); 3]; ((1usize << (2 * levels)) - 1) / 3];
        let mut side = n;
        for l in (0..levels).rev() {
            let half = side / 2;
            let mut next = vec![T::default(); half * half];
            for j in 0..half {
                for i in 0..half {
                    let a = s[2 * j * side + 2 * i];
                    let b = s[2 * j * side + 2 * i + 1];
                    let c = s[(2 * j + 1) * side + 2 * i];
                    let d = s[(2 * j + 1) * side + 2 * i + 1];
                    next[j * half + i] = (a + b + c + d) * 0.5;
                    details[detail_index(l, i as u32, j as u32)] = [
                        (a - b + c - d) * 0.5,
                        (a + b - c - d) * 0.5,
                        (a - b - c + d) * 0.5,
                    ];
                }
            }
            s = next;
            side = half;
        }
        Haar2d {
            levels,
            scale: s[0],
            details,
        }
    }

    /// The same function on a finer grid of `2^levels` texels per side: the coarse
    /// coefficients are exactly the fine ones, the finer details being zero.
    pub fn refined_to(&self, levels: u32) -> Self {
        assert!(levels >= self.levels, "refining to a coarser grid");
        let mut details = self.details.clone();
        details.resize(((1usize << (2 * levels)) - 1) / 3, [T::default(); 3]);
        Haar2d {
            levels,
            scale: self.scale,
            details,
        }
    }

    /// `a·x + b·y` coefficient by coefficient, at the finer of the two resolutions: the
    /// coarser map counts as refined to it ([`Haar2d::refined_to`], zero finer details), so
    /// maps of a subtree that never needs fine detail stay small, with the same result.
    pub fn combine(x: &Self, a: f32, y: &Self, b: f32) -> Self {
        let scaled = |c: &[T; 3], k: f32| [c[0] * k, c[1] * k, c[2] * k];
        let shared = x.details.len().min(y.details.len());
        let mut details: Vec<Details<T>> = x.details[..shared]
            .iter()
            .zip(&y.details[..shared])
            .map(|(p, q)| {
                [
                    p[0] * a + q[0] * b,
                    p[1] * a + q[1] * b,
                    p[2] * a + q[2] * b,
                ]
            })
            .collect();
        details.extend(x.details[shared..].iter().map(|p| scaled(p, a)));
        details.extend(y.details[shared..].iter().map(|q| scaled(q, b)));
        Haar2d {
            levels: x.levels.max(y.levels),
            scale: x.scale * a + y.scale * b,
            details,
        }
    }

    /// The L2 norm of the function (of its coefficient vector, by orthonormality), with each
    /// coefficient measured by [`Coefficient::magnitude`].
    pub fn norm(&self) -> f32 {
        std::iter::once(self.scale)
            .chain(self.details.iter().flat_map(|d| d.iter().copied()))
            .map(|c| (c.magnitude() as f64).powi(2))
            .sum::<f64>()
            .sqrt() as f32
    }

    /// The image back (exact up to rounding).
    pub fn inverse(&self) -> Vec<T> {
        let mut s = vec![self.scale];
        for l in 0..self.levels {
            let side = 1usize << l;
            let mut next = vec![T::default(); 4 * side * side];
            for j in 0..side {
                for i in 0..side {
                    let m = s[j * side + i];
                    let [dx, dy, dxy] = self.details[detail_index(l, i as u32, j as u32)];
                    let w = 2 * side;
                    next[2 * j * w + 2 * i] = (m + dx + dy + dxy) * 0.5;
                    next[2 * j * w + 2 * i + 1] = (m - dx + dy - dxy) * 0.5;
                    next[(2 * j + 1) * w + 2 * i] = (m + dx - dy - dxy) * 0.5;
                    next[(2 * j + 1) * w + 2 * i + 1] = (m - dx - dy + dxy) * 0.5;
                }
            }
            s = next;
        }
        let n = 1usize << self.levels;
        s.iter().map(|&v| v * n as f32).collect()
    }

    /// f at the point `(x, y)` of the unit square, from the root down to the finest cell
    /// containing it: O(J).
    pub fn eval(&self, x: f32, y: f32) -> T {
        let mut value = self.scale;
        for l in 0..self.levels {
            let (i, j, quadrant) = locate(x, y, l);
            value = value + detail_value(self.details[detail_index(l, i, j)], quadrant, l);
        }
        value
    }
}

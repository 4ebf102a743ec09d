//! Fewer gathers for the same image (issue 20): diffuse receivers gather on a sparse grid of
//! pixels, and the receivers between take their irradiance from the grid where it is smooth.
//!
//! Indirect light on a diffuse surface varies slowly, except across edges, contacts and the
//! shadows of indirect light; the albedo that multiplies it (a texture) may vary fast. So a
//! tile's diffuse receivers are split:
//!
//! - **Eligible** receivers: a diffuse BSDF, alone in their pixel (edge pixels, with four
//!   gathering samples, and specular chains always gather).
//! - **Anchors**: the eligible receivers on the grid of every [`CELL`]-th row and column of
//!   the tile (and its last row and column). They gather, and keep their irradiance E (the
//!   cosine-weighted incident light over π: the outgoing radiance of a white diffuse surface).
//! - The others take E from the four anchors at the corners of their cell, bilinearly, when
//!   all four exist, lie on the receiver's mesh and plane (normals within 18°, offsets from
//!   its tangent plane within a tenth of the distance) and agree with each other to
//!   [`CONTRAST`] in luminance; otherwise they gather. Each multiplies E by its own albedo.
//!
//! Everything is decided within the tile, in receiver order: the image is the same for any
//! thread count.

use super::primary::Receiver;
use crate::bsdf::Bsdf;
use crate::spectrum::{luminance, Rgb};

/// Pixels between anchors along a row or column.
pub const CELL: u32 = 4;

/// The most the brightest corner of a cell may exceed the darkest, relative to it, for the
/// receivers inside to interpolate (see docs/render.md for the measure).
pub const CONTRAST: f32 = 0.3;

/// Normals within this cosine (18°) and tangent-plane offsets within this fraction of the
/// distance make a corner the same surface as the receiver.
const SAME_NORMAL: f32 = 0.95;
const SAME_PLANE: f32 = 0.1;

/// Which of a tile's receivers gather, and how the others are interpolated.
pub struct SparsePlan {
    /// Per receiver: its pixel's receiver is alone and diffuse (see the module docs).
    eligible: Vec<bool>,
    /// Per receiver: it gathers in the first pass (anchors and the ineligible).
    first: Vec<bool>,
    /// Per pixel of the tile (row-major within it): its eligible receiver, or `u32::MAX`.
    at: Vec<u32>,
    /// The tile's origin in the image, its size, and the image's width.
    origin: (u32, u32),
    size: (u32, u32),
    width: u32,
}

/// Image pixel `pixel`'s coordinates within the tile at `origin`, in an image `width` wide.
fn local(pixel: u32, origin: (u32, u32), width: u32) -> (u32, u32) {
    (pixel % width - origin.0, pixel / width - origin.1)
}

/// Whether tile-local coordinate `c` of a tile `n` pixels wide is on the anchor grid.
fn on_grid(c: u32, n: u32) -> bool {
    c.is_multiple_of(CELL) || c + 1 == n
}

/// The anchor coordinates around `c` (`c` itself off the grid): the grid line at or below,
/// and the next one above.
fn cell_of(c: u32, n: u32) -> (u32, u32) {
    let low = c - c % CELL;
    (low, (low + CELL).min(n - 1))
}

impl SparsePlan {
    /// The plan for the receivers of the tile at `origin` of `size` pixels, in an image
    /// `width` wide. With `sparse` false every receiver gathers.
    pub fn new(
        receivers: &[Receiver],
        origin: (u32, u32),
        size: (u32, u32),
        width: u32,
        sparse: bool,
    ) -> SparsePlan {
        // Each receiver's tile-local pixel, and its index in the tile.
        let cells: Vec<(u32, u32, usize)> = receivers
            .iter()
            .map(|r| {
                let (x, y) = local(r.pixel, origin, width);
                (x, y, (y * size.0 + x) as usize)
            })
            .collect();
        let mut count = vec![0u32; (size.0 * size.1) as usize];
        for &(_, _, i) in &cells {
            count[i] += 1;
        }
        let eligible: Vec<bool> = receivers
            .iter()
            .zip(&cells)
            .map(|(r, c)| sparse && matches!(r.bsdf, Bsdf::Diffuse(_)) && count[c.2] == 1)
            .collect();
        let mut at = vec![u32::MAX; count.len()];
        let first = cells
            .iter()
            .zip(&eligible)
            .enumerate()
            .map(|(k, (&(x, y, i), &e))| {
                if e {
                    at[i] = k as u32;
                }
                !e || (on_grid(x, size.0) && on_grid(y, size.1))
            })
            .collect();
        SparsePlan {
            eligible,
            first,
            at,
            origin,
            size,
            width,
        }
    }

    /// Whether receiver `k` gathers in the first pass (an anchor, or not eligible).
    pub fn gathers_first(&self, k: usize) -> bool {
        self.first[k]
    }

    /// Whether receiver `k` is eligible: its gather's value is its irradiance E.
    pub fn eligible(&self, k: usize) -> bool {
        self.eligible[k]
    }

    /// The irradiance of receiver `k` (not on the grid) from its cell's corners, given each
    /// anchor's (`value(j)` for receiver j), or `None` where it must gather.
    pub fn interpolate(
        &self,
        receivers: &[Receiver],
        k: usize,
        value: impl Fn(usize) -> Rgb,
    ) -> Option<Rgb> {
        let r = &receivers[k];
        let (x, y) = local(r.pixel, self.origin, self.width);
        let ((x0, x1), (y0, y1)) = (cell_of(x, self.size.0), cell_of(y, self.size.1));
        let fx = (x - x0) as f32 / (x1 - x0) as f32;
        let fy = (y - y0) as f32 / (y1 - y0) as f32;
        let corners = [
            ((x0, y0), (1.0 - fx) * (1.0 - fy)),
            ((x1, y0), fx * (1.0 - fy)),
            ((x0, y1), (1.0 - fx) * fy),
            ((x1, y1), fx * fy),
        ];
        // Every corner must be an anchor on the receiver's surface.
        let mut sum = Rgb::ZERO;
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        for ((cx, cy), w) in corners {
            let j = self.at[(cy * self.size.0 + cx) as usize];
            let c = receivers.get(j as usize)?;
            let offset = c.p - r.p;
            let same_surface = c.mesh == r.mesh
                && c.frame.n.dot(r.frame.n) >= SAME_NORMAL
                && r.frame.n.dot(offset).abs() <= SAME_PLANE * offset.length();
            if !same_surface {
                return None;
            }
            let e = value(j as usize);
            (lo, hi) = (lo.min(luminance(e)), hi.max(luminance(e)));
            sum += e * w;
        }
        (hi <= (1.0 + CONTRAST) * lo).then_some(sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::microfacet::{Distribution, Microfacet};
    use crate::bsdf::{Diffuse, RoughConductor};
    use crate::geometry::frame::Frame;
    use glam::Vec3;

    /// Receivers on the plane z = 0 (mesh 0), one per pixel of an 8 × 8 tile at the image's
    /// corner, pixel (x, y) at (x, y, 0) facing +z.
    fn plane() -> Vec<Receiver> {
        (0..64u32)
            .map(|pixel| Receiver {
                pixel,
                weight: Rgb::ONE,
                p: Vec3::new((pixel % 8) as f32, (pixel / 8) as f32, 0.0),
                err: Vec3::ZERO,
                ng: Vec3::Z,
                mesh: 0,
                frame: Frame::from_normal(Vec3::Z),
                bsdf: Bsdf::Diffuse(Diffuse {
                    reflectance: Rgb::splat(0.5),
                }),
                view: Vec3::Z,
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
        let plan = SparsePlan::new(&receivers, (0, 0), (8, 8), 8, true);
        let anchors: Vec<u32> = (0..64)
            .filter(|&k| plan.gathers_first(k as usize))
            .collect();
        let expected: Vec<u32> = (0..64)
            .filter(|k| [0, 4, 7].contains(&(k % 8)) && [0, 4, 7].contains(&(k / 8)))
            .collect();
        assert_eq!(anchors, expected);
        // E = 1 + 0.01 x + 0.02 y + 0.001 x y: bilinear, corners within 30 %.
        let e = |k: usize| {
            let (x, y) = ((k % 8) as f32, (k / 8) as f32);
            Rgb::splat(1.0 + 0.01 * x + 0.02 * y + 0.001 * x * y)
        };
        for k in (0..64).filter(|&k| !plan.gathers_first(k)) {
            let got = plan.interpolate(&receivers, k, e).expect("interpolates");
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
            SparsePlan::new(&r, (0, 0), (8, 8), 8, true).interpolate(&r, k, e)
        };
        assert!(changed(&|r| r.mesh = 1).is_none(), "another mesh");
        let turned = Frame::from_normal(Vec3::new(0.0, 0.4, 1.0).normalize());
        assert!(changed(&|r| r.frame = turned).is_none(), "a turned normal");
        assert!(changed(&|r| r.p.z = 0.5).is_none(), "a step off the plane");
        let bright = |j: usize| if j == corner { e(j) * 1.4 } else { e(j) };
        assert!(
            plan.interpolate(&receivers, k, bright).is_none(),
            "disagreeing corners"
        );
        // A conductor is not eligible: it gathers.
        let mut shiny = receivers.clone();
        shiny[k].bsdf = Bsdf::Conductor(RoughConductor {
            distr: Microfacet::new(Distribution::Ggx, 0.3, 0.3),
            eta: Rgb::ZERO,
            k: Rgb::ONE,
            specular_reflectance: Rgb::ONE,
        });
        assert!(SparsePlan::new(&shiny, (0, 0), (8, 8), 8, true).gathers_first(k));
        // Off, everyone gathers.
        let dense = SparsePlan::new(&receivers, (0, 0), (8, 8), 8, false);
        assert!((0..64).all(|k| dense.gathers_first(k)));
    }
}

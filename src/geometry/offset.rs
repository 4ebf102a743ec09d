//! Self-intersection-free ray origins.
//!
//! A hit point reconstructed from barycentrics carries a rounding error bounded by
//! `γ₇ · Σ|bᵢ pᵢ|` per component (Pharr, Jakob & Humphreys, pbrt-v4 §6.8). Moving the origin
//! along the geometric normal by the projection of that bound, then rounding away from the
//! surface, puts it provably on the intended side. The offset is proportional to the magnitude of
//! the coordinates, so it scales with the scene (1e-3 or 1e4 units alike) with no epsilon to tune.

use glam::Vec3A;

/// `γₙ = n ε / (1 − n ε)` with ε = 2⁻²⁴ (pbrt's bound for n rounded operations).
#[inline]
pub const fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5;
    (n as f32 * e) / (1.0 - n as f32 * e)
}

/// A point `Σ bᵢ pᵢ` and its absolute error bound.
#[inline]
pub fn interpolate_with_error(p: [Vec3A; 3], b: [f32; 3]) -> (Vec3A, Vec3A) {
    let a = p[0] * b[0];
    let c = p[1] * b[1];
    let d = p[2] * b[2];
    let point = a + c + d;
    let err = (a.abs() + c.abs() + d.abs()) * gamma(7);
    (point, err)
}

/// Next representable float towards +∞ (towards −∞ for [`next_down`]).
#[inline]
fn next_up(x: f32) -> f32 {
    if x.is_infinite() && x > 0.0 {
        return x;
    }
    let x = if x == -0.0 { 0.0 } else { x };
    let bits = x.to_bits();
    f32::from_bits(if x >= 0.0 { bits + 1 } else { bits - 1 })
}

#[inline]
fn next_down(x: f32) -> f32 {
    -next_up(-x)
}

/// Offset `p` (with error bound `err`) along the geometric normal `ng` to the side of `w`.
#[inline]
pub fn offset_origin(p: Vec3A, err: Vec3A, ng: Vec3A, w: Vec3A) -> Vec3A {
    let d = ng.abs().dot(err);
    let mut off = ng * d;
    if w.dot(ng) < 0.0 {
        off = -off;
    }
    let mut po = p + off;
    for i in 0..3 {
        if off[i] > 0.0 {
            po[i] = next_up(po[i]);
        } else if off[i] < 0.0 {
            po[i] = next_down(po[i]);
        }
    }
    po
}

/// Shadow segments stop this fraction short of their (offset) end point.
pub const SHADOW_EPSILON: f32 = 1e-4;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_moves_to_the_requested_side() {
        let n = Vec3A::Y;
        for scale in [1e-3_f32, 1.0, 1e4] {
            let p = Vec3A::new(0.3, 0.7, -0.2) * scale;
            let err = Vec3A::splat(gamma(7)) * p.abs();
            let up = offset_origin(p, err, n, Vec3A::Y);
            let down = offset_origin(p, err, n, -Vec3A::Y);
            assert!(up.y > p.y && down.y < p.y);
            // The offset is relative to the coordinates: a few ulps, not an absolute epsilon.
            assert!((up.y - p.y) / p.y.abs() < 1e-5);
        }
    }
}

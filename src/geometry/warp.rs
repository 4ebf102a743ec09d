//! Warps from the unit square to disks, hemispheres and triangles (Mitsuba's `warp` namespace).

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};

/// Shirley–Chiu concentric map with Cline's reduced branching, as in Mitsuba.
#[inline]
pub(crate) fn square_to_uniform_disk_concentric(u: Vec2) -> Vec2 {
    let x = 2.0 * u.x - 1.0;
    let y = 2.0 * u.y - 1.0;
    if x == 0.0 && y == 0.0 {
        return Vec2::ZERO;
    }
    let quadrant_1_or_3 = x.abs() < y.abs();
    let (r, rp) = if quadrant_1_or_3 { (y, x) } else { (x, y) };
    let (s, c) = sin_cos_quarter(FRAC_PI_4 * rp / r);
    // In quadrants 1 and 3 the angle is π/2 − φ, whose sine and cosine are φ's cosine and sine.
    let (s, c) = if quadrant_1_or_3 { (c, s) } else { (s, c) };
    Vec2::new(r * c, r * s)
}

/// sin x and cos x for |x| ≤ π/4, within 1.5 units in the last place of f32 (at most 0.73 and
/// 1.22 over a fine grid of the range): Cephes' `sinf` and `cosf` minimax polynomials for that
/// range, which needs no reduction. Inlined, where libm's `sincosf` is a call with its own
/// range reduction (2–3 % of a path tracer's time: every diffuse bounce draws one).
#[inline]
fn sin_cos_quarter(x: f32) -> (f32, f32) {
    let z = x * x;
    let sin = x + x * z * (-1.666_665_5e-1 + z * (8.332_161e-3 + z * -1.951_529_6e-4));
    let cos = 1.0 - 0.5 * z + z * z * (4.166_664_6e-2 + z * (-1.388_731_6e-3 + z * 2.443_315_7e-5));
    (sin, cos)
}

/// Inverse of [`square_to_uniform_disk_concentric`] (Shirley & Chiu, as Mitsuba's
/// `uniform_disk_to_square_concentric`). Each octant's angle is the arctangent of the smaller
/// coordinate over the larger, in [−1, 1], where `atan_unit` needs no range reduction (the
/// microbuffer looks up every splat here, and libm's `atan2` took 10 % of a render).
#[inline]
pub(crate) fn uniform_disk_to_square_concentric(p: Vec2) -> Vec2 {
    let r = p.length();
    let scale = r * (1.0 / FRAC_PI_4);
    let (a, b) = if p.x.abs() >= p.y.abs() {
        if p.x == 0.0 {
            return Vec2::splat(0.5);
        }
        let s = p.x.signum();
        (s * r, s * atan_unit(p.y / p.x) * scale)
    } else {
        let s = p.y.signum();
        (s * atan_unit(p.x / p.y) * scale, s * r)
    };
    Vec2::new(0.5 * (a + 1.0), 0.5 * (b + 1.0))
}

/// atan t for t in [−1, 1], within 2·10⁻⁸ (Abramowitz & Stegun 4.4.49), below f32's resolution.
/// The polynomial in t² is evaluated by Estrin's scheme (pairs, then pairs of pairs), whose
/// three dependent steps take a third of Horner's eight: the splats of a render wait on it.
#[inline]
fn atan_unit(t: f32) -> f32 {
    const A: [f32; 8] = [
        -0.333_331_45,
        0.199_935_51,
        -0.142_089,
        0.106_562_64,
        -0.075_289_64,
        0.042_909_614,
        -0.016_165_737,
        0.002_866_225_7,
    ];
    let t2 = t * t;
    let t4 = t2 * t2;
    let t8 = t4 * t4;
    let pair = |i: usize| A[i] + A[i + 1] * t2;
    let low = pair(0) + pair(2) * t4;
    let high = pair(4) + pair(6) * t4;
    let poly = low + high * t8;
    t + t * t2 * poly
}

/// The equal-area map from the unit square to the hemisphere around +z: the concentric disk,
/// then Lambert's azimuthal equal-area projection (z = 1 − r², (x, y) scaled by √(2 − r²)).
/// Every cell of an n × n grid subtends 2π/n² steradians (docs/design.md §5.3).
#[inline]
pub fn square_to_hemisphere_equal_area(u: Vec2) -> Vec3 {
    let p = square_to_uniform_disk_concentric(u);
    let r2 = p.length_squared().min(1.0);
    let s = (2.0 - r2).sqrt();
    Vec3::new(p.x * s, p.y * s, 1.0 - r2)
}

/// Inverse of [`square_to_hemisphere_equal_area`] for a unit `v` with `v.z ≥ 0`.
#[inline]
pub fn hemisphere_equal_area_to_square(v: Vec3) -> Vec2 {
    // r² = 1 − z and (x, y) = p √(1 + z), so p = (x, y) / √(1 + z).
    let p = Vec2::new(v.x, v.y) / (1.0 + v.z.max(0.0)).sqrt();
    uniform_disk_to_square_concentric(p)
}

/// Uniform direction on the sphere (Archimedes: z uniform in [−1, 1]).
#[inline]
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.y;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (std::f32::consts::TAU * u.x).sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// Cosine-weighted hemisphere around +z.
#[inline]
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let p = square_to_uniform_disk_concentric(u);
    let z = (1.0 - p.length_squared()).max(0.0).sqrt();
    Vec3::new(p.x, p.y, z)
}

/// Density of [`square_to_cosine_hemisphere`] per unit solid angle.
#[inline]
pub(crate) fn square_to_cosine_hemisphere_pdf(v: Vec3) -> f32 {
    FRAC_1_PI * v.z
}

/// Uniform barycentric coordinates `(b1, b2)` on a triangle (Heitz's low-distortion map).
#[inline]
pub(crate) fn square_to_uniform_triangle(u: Vec2) -> Vec2 {
    if u.y > u.x {
        let b0 = u.x * 0.5;
        let b1 = u.y - b0;
        Vec2::new(b0, b1)
    } else {
        let b1 = u.y * 0.5;
        let b0 = u.x - b1;
        Vec2::new(b0, b1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn concentric_map_matches_mitsuba_rows() {
        // Mitsuba's diffuse sample() at u = (0.25, 0.75) gives wo = (-0.35355338, 0.35355341, ·).
        let p = square_to_uniform_disk_concentric(Vec2::new(0.25, 0.75));
        assert!((p.x + 0.353_553_38).abs() < 1e-7 && (p.y - 0.353_553_4).abs() < 1e-7);
    }

    #[test]
    fn quarter_sin_cos_is_within_one_and_a_half_ulps() {
        // Every 2^-16 of the range, and its ends; against f64 (the error of the result's
        // rounding included), in units of the f32 spacing in the exact value's binade (just
        // below a power of two, the finer spacing below it, not the one above).
        let ulps = |got: f32, exact: f64| {
            if exact == 0.0 {
                return f64::from(got).abs() / f64::from(f32::MIN_POSITIVE);
            }
            let spacing = 2f64.powi(exact.abs().log2().floor() as i32 - 23);
            (f64::from(got) - exact).abs() / spacing
        };
        let n = 1 << 16;
        for i in -n..=n {
            let x = i as f32 / n as f32 * std::f32::consts::FRAC_PI_4;
            let (s, c) = sin_cos_quarter(x);
            let (es, ec) = f64::from(x).sin_cos();
            assert!(ulps(s, es) <= 1.5, "sin {x}: {s} against {es}");
            assert!(ulps(c, ec) <= 1.5, "cos {x}: {c} against {ec}");
        }
    }

    #[test]
    fn atan_unit_is_exact_to_f32() {
        for i in -1000..=1000 {
            let t = i as f32 / 1000.0;
            let err = (atan_unit(t) as f64 - (t as f64).atan()).abs();
            assert!(err < 1.2e-7, "t = {t}: error {err:e}");
        }
    }

    #[test]
    fn concentric_inverse_round_trips() {
        // A 64 × 64 grid of points of the square, including its edges, diagonals and centre.
        for i in 0..=64 {
            for j in 0..=64 {
                let u = Vec2::new(i as f32, j as f32) / 64.0;
                let back = uniform_disk_to_square_concentric(square_to_uniform_disk_concentric(u));
                assert!((back - u).abs().max_element() < 2e-6, "{u} -> {back}");
                let h = hemisphere_equal_area_to_square(square_to_hemisphere_equal_area(u));
                assert!((h - u).abs().max_element() < 1e-5, "{u} -> {h}");
            }
        }
    }

    #[test]
    fn triangle_warp_stays_inside() {
        for i in 0..32 {
            for j in 0..32 {
                let b = square_to_uniform_triangle(Vec2::new(i as f32 / 31.0, j as f32 / 31.0));
                assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
            }
        }
    }
}

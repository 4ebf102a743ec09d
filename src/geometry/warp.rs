//! Warps from the unit square to disks, hemispheres and triangles (Mitsuba's `warp` namespace).

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4};

/// Shirley–Chiu concentric map with Cline's reduced branching, as in Mitsuba.
#[inline]
pub fn square_to_uniform_disk_concentric(u: Vec2) -> Vec2 {
    let x = 2.0 * u.x - 1.0;
    let y = 2.0 * u.y - 1.0;
    if x == 0.0 && y == 0.0 {
        return Vec2::ZERO;
    }
    let quadrant_1_or_3 = x.abs() < y.abs();
    let (r, rp) = if quadrant_1_or_3 { (y, x) } else { (x, y) };
    let mut phi = FRAC_PI_4 * rp / r;
    if quadrant_1_or_3 {
        phi = FRAC_PI_2 - phi;
    }
    let (s, c) = phi.sin_cos();
    Vec2::new(r * c, r * s)
}

/// Inverse of [`square_to_uniform_disk_concentric`] (Shirley & Chiu, as Mitsuba's
/// `uniform_disk_to_square_concentric`).
#[inline]
pub fn uniform_disk_to_square_concentric(p: Vec2) -> Vec2 {
    use std::f32::consts::PI;
    let r = p.length();
    let mut phi = p.y.atan2(p.x);
    if phi < -FRAC_PI_4 {
        phi += 2.0 * PI;
    }
    let (a, b) = if phi < FRAC_PI_4 {
        (r, phi * r / FRAC_PI_4)
    } else if phi < 3.0 * FRAC_PI_4 {
        (-(phi - FRAC_PI_2) * r / FRAC_PI_4, r)
    } else if phi < 5.0 * FRAC_PI_4 {
        (-r, -(phi - PI) * r / FRAC_PI_4)
    } else {
        ((phi - 3.0 * FRAC_PI_2) * r / FRAC_PI_4, -r)
    };
    Vec2::new(0.5 * (a + 1.0), 0.5 * (b + 1.0))
}

/// The equal-area map from the unit square to the hemisphere around +z: the concentric disk,
/// then Lambert's azimuthal equal-area projection (z = 1 − r², (x, y) scaled by √(2 − r²)).
/// Every cell of an n × n grid subtends 2π/n² steradians (DESIGN.md §5.3).
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
pub fn square_to_cosine_hemisphere_pdf(v: Vec3) -> f32 {
    FRAC_1_PI * v.z
}

/// Uniform barycentric coordinates `(b1, b2)` on a triangle (Heitz's low-distortion map).
#[inline]
pub fn square_to_uniform_triangle(u: Vec2) -> Vec2 {
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
    fn triangle_warp_stays_inside() {
        for i in 0..32 {
            for j in 0..32 {
                let b = square_to_uniform_triangle(Vec2::new(i as f32 / 31.0, j as f32 / 31.0));
                assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
            }
        }
    }
}

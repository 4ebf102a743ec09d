//! The equal-area octahedral map between the unit sphere and the unit square (Clarberg, "Fast
//! Equal-Area Mapping of the (Hemi)Sphere using SIMD", JGT 2008), docs/design.md §5.3.
//!
//! The upper hemisphere fills the inner diamond |u| + |v| ≤ 1 of [−1, 1]², the lower one the four
//! corner triangles, folded across the diamond's edges. The Jacobian is constant, so every texel
//! of an N × N grid over the square subtends exactly 4π / N² steradians: one wavelet threshold
//! means the same thing in every direction. Computed in f64, so that texel lookups are exact to
//! the f32 precision of the directions.

use glam::{DVec2, DVec3, Vec2, Vec3};
use std::f64::consts::FRAC_PI_4;
use std::sync::OnceLock;

/// The point of [0, 1]² for the unit direction `w` (any length > 0 is accepted).
pub fn direction_to_square(w: Vec3) -> Vec2 {
    let w = w.as_dvec3().normalize();
    let (ax, ay) = (w.x.abs(), w.y.abs());
    // r = √(1 − |z|), computed without cancellation as (x² + y²) / (1 + |z|) under the root.
    let r = ((ax * ax + ay * ay) / (1.0 + w.z.abs())).sqrt();
    // φ/(π/2) in [0, 1]: the position along the diamond edge.
    let t = if ax == 0.0 && ay == 0.0 {
        0.0
    } else {
        ay.atan2(ax) / (2.0 * FRAC_PI_4)
    };
    let v = t * r;
    let u = r - v;
    let (u, v) = if w.z < 0.0 {
        (1.0 - v, 1.0 - u)
    } else {
        (u, v)
    };
    let p = DVec2::new(u.copysign(w.x), v.copysign(w.y));
    ((p + 1.0) * 0.5).as_vec2()
}

/// The unit direction of the point `p` of [0, 1]² (inverse of [`direction_to_square`]).
pub fn square_to_direction(p: Vec2) -> Vec3 {
    square_to_direction_f64(p.as_dvec2()).as_vec3()
}

/// [`square_to_direction`] in double precision (for texel integration and tests).
pub fn square_to_direction_f64(p: DVec2) -> DVec3 {
    let q = p * 2.0 - 1.0;
    let (au, av) = (q.x.abs(), q.y.abs());
    let d = 1.0 - (au + av);
    let r = 1.0 - d.abs();
    let phi = if r == 0.0 {
        FRAC_PI_4
    } else {
        ((av - au) / r + 1.0) * FRAC_PI_4
    };
    let z = (1.0 - r * r).copysign(d);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    let (sin, cos) = phi.sin_cos();
    DVec3::new((cos * s).copysign(q.x), (sin * s).copysign(q.y), z)
}

/// The centre of texel `t` (row-major) of an `n × n` grid over the unit square.
#[inline]
pub fn texel_centre(t: u32, n: u32) -> Vec2 {
    Vec2::new((t % n) as f32 + 0.5, (t / n) as f32 + 0.5) / n as f32
}

/// Finest map resolution with a shared direction table.
pub(crate) const MAX_TABLE_LEVELS: u32 = 10;

/// The directions of the texel centres of the `2^levels × 2^levels` map (row-major), computed
/// once per resolution and shared: every surfel of a bake needs the same ones.
pub fn texel_directions(levels: u32) -> &'static [Vec3] {
    static TABLES: [OnceLock<Vec<Vec3>>; MAX_TABLE_LEVELS as usize + 1] =
        [const { OnceLock::new() }; MAX_TABLE_LEVELS as usize + 1];
    assert!(
        levels <= MAX_TABLE_LEVELS,
        "map resolution 2^{levels} is beyond the tables"
    );
    TABLES[levels as usize].get_or_init(|| {
        let n = 1u32 << levels;
        (0..n * n)
            .map(|t| square_to_direction(texel_centre(t, n)))
            .collect()
    })
}

/// The texel `(x, y)` of an `n × n` grid that holds direction `w`.
pub fn texel_of(w: Vec3, n: u32) -> (u32, u32) {
    texel_at(direction_to_square(w), n)
}

/// The texel `(x, y)` of an `n × n` grid that holds point `p` of the unit square: the one a
/// Haar map's evaluation at `p` reads.
#[inline]
pub fn texel_at(p: Vec2, n: u32) -> (u32, u32) {
    let cell = |c: f32| ((c * n as f32) as u32).min(n - 1);
    (cell(p.x), cell(p.y))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poles_and_axes() {
        let close = |a: Vec2, b: Vec2| (a - b).length() < 1e-6;
        assert!(close(direction_to_square(Vec3::Z), Vec2::splat(0.5)));
        assert!(close(direction_to_square(Vec3::X), Vec2::new(1.0, 0.5)));
        assert!(close(direction_to_square(Vec3::Y), Vec2::new(0.5, 1.0)));
        // The south pole is every corner; −z lands on one of them.
        let s = direction_to_square(-Vec3::Z);
        assert!(s.x.fract() == 0.0 && s.y.fract() == 0.0);
    }
}

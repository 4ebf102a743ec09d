//! Lambert's closed form for the light a triangle of constant radiance sends onto a point:
//! its projected solid angle, ∫ max(0, n·ω) dω over the directions it covers, so that the
//! irradiance it gives is L times that. The final render's direct light on diffuse surfaces
//! uses it as the unshadowed value its shadow rays scale (`render::primary`).

use glam::{DVec3, Vec3};

/// The projected solid angle of triangle `v` seen from `p` under the unit normal `n`: the
/// part of the triangle below `p`'s horizon is clipped away, then Lambert's formula
/// ½ |Σ Θᵢ n·γ̂ᵢ| sums over the polygon's edges, Θᵢ the angle an edge subtends and γ̂ᵢ the
/// unit normal of the plane through it and `p`. In double precision, with each angle an
/// atan2 (accurate for the tiny angles of a far light, where an acos of a cosine near 1 is
/// not). Zero for a triangle wholly below the horizon or seen edge-on.
pub fn projected_solid_angle(p: Vec3, n: Vec3, v: [Vec3; 3]) -> f32 {
    let n = n.as_dvec3();
    let corners = v.map(|q| (q - p).as_dvec3());
    // Sutherland–Hodgman against the plane n·x = 0: at most one more corner than it had.
    let mut clipped = [DVec3::ZERO; 4];
    let mut len = 0;
    for i in 0..3 {
        let (a, b) = (corners[i], corners[(i + 1) % 3]);
        let (ha, hb) = (n.dot(a), n.dot(b));
        if ha >= 0.0 {
            clipped[len] = a;
            len += 1;
        }
        if (ha >= 0.0) != (hb >= 0.0) {
            clipped[len] = a + (b - a) * (ha / (ha - hb));
            len += 1;
        }
    }
    if len < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for i in 0..len {
        let (a, b) = (clipped[i], clipped[(i + 1) % len]);
        let c = a.cross(b);
        let sin = c.length();
        if sin > 0.0 {
            sum += sin.atan2(a.dot(b)) * n.dot(c) / sin;
        }
    }
    (0.5 * sum.abs()) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    /// A triangle covering the hemisphere's quarter (the octant's face, seen from its corner)
    /// projects to a quarter of the disc, π/4; a small far one to area·cos·cos/d²; one half
    /// below the horizon to the half above it; one wholly below to zero.
    #[test]
    fn closed_forms() {
        let octant = [Vec3::X, Vec3::Y, Vec3::Z];
        assert!((projected_solid_angle(Vec3::ZERO, Vec3::Z, octant) - PI / 4.0).abs() < 1e-6);
        let (d, s) = (100.0, 0.01);
        let far = [
            Vec3::new(0.0, 0.0, d),
            Vec3::new(s, 0.0, d),
            Vec3::new(0.0, s, d),
        ];
        let expected = 0.5 * s * s / (d * d);
        let got = projected_solid_angle(Vec3::ZERO, Vec3::Z, far);
        assert!((got / expected - 1.0).abs() < 1e-5, "{got} vs {expected}");
        // The square [−1, 1]² at height 1, as two triangles, over a receiver at its centre's
        // foot: four corner-aligned unit rectangles, each (1/√2) atan(1/√2) (the rectangle's
        // form factor times π).
        let square = [
            [
                Vec3::new(-1.0, -1.0, 1.0),
                Vec3::new(1.0, -1.0, 1.0),
                Vec3::new(1.0, 1.0, 1.0),
            ],
            [
                Vec3::new(-1.0, -1.0, 1.0),
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(-1.0, 1.0, 1.0),
            ],
        ];
        let whole: f32 = square
            .iter()
            .map(|t| projected_solid_angle(Vec3::ZERO, Vec3::Z, *t))
            .sum();
        let exact = 4.0 * (1.0f32 / 2f32.sqrt()).atan() / 2f32.sqrt();
        assert!((whole - exact).abs() < 1e-5, "{whole} vs {exact}");
        let below = [
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 1.0, -1.0),
        ];
        assert_eq!(projected_solid_angle(Vec3::ZERO, Vec3::Z, below), 0.0);
        // A receiver facing +x has its horizon through the square's middle: the clipped
        // square is its half x ≥ 0, which lies wholly above that horizon.
        let tilted = Vec3::new(1.0, 0.0, 0.0);
        let half: f32 = square
            .iter()
            .map(|t| projected_solid_angle(Vec3::ZERO, tilted, *t))
            .sum();
        let right = [
            [
                Vec3::new(0.0, -1.0, 1.0),
                Vec3::new(1.0, -1.0, 1.0),
                Vec3::new(1.0, 1.0, 1.0),
            ],
            [
                Vec3::new(0.0, -1.0, 1.0),
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(0.0, 1.0, 1.0),
            ],
        ];
        let unclipped: f32 = right
            .iter()
            .map(|t| projected_solid_angle(Vec3::ZERO, tilted, *t))
            .sum();
        assert!((half - unclipped).abs() < 1e-6, "{half} vs {unclipped}");
        assert!(half > 0.0);
    }
}

//! Orthonormal shading frames.
//!
//! Local coordinates follow Mitsuba: `x` is the tangent (the `alpha_u` axis of an anisotropic
//! BSDF), `y` the bitangent and `z` the shading normal, so `cos θ = v.z`.

use glam::Vec3;

/// An orthonormal basis `(s, t, n)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Tangent.
    pub s: Vec3,
    /// Bitangent.
    pub t: Vec3,
    /// Normal.
    pub n: Vec3,
}

impl Frame {
    /// A frame around the unit normal `n`, tangent chosen by the branchless construction of
    /// Duff et al., "Building an Orthonormal Basis, Revisited" (JCGT 2017), as Mitsuba does.
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0_f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    #[inline]
    /// `v` in the frame's coordinates (world to local).
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    #[inline]
    /// `v` from the frame's coordinates (local to world).
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// `(sin φ, cos φ)` of a local direction; `(0, 1)` on the pole, as in Mitsuba's `Frame3f::sincos_phi`.
#[inline]
pub(crate) fn sincos_phi(v: Vec3) -> (f32, f32) {
    let sin_theta_2 = v.x * v.x + v.y * v.y;
    if sin_theta_2 <= 4.0 * f32::EPSILON * 0.5 {
        return (0.0, 1.0);
    }
    let inv = 1.0 / sin_theta_2.sqrt();
    ((v.y * inv).clamp(-1.0, 1.0), (v.x * inv).clamp(-1.0, 1.0))
}

/// Mirror `wi` about `m`: `2 (wi·m) m − wi`.
#[inline]
pub fn reflect(wi: Vec3, m: Vec3) -> Vec3 {
    m * (2.0 * wi.dot(m)) - wi
}

/// Refract `wi` through the microfacet normal `m` (Mitsuba's convention: `cos_theta_t` already
/// carries the sign of the far side, `eta_ti` is the relative index seen from the far side).
#[inline]
pub fn refract(wi: Vec3, m: Vec3, cos_theta_t: f32, eta_ti: f32) -> Vec3 {
    m * (wi.dot(m) * eta_ti + cos_theta_t) - wi * eta_ti
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_orthonormal() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
            Vec3::new(1e-8, 0.0, -1.0).normalize(),
        ] {
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-6);
            assert!((f.t.length() - 1.0).abs() < 1e-6);
            assert!(f.s.dot(f.t).abs() < 1e-6 && f.s.dot(n).abs() < 1e-6);
            assert!((f.s.cross(f.t) - n).length() < 1e-5, "right-handed");
            let v = Vec3::new(0.2, 0.5, -0.7);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-6);
        }
    }
}

//! Fresnel equations for dielectrics and conductors (unpolarised), as in Mitsuba 3's `fresnel.h`.

use crate::geometry::special::{mulsign, safe_sqrt};
use crate::spectrum::Rgb;

/// Result of the dielectric Fresnel equations at one microfacet.
#[derive(Clone, Copy, Debug)]
pub struct DielectricFresnel {
    /// Reflectance F.
    pub r: f32,
    /// Cosine of the transmitted direction, with the sign of the far side.
    pub cos_theta_t: f32,
    /// Relative index from the incident side (`eta` outside, `1/eta` inside).
    pub eta_it: f32,
    /// Its reciprocal.
    pub eta_ti: f32,
}

/// Dielectric Fresnel reflectance for relative index `eta` (interior over exterior).
/// `cos_theta_i < 0` means the incident direction is inside.
pub fn fresnel_dielectric(cos_theta_i: f32, eta: f32) -> DielectricFresnel {
    let outside = cos_theta_i >= 0.0;
    let rcp_eta = 1.0 / eta;
    let (eta_it, eta_ti) = if outside {
        (eta, rcp_eta)
    } else {
        (rcp_eta, eta)
    };
    // Snell's law: cos² of the transmitted angle.
    let cos_theta_t_sqr = 1.0 - (1.0 - cos_theta_i * cos_theta_i) * (eta_ti * eta_ti);
    let cos_i = cos_theta_i.abs();
    let cos_t = safe_sqrt(cos_theta_t_sqr);
    let index_matched = eta == 1.0;
    let r = if index_matched {
        0.0
    } else if cos_i == 0.0 {
        1.0
    } else {
        let a_s = (cos_i - eta_it * cos_t) / (cos_i + eta_it * cos_t);
        let a_p = (cos_t - eta_it * cos_i) / (cos_t + eta_it * cos_i);
        0.5 * (a_s * a_s + a_p * a_p)
    };
    DielectricFresnel {
        r,
        cos_theta_t: -mulsign(cos_t, cos_theta_i),
        eta_it,
        eta_ti,
    }
}

/// Conductor Fresnel reflectance for the complex index `eta + i k` (per channel), after
/// K. D. Moeller, "Optics" (1988), as in Mitsuba. `eta = 0, k = 1` gives exactly 1.
#[inline(always)]
pub(crate) fn fresnel_conductor(cos_theta_i: f32, eta: Rgb, k: Rgb) -> Rgb {
    let ch = |eta_r: f32, eta_i: f32| -> f32 {
        let cos2 = cos_theta_i * cos_theta_i;
        let sin2 = 1.0 - cos2;
        let sin4 = sin2 * sin2;
        let temp_1 = eta_r * eta_r - eta_i * eta_i - sin2;
        let a_2_pb_2 = safe_sqrt(temp_1 * temp_1 + 4.0 * eta_i * eta_i * eta_r * eta_r);
        let a = safe_sqrt(0.5 * (a_2_pb_2 + temp_1));
        let term_1 = a_2_pb_2 + cos2;
        let term_2 = 2.0 * cos_theta_i * a;
        let r_s = (term_1 - term_2) / (term_1 + term_2);
        let term_3 = a_2_pb_2 * cos2 + sin4;
        let term_4 = term_2 * sin2;
        let r_p = r_s * (term_3 - term_4) / (term_3 + term_4);
        0.5 * (r_s + r_p)
    };
    Rgb::new(ch(eta.x, k.x), ch(eta.y, k.y), ch(eta.z, k.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_normal_incidence_is_schlick_r0() {
        let f = fresnel_dielectric(1.0, 1.5);
        assert!((f.r - 0.04).abs() < 1e-6);
        assert!((f.cos_theta_t + 1.0).abs() < 1e-6);
    }

    #[test]
    fn total_internal_reflection() {
        // Inside glass at 60 degrees: sin = 0.866 > 1/1.5.
        let f = fresnel_dielectric(-0.5, 1.5);
        assert_eq!(f.r, 1.0);
    }

    #[test]
    fn perfect_mirror_conductor() {
        let f = fresnel_conductor(0.3, Rgb::ZERO, Rgb::ONE);
        assert_eq!(f, Rgb::ONE);
    }
}

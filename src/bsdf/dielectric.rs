//! Mitsuba's `roughdielectric`: microfacet reflection and refraction through a rough interface
//! (Walter et al. 2007), two-sided, with lobe selection by the Fresnel reflectance.

use super::fresnel::fresnel_dielectric;
use super::microfacet::{Distribution, Microfacet};
use super::sample::{BsdfSample, Lobe, TransportMode};
use crate::geometry::frame::{reflect, refract};
use crate::spectrum::Rgb;
use glam::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
/// Mitsuba's `roughdielectric`: a microfacet interface between two indices of refraction.
pub struct RoughDielectric {
    /// The microfacet distribution.
    pub distr: Microfacet,
    /// Relative index `int_ior / ext_ior`.
    pub eta: f32,
    /// Multiplies the reflected part (Mitsuba's `specular_reflectance`).
    pub specular_reflectance: Rgb,
    /// Multiplies the transmitted part (Mitsuba's `specular_transmittance`).
    pub specular_transmittance: Rgb,
}

impl RoughDielectric {
    /// The half vector of `(wi, wo)` on the side of the macro normal, and the relative index
    /// seen from `wi`'s side. `None` for directions in the tangent plane.
    fn half_vector(&self, wi: Vec3, wo: Vec3) -> (Vec3, bool, f32) {
        let reflect = wi.z * wo.z > 0.0;
        let eta = if wi.z > 0.0 { self.eta } else { 1.0 / self.eta };
        let m = (wi + wo * if reflect { 1.0 } else { eta }).normalize();
        let m = if m.z.is_sign_negative() { -m } else { m };
        (m, reflect, eta)
    }

    /// `f(wi, wo) · |cos θo|` in the local frame, radiance or importance (see [`super::Bsdf::eval`]).
    pub fn eval(&self, wi: Vec3, wo: Vec3, mode: TransportMode) -> Rgb {
        let (m, reflect, eta) = self.half_vector(wi, wo);
        let d = self.distr.eval(m);
        let f = fresnel_dielectric(wi.dot(m), self.eta).r;
        let g = self.distr.g(wi, wo, m);
        let value = if reflect {
            self.specular_reflectance * (f * d * g / (4.0 * wi.z.abs()))
        } else {
            // Radiance is compressed by (1/eta)² when it crosses into the denser medium.
            let scale = match mode {
                TransportMode::Radiance => 1.0 / (eta * eta),
                TransportMode::Importance => 1.0,
            };
            let denom = wi.dot(m) + eta * wo.dot(m);
            let v = (scale * (1.0 - f) * d * g * eta * eta * wi.dot(m) * wo.dot(m))
                / (wi.z * denom * denom);
            self.specular_transmittance * v.abs()
        };
        if value.is_finite() {
            value
        } else {
            Rgb::ZERO
        }
    }

    /// [`RoughDielectric::eval`] from `wi` towards every direction of `wo` (lanes of x, y
    /// and z), into `out`: see [`crate::bsdf::Bsdf::eval_lanes`]. GGX only.
    pub(super) fn eval_lanes(
        &self,
        wi: Vec3,
        [xs, ys, zs]: [&[f32]; 3],
        mode: TransportMode,
        out: &mut [Rgb],
    ) {
        debug_assert_eq!(self.distr.kind, Distribution::Ggx);
        let eta_side = if wi.z > 0.0 { self.eta } else { 1.0 / self.eta };
        let cos_scale = 4.0 * wi.z.abs();
        let radiance_scale = match mode {
            TransportMode::Radiance => 1.0 / (eta_side * eta_side),
            TransportMode::Importance => 1.0,
        };
        let lanes = xs.iter().zip(ys).zip(zs).zip(out.iter_mut());
        for (((&ox, &oy), &oz), out) in lanes {
            // The half vector on the side of the macro normal.
            let reflect = wi.z * oz > 0.0;
            let along = if reflect { 1.0 } else { eta_side };
            let (hx, hy, hz) = (wi.x + ox * along, wi.y + oy * along, wi.z + oz * along);
            let recip = 1.0 / (hx * hx + hy * hy + hz * hz).sqrt();
            let flip = if (hz * recip).is_sign_negative() {
                -1.0
            } else {
                1.0
            };
            let (mx, my, mz) = (hx * recip * flip, hy * recip * flip, hz * recip * flip);
            let d = self.distr.ggx_d(mx, my, mz);
            // Fresnel reflectance at wi·m.
            let wi_m = wi.x * mx + wi.y * my + wi.z * mz;
            let f = fresnel_dielectric(wi_m, self.eta).r;
            let wo_m = ox * mx + oy * my + oz * mz;
            let g = self.distr.ggx_smith_g1(wi.to_array(), wi_m)
                * self.distr.ggx_smith_g1([ox, oy, oz], wo_m);
            let reflected = f * d * g / cos_scale;
            let denom = wi_m + eta_side * wo_m;
            let transmitted =
                (radiance_scale * (1.0 - f) * d * g * eta_side * eta_side * wi_m * wo_m)
                    / (wi.z * denom * denom);
            let value = if reflect {
                self.specular_reflectance * reflected
            } else {
                self.specular_transmittance * transmitted.abs()
            };
            *out = if value.is_finite() { value } else { Rgb::ZERO };
        }
    }

    /// Solid-angle density of `sample` producing `wo`.
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        let (m, reflect, eta) = self.half_vector(wi, wo);
        // The sides of micro- and macrosurface must agree (the same rule as in smith_g1).
        if !(wi.dot(m) * wi.z > 0.0 && wo.dot(m) * wo.z > 0.0) {
            return 0.0;
        }
        let dwh_dwo = if reflect {
            1.0 / (4.0 * wo.dot(m))
        } else {
            let denom = wi.dot(m) + eta * wo.dot(m);
            (eta * eta * wo.dot(m)) / (denom * denom)
        };
        let wi_up = if wi.z.is_sign_negative() { -wi } else { wi };
        let f = fresnel_dielectric(wi.dot(m), self.eta).r;
        let prob = self.distr.pdf(wi_up, m) * if reflect { f } else { 1.0 - f };
        let p = prob * dwh_dwo.abs();
        if p.is_finite() {
            p
        } else {
            0.0
        }
    }

    /// `u0` chooses the lobe (reflection iff `u0 <= F`), `u` drives the microfacet sampler.
    pub fn sample(&self, wi: Vec3, u0: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let cos_theta_i = wi.z;
        let wi_up = if cos_theta_i.is_sign_negative() {
            -wi
        } else {
            wi
        };
        let (m, pdf_m) = self.distr.sample(wi_up, u);
        let fr = fresnel_dielectric(wi.dot(m), self.eta);
        let f = fr.r;
        let selected_r = u0 <= f;
        let (wo, eta, lobe, mut weight, pdf_lobe, dwh_dwo);
        if selected_r {
            wo = reflect(wi, m);
            if !(cos_theta_i * wo.z > 0.0) {
                return None;
            }
            eta = 1.0;
            lobe = Lobe::Reflection;
            weight = self.specular_reflectance;
            pdf_lobe = f;
            dwh_dwo = 1.0 / (4.0 * wo.dot(m));
        } else {
            wo = refract(wi, m, fr.cos_theta_t, fr.eta_ti);
            if !(cos_theta_i * wo.z < 0.0) {
                return None;
            }
            eta = fr.eta_it;
            lobe = Lobe::Transmission;
            let factor = match mode {
                TransportMode::Radiance => fr.eta_ti,
                TransportMode::Importance => 1.0,
            };
            weight = self.specular_transmittance * (factor * factor);
            pdf_lobe = 1.0 - f;
            let denom = wi.dot(m) + eta * wo.dot(m);
            dwh_dwo = (eta * eta * wo.dot(m)) / (denom * denom);
        }
        weight *= self.distr.smith_g1(wo, m);
        let pdf = pdf_m * pdf_lobe * dwh_dwo.abs();
        if !(pdf > 0.0 && pdf.is_finite() && weight.is_finite()) {
            return None;
        }
        Some(BsdfSample {
            wo,
            pdf,
            eta,
            lobe,
            weight,
        })
    }
}

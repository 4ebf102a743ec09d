//! Mitsuba's `roughconductor`: one-sided microfacet reflection with the complex-index Fresnel term.

use super::fresnel::fresnel_conductor;
use super::microfacet::{Distribution, Microfacet};
use super::sample::{BsdfSample, Lobe};
use crate::geometry::frame::reflect;
use crate::spectrum::Rgb;
use glam::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
/// Mitsuba's `roughconductor`: a microfacet conductor with a complex index of refraction.
pub struct RoughConductor {
    /// The microfacet distribution.
    pub distr: Microfacet,
    /// Real part of the complex index of refraction, per channel.
    pub eta: Rgb,
    /// Imaginary part (extinction), per channel.
    pub k: Rgb,
    /// Multiplies the Fresnel reflectance (Mitsuba's `specular_reflectance`, 1 for physical conductors).
    pub specular_reflectance: Rgb,
}

impl RoughConductor {
    #[inline(always)]
    fn fresnel(&self, cos_theta: f32) -> Rgb {
        fresnel_conductor(cos_theta, self.eta, self.k) * self.specular_reflectance
    }

    /// `f(wi, wo) · |cos θo|` in the local frame (see [`super::Bsdf::eval`]).
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return Rgb::ZERO;
        }
        let h = (wo + wi).normalize();
        let d = self.distr.eval(h);
        if d == 0.0 {
            return Rgb::ZERO;
        }
        let g = self.distr.g(wi, wo, h);
        // f·cos θo = D G F / (4 cos θi): the cos θo of the BRDF cancels the foreshortening.
        self.fresnel(wi.dot(h)) * (d * g / (4.0 * wi.z))
    }

    /// [`RoughConductor::eval`] from `wi` towards every direction of `wo` (lanes of x, y and
    /// z), into `out`: see [`crate::bsdf::Bsdf::eval_lanes`]. GGX only.
    pub(super) fn eval_lanes(&self, wi: Vec3, [xs, ys, zs]: [&[f32]; 3], out: &mut [Rgb]) {
        debug_assert_eq!(self.distr.kind, Distribution::Ggx);
        if !(wi.z > 0.0) {
            out.fill(Rgb::ZERO);
            return;
        }
        let cos_scale = 4.0 * wi.z;
        let lanes = xs.iter().zip(ys).zip(zs).zip(out.iter_mut());
        for (((&ox, &oy), &oz), out) in lanes {
            let (hx, hy, hz) = (ox + wi.x, oy + wi.y, oz + wi.z);
            let recip = 1.0 / (hx * hx + hy * hy + hz * hz).sqrt();
            let (mx, my, mz) = (hx * recip, hy * recip, hz * recip);
            let d = self.distr.ggx_d(mx, my, mz);
            let wi_m = wi.x * mx + wi.y * my + wi.z * mz;
            let wo_m = ox * mx + oy * my + oz * mz;
            let g = self.distr.ggx_smith_g1(wi.to_array(), wi_m)
                * self.distr.ggx_smith_g1([ox, oy, oz], wo_m);
            let value = self.fresnel(wi_m) * (d * g / cos_scale);
            *out = if oz > 0.0 && d != 0.0 {
                value
            } else {
                Rgb::ZERO
            };
        }
    }

    /// Solid-angle density of [`RoughConductor::sample`] producing `wo`.
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        let m = (wo + wi).normalize();
        if !(wi.z > 0.0 && wo.z > 0.0 && wi.dot(m) > 0.0 && wo.dot(m) > 0.0) {
            return 0.0;
        }
        self.distr.eval(m) * self.distr.smith_g1(wi, m) / (4.0 * wi.z)
    }

    /// Sample `wo` by the distribution of visible normals; `None` when it falls below the horizon.
    pub fn sample(&self, wi: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let (m, pdf_m) = self.distr.sample(wi, u);
        let wo = reflect(wi, m);
        if !(pdf_m != 0.0 && wo.z > 0.0) {
            return None;
        }
        let weight = self.fresnel(wi.dot(m)) * self.distr.smith_g1(wo, m);
        Some(BsdfSample {
            wo,
            pdf: pdf_m / (4.0 * wo.dot(m)),
            eta: 1.0,
            lobe: Lobe::Reflection,
            weight,
        })
    }
}

//! A thin-walled rough dielectric: glTF's `KHR_materials_transmission` without a volume (the
//! glTF spec's thin-walled case, docs/design.md §4), such as a window pane or a leaf modelled as one
//! surface.
//!
//! Mitsuba's `thindielectric` is smooth only, so this extends it to rough interfaces in the way
//! that keeps its limit: a microfacet normal `m` is drawn from the visible normals; the slab
//! reflects with R' = R + T²R / (1 − R²) (both faces and every internal bounce, with R = F(wi·m)
//! and T = 1 − R, Mitsuba's and pbrt-v4's formula), and transmits the rest, leaving on the far
//! side along the mirror image of the reflected direction (a slab with parallel faces does not
//! bend light). As α → 0 this is exactly Mitsuba's `thindielectric`. It is two-sided,
//! reciprocal and energy-conserving (only Smith masking loses energy, as for every microfacet
//! model here).

use super::fresnel::fresnel_dielectric;
use super::microfacet::Microfacet;
use super::sample::{BsdfSample, Lobe};
use crate::geometry::frame::reflect;
use crate::spectrum::Rgb;
use glam::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
/// Mitsuba's `thindielectric` with rough faces: a slab thin enough that light leaves where it enters, unbent.
pub struct ThinDielectric {
    /// The microfacet distribution of its faces.
    pub distr: Microfacet,
    /// Relative index of the slab's material.
    pub eta: f32,
    /// Multiplies the reflected part.
    pub specular_reflectance: Rgb,
    /// Multiplies the transmitted part.
    pub specular_transmittance: Rgb,
}

/// `v` mirrored through the surface plane.
#[inline]
fn flip(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.y, -v.z)
}

impl ThinDielectric {
    /// The slab's reflectance R' at a microfacet seen at cosine `cos_theta` (≥ 0).
    fn slab_reflectance(&self, cos_theta: f32) -> f32 {
        let r = fresnel_dielectric(cos_theta, self.eta).r;
        let t = 1.0 - r;
        if r < 1.0 {
            r + t * t * r / (1.0 - r * r)
        } else {
            1.0
        }
    }

    /// The slab is symmetric under mirroring through its plane, so the pair is mirrored until
    /// `wi` is above and `wo` is then folded above too: returns `(wi, wo_folded, transmitted)`,
    /// or `None` in the tangent plane.
    fn fold(wi: Vec3, wo: Vec3) -> Option<(Vec3, Vec3, bool)> {
        if wi.z == 0.0 || wo.z == 0.0 {
            return None;
        }
        let transmitted = (wi.z < 0.0) != (wo.z < 0.0);
        let up = |v: Vec3| if v.z < 0.0 { flip(v) } else { v };
        Some((up(wi), up(wo), transmitted))
    }

    /// The lobe weights (reflect, transmit) used for both evaluation and selection: R' and
    /// 1 − R' when both lobes are on, or the one lobe alone.
    fn lobe_probabilities(&self, r: f32) -> (f32, f32) {
        let has_r = self.specular_reflectance != Rgb::ZERO;
        let has_t = self.specular_transmittance != Rgb::ZERO;
        match (has_r, has_t) {
            (true, true) => (r, 1.0 - r),
            (true, false) => (1.0, 0.0),
            (false, true) => (0.0, 1.0),
            (false, false) => (0.0, 0.0),
        }
    }

    /// `f(wi, wo) · |cos θo|`.
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        let Some((wi_up, wo_up, transmitted)) = Self::fold(wi, wo) else {
            return Rgb::ZERO;
        };
        let h = (wi_up + wo_up).normalize();
        let d = self.distr.eval(h);
        if d == 0.0 {
            return Rgb::ZERO;
        }
        let g = self.distr.g(wi_up, wo_up, h);
        let r = self.slab_reflectance(wi_up.dot(h));
        let (weight, tint) = if transmitted {
            (1.0 - r, self.specular_transmittance)
        } else {
            (r, self.specular_reflectance)
        };
        tint * (weight * d * g / (4.0 * wi_up.z))
    }

    /// Solid-angle density of [`ThinDielectric::sample`] producing `wo`.
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        let Some((wi_up, wo_up, transmitted)) = Self::fold(wi, wo) else {
            return 0.0;
        };
        let m = (wi_up + wo_up).normalize();
        if !(wi_up.dot(m) > 0.0 && wo_up.dot(m) > 0.0) {
            return 0.0;
        }
        let (pr, pt) = self.lobe_probabilities(self.slab_reflectance(wi_up.dot(m)));
        let lobe = if transmitted { pt } else { pr };
        lobe * self.distr.eval(m) * self.distr.smith_g1(wi_up, m) / (4.0 * wi_up.z)
    }

    /// Sample `wo`: `u0` chooses reflection or transmission, `u` the microfacet normal.
    pub fn sample(&self, wi: Vec3, u0: f32, u: Vec2) -> Option<BsdfSample> {
        if wi.z == 0.0 {
            return None;
        }
        let below = wi.z < 0.0;
        let wi_up = if below { flip(wi) } else { wi };
        let (m, pdf_m) = self.distr.sample(wi_up, u);
        let wo_up = reflect(wi_up, m);
        if !(pdf_m != 0.0 && wo_up.z > 0.0) {
            return None;
        }
        let r = self.slab_reflectance(wi_up.dot(m));
        let (pr, pt) = self.lobe_probabilities(r);
        let transmit = u0 >= pr;
        let (p_lobe, physical, tint, lobe) = if transmit {
            (pt, 1.0 - r, self.specular_transmittance, Lobe::Transmission)
        } else {
            (pr, r, self.specular_reflectance, Lobe::Reflection)
        };
        if !(p_lobe > 0.0) {
            return None;
        }
        // Unfold: transmission crosses the plane, and wi from below mirrors everything.
        let wo = if transmit != below {
            flip(wo_up)
        } else {
            wo_up
        };
        Some(BsdfSample {
            wo,
            pdf: p_lobe * pdf_m / (4.0 * wo_up.dot(m)),
            eta: 1.0,
            lobe,
            // f·cos / pdf: D G1(wi) cancel with the density, and R' (or 1 − R') with the
            // selection probability when both lobes are on.
            weight: tint * (self.distr.smith_g1(wo_up, m) * physical / p_lobe),
        })
    }
}

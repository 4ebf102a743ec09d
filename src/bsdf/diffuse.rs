//! Mitsuba's `diffuse`: a one-sided Lambertian reflector.

use super::sample::{BsdfSample, Lobe};
use crate::geometry::warp::{square_to_cosine_hemisphere, square_to_cosine_hemisphere_pdf};
use crate::spectrum::Rgb;
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug, PartialEq)]
/// Mitsuba's `diffuse`: a Lambertian reflector.
pub struct Diffuse {
    /// Its albedo.
    pub reflectance: Rgb,
}

impl Diffuse {
    /// `f(wi, wo) · cos θo` in the local frame: `reflectance / π · cos θo` above the surface.
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if wi.z > 0.0 && wo.z > 0.0 {
            self.reflectance * (FRAC_1_PI * wo.z)
        } else {
            Rgb::ZERO
        }
    }

    /// Solid-angle density of [`Diffuse::sample`]: cosine-weighted.
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z > 0.0 && wo.z > 0.0 {
            square_to_cosine_hemisphere_pdf(wo)
        } else {
            0.0
        }
    }

    /// Sample `wo` cosine-weighted over the upper hemisphere.
    pub fn sample(&self, wi: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let wo = square_to_cosine_hemisphere(u);
        let pdf = square_to_cosine_hemisphere_pdf(wo);
        (pdf > 0.0).then_some(BsdfSample {
            wo,
            pdf,
            eta: 1.0,
            lobe: Lobe::Reflection,
            weight: self.reflectance,
        })
    }
}

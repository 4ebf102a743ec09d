//! Mitsuba 3's `diffuse`, `roughconductor` and `roughdielectric`, value for value (docs/design.md §4).
//!
//! # Convention
//!
//! One convention everywhere, Mitsuba's:
//!
//! * `wi` and `wo` are unit vectors in the local shading frame (`z` = shading normal, `x` = the
//!   `alpha_u` tangent), and both point **away** from the surface: `wi` towards the camera or
//!   previous path vertex, `wo` towards the light or next vertex.
//! * [`Bsdf::eval`] returns `f(wi, wo) · |cos θo|`: the cosine is included.
//! * [`Bsdf::pdf`] is the solid-angle density with which [`Bsdf::sample`] produces `wo`, lobe
//!   selection included.
//! * [`Bsdf::sample`] returns `weight = eval / pdf`.
//! * In [`TransportMode::Radiance`] transmission carries the `1/η²` radiance scaling.

pub mod conductor;
pub mod dielectric;
pub mod diffuse;
pub mod fresnel;
pub mod ior;
pub mod microfacet;
pub mod mitsuba;
pub mod sample;
pub mod thin;

pub use conductor::RoughConductor;
pub use dielectric::RoughDielectric;
pub use diffuse::Diffuse;
pub use microfacet::{Distribution, Microfacet};
pub use sample::{BsdfSample, Lobe, TransportMode};
pub use thin::ThinDielectric;

use crate::spectrum::Rgb;
use glam::{Vec2, Vec3};

/// A BSDF with every parameter resolved at one shading point (textures already looked up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// Mitsuba's `diffuse`.
    Diffuse(Diffuse),
    /// Mitsuba's `roughconductor`.
    Conductor(RoughConductor),
    /// Mitsuba's `roughdielectric`.
    Dielectric(RoughDielectric),
    /// Not a Mitsuba plugin: glTF's thin-walled transmission (see [`thin`]).
    ThinDielectric(ThinDielectric),
}

impl Bsdf {
    /// `f(wi, wo) · |cos θo|`.
    #[inline]
    pub fn eval(&self, wi: Vec3, wo: Vec3, mode: TransportMode) -> Rgb {
        match self {
            Bsdf::Diffuse(b) => b.eval(wi, wo),
            Bsdf::Conductor(b) => b.eval(wi, wo),
            Bsdf::Dielectric(b) => b.eval(wi, wo, mode),
            Bsdf::ThinDielectric(b) => b.eval(wi, wo),
        }
    }

    /// [`Bsdf::eval`] from `wi` towards every direction of `wo`, given as lanes of x, y and z,
    /// into `out` (one value per lane): the same values bit for bit, evaluated several at a
    /// time where the BSDF has a form without branches (GGX conductors and dielectrics: the
    /// same operations in the same order, `tests/bsdf_conformance.rs`), one by one otherwise.
    /// What a map of point values over many emitter samples needs (`bake::direct`).
    pub fn eval_lanes(&self, wi: Vec3, wo: [&[f32]; 3], mode: TransportMode, out: &mut Vec<Rgb>) {
        let n = wo.iter().map(|l| l.len()).min().unwrap_or(0);
        out.clear();
        out.resize(n, Rgb::ZERO);
        match self {
            Bsdf::Conductor(c) if c.distr.kind == Distribution::Ggx => c.eval_lanes(wi, wo, out),
            Bsdf::Dielectric(d) if d.distr.kind == Distribution::Ggx => {
                d.eval_lanes(wi, wo, mode, out)
            }
            _ => {
                for (k, out) in out.iter_mut().enumerate() {
                    *out = self.eval(wi, Vec3::new(wo[0][k], wo[1][k], wo[2][k]), mode);
                }
            }
        }
    }

    /// Solid-angle density of [`Bsdf::sample`] producing `wo`.
    #[inline]
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        match self {
            Bsdf::Diffuse(b) => b.pdf(wi, wo),
            Bsdf::Conductor(b) => b.pdf(wi, wo),
            Bsdf::Dielectric(b) => b.pdf(wi, wo),
            Bsdf::ThinDielectric(b) => b.pdf(wi, wo),
        }
    }

    /// Sample `wo`: `u0` selects the lobe (dielectric only), `u` drives the direction.
    /// `None` when the sample is invalid (below the horizon, wrong side, zero density).
    #[inline]
    pub fn sample(&self, wi: Vec3, u0: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        match self {
            Bsdf::Diffuse(b) => b.sample(wi, u),
            Bsdf::Conductor(b) => b.sample(wi, u),
            Bsdf::Dielectric(b) => b.sample(wi, u0, u, mode),
            Bsdf::ThinDielectric(b) => b.sample(wi, u0, u),
        }
    }

    /// True when the BSDF scatters light arriving from below the shading normal.
    pub fn is_two_sided(&self) -> bool {
        matches!(self, Bsdf::Dielectric(_) | Bsdf::ThinDielectric(_))
    }

    /// The BSDF with its tints set to one (`specular_reflectance` and
    /// `specular_transmittance`; diffuse's reflectance is not a tint), and those tints:
    /// `[reflected, transmitted]`. The BSDF's value and the flux it sends to each side are
    /// those of the untinted BSDF times the tint of that side (the tints scale the lobes; the
    /// Fresnel term, not they, splits reflection from transmission). So one operator serves
    /// every tint of a textured colour ([`crate::bake::bounce::bsdf_operator::Operators`]).
    pub fn untinted(&self) -> (Bsdf, [Rgb; 2]) {
        match *self {
            Bsdf::Diffuse(d) => (Bsdf::Diffuse(d), [Rgb::ONE; 2]),
            Bsdf::Conductor(c) => (
                Bsdf::Conductor(RoughConductor {
                    specular_reflectance: Rgb::ONE,
                    ..c
                }),
                [c.specular_reflectance; 2],
            ),
            Bsdf::Dielectric(d) => (
                Bsdf::Dielectric(RoughDielectric {
                    specular_reflectance: Rgb::ONE,
                    specular_transmittance: Rgb::ONE,
                    ..d
                }),
                [d.specular_reflectance, d.specular_transmittance],
            ),
            Bsdf::ThinDielectric(d) => (
                Bsdf::ThinDielectric(ThinDielectric {
                    specular_reflectance: Rgb::ONE,
                    specular_transmittance: Rgb::ONE,
                    ..d
                }),
                [d.specular_reflectance, d.specular_transmittance],
            ),
        }
    }

    /// The BSDF with the isotropic microfacet roughness `alpha` (unchanged for diffuse).
    pub fn with_alpha(&self, alpha: f32) -> Bsdf {
        let distr = |d: Microfacet| Microfacet::new(d.kind, alpha, alpha);
        match *self {
            Bsdf::Diffuse(d) => Bsdf::Diffuse(d),
            Bsdf::Conductor(c) => Bsdf::Conductor(RoughConductor {
                distr: distr(c.distr),
                ..c
            }),
            Bsdf::Dielectric(d) => Bsdf::Dielectric(RoughDielectric {
                distr: distr(d.distr),
                ..d
            }),
            Bsdf::ThinDielectric(d) => Bsdf::ThinDielectric(ThinDielectric {
                distr: distr(d.distr),
                ..d
            }),
        }
    }

    /// The surface's colour, as a denoiser's albedo guide takes it: the diffuse reflectance,
    /// a conductor's reflectance at normal incidence, a dielectric's transmittance.
    pub(crate) fn albedo_estimate(&self) -> Rgb {
        match self {
            Bsdf::Diffuse(d) => d.reflectance,
            Bsdf::Conductor(c) => {
                fresnel::fresnel_conductor(1.0, c.eta, c.k) * c.specular_reflectance
            }
            Bsdf::Dielectric(d) => d.specular_transmittance,
            Bsdf::ThinDielectric(d) => d.specular_transmittance,
        }
    }

    /// The smaller microfacet roughness, or `None` for the diffuse BSDF.
    pub fn alpha(&self) -> Option<f32> {
        let d = match self {
            Bsdf::Diffuse(_) => return None,
            Bsdf::Conductor(b) => b.distr,
            Bsdf::Dielectric(b) => b.distr,
            Bsdf::ThinDielectric(b) => b.distr,
        };
        Some(d.alpha_u.min(d.alpha_v))
    }

    /// The directions a glossy lobe is centred on for light leaving along `wo` (local frame):
    /// the mirror direction, and for transmitting BSDFs the straight or refracted one (`None`
    /// under total internal reflection).
    pub(crate) fn lobe_centres(&self, wo: Vec3) -> [Option<Vec3>; 2] {
        let mirror = Some(Vec3::new(-wo.x, -wo.y, wo.z));
        let through = match self {
            Bsdf::Diffuse(_) | Bsdf::Conductor(_) => None,
            Bsdf::ThinDielectric(_) => Some(-wo),
            Bsdf::Dielectric(b) => {
                // Snell through the macro normal, from wo's side.
                let eta = if wo.z > 0.0 { b.eta } else { 1.0 / b.eta };
                let sin2_t = (1.0 - wo.z * wo.z).max(0.0) / (eta * eta);
                (sin2_t < 1.0).then(|| {
                    let cos_t = (1.0 - sin2_t).sqrt().copysign(-wo.z);
                    Vec3::new(-wo.x / eta, -wo.y / eta, cos_t).normalize()
                })
            }
        };
        [mirror, through]
    }
}

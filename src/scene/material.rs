//! Materials of the scene IR and their mapping to Mitsuba BSDFs (DESIGN.md §4).
//!
//! An explicit Mitsuba description always wins. Otherwise glTF metallic-roughness maps as:
//! `alpha = roughness²` with GGX; transmission > 0 → `roughdielectric` (`int_ior` = the glTF
//! IOR, exterior 1.0, `specular_transmittance` = base colour), or the thin-walled
//! [`ThinDielectric`] when the material has no `KHR_materials_volume` or a zero thickness (the
//! glTF definition of thin-walled); metallic ≥ 0.5 →
//! `roughconductor` with `material: none` and `specular_reflectance` = base colour; otherwise
//! `diffuse(base colour)`. Textured factors are resolved per shading point, so a metallic mask
//! switches the BSDF per texel.

use super::texture::{TexRef, Texture};
use crate::bsdf::{
    Bsdf, Diffuse, Distribution, Microfacet, RoughConductor, RoughDielectric, ThinDielectric,
};
use crate::spectrum::Rgb;
use glam::Vec2;

/// glTF metallic-roughness parameters (with their textures).
#[derive(Clone, Debug)]
pub struct PbrParams {
    pub base_color: Rgb,
    pub base_color_texture: Option<TexRef>,
    pub metallic: f32,
    pub roughness: f32,
    /// Roughness in G, metalness in B (glTF convention).
    pub metallic_roughness_texture: Option<TexRef>,
    pub transmission: f32,
    pub transmission_texture: Option<TexRef>,
    /// Index of refraction of the interior (KHR_materials_ior, default 1.5).
    pub ior: f32,
    /// A transmissive surface without a volume behind it (a pane, a leaf).
    pub thin_walled: bool,
}

impl PbrParams {
    /// Untextured, opaque parameters.
    pub fn constant(base_color: Rgb, metallic: f32, roughness: f32) -> PbrParams {
        PbrParams {
            base_color,
            base_color_texture: None,
            metallic,
            roughness,
            metallic_roughness_texture: None,
            transmission: 0.0,
            transmission_texture: None,
            ior: 1.5,
            thin_walled: false,
        }
    }
}

/// What scatters light at a surface.
#[derive(Clone, Debug)]
pub enum Scattering {
    /// An explicit Mitsuba description (`extras.mitsuba` or `mitsuba:*` attributes).
    Explicit(Bsdf),
    /// Mapped from metallic-roughness.
    Pbr(PbrParams),
}

/// Emitted radiance of a surface: `factor × strength`, times a texture if any.
#[derive(Clone, Debug)]
pub struct Emission {
    pub radiance: Rgb,
    pub texture: Option<TexRef>,
    /// Emits from both faces (glTF `doubleSided`); otherwise only from the front face.
    pub two_sided: bool,
}

#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    pub scattering: Scattering,
    pub emission: Option<Emission>,
}

impl Material {
    /// The BSDF at a shading point with texture coordinate `uv`.
    pub fn bsdf_at(&self, textures: &[Texture], uv: Vec2) -> Bsdf {
        match &self.scattering {
            Scattering::Explicit(b) => *b,
            Scattering::Pbr(p) => {
                let mut base = p.base_color;
                if let Some(t) = &p.base_color_texture {
                    base *= t.sample(textures, uv).truncate();
                }
                let (mut metallic, mut roughness) = (p.metallic, p.roughness);
                if let Some(t) = &p.metallic_roughness_texture {
                    let v = t.sample(textures, uv);
                    roughness *= v.y;
                    metallic *= v.z;
                }
                let mut transmission = p.transmission;
                if let Some(t) = &p.transmission_texture {
                    transmission *= t.sample(textures, uv).x;
                }
                let alpha = roughness.clamp(0.0, 1.0).powi(2);
                let distr = Microfacet::new(Distribution::Ggx, alpha, alpha);
                if transmission > 0.0 && p.thin_walled {
                    Bsdf::ThinDielectric(ThinDielectric {
                        distr,
                        eta: p.ior,
                        specular_reflectance: Rgb::ONE,
                        specular_transmittance: base,
                    })
                } else if transmission > 0.0 {
                    Bsdf::Dielectric(RoughDielectric {
                        distr,
                        eta: p.ior,
                        specular_reflectance: Rgb::ONE,
                        specular_transmittance: base,
                    })
                } else if metallic >= 0.5 {
                    Bsdf::Conductor(RoughConductor {
                        distr,
                        eta: Rgb::ZERO,
                        k: Rgb::ONE,
                        specular_reflectance: base,
                    })
                } else {
                    Bsdf::Diffuse(Diffuse { reflectance: base })
                }
            }
        }
    }

    /// Emitted radiance at `uv` towards a direction on the `front` (or back) side.
    pub fn emission_at(&self, textures: &[Texture], uv: Vec2, front: bool) -> Rgb {
        match &self.emission {
            Some(e) if front || e.two_sided => match &e.texture {
                Some(t) => e.radiance * t.sample(textures, uv).truncate(),
                None => e.radiance,
            },
            _ => Rgb::ZERO,
        }
    }
}

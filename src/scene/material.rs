//! Materials of the scene IR and their mapping to Mitsuba BSDFs (docs/design.md §4).
//!
//! An explicit Mitsuba description always wins. Otherwise glTF metallic-roughness (and
//! UsdPreviewSurface, read into the same parameters) maps as: `alpha = roughness²` with GGX;
//! metallic ≥ 0.5 → `roughconductor` with `material: none` and `specular_reflectance` = base
//! colour; otherwise transmission > 0 → `roughdielectric` (`int_ior` = the glTF IOR, exterior
//! 1.0, `specular_transmittance` = base colour), or the thin-walled [`ThinDielectric`] when the
//! material has no `KHR_materials_volume` or a zero thickness (the glTF definition of
//! thin-walled); otherwise `diffuse(base colour)`. Metal comes first, in docs/design.md §4's order
//! and as in glTF, where transmission is a lobe of the dielectric part only. Textured factors
//! are resolved per shading point, so a metallic mask switches the BSDF per texel.

use super::normal_map::NormalMap;
use super::texture::{ChannelRef, TexRef, Texture};
use crate::bsdf::{
    Bsdf, Diffuse, Distribution, Microfacet, RoughConductor, RoughDielectric, ThinDielectric,
};
use crate::spectrum::Rgb;
use glam::Vec2;

/// How close to 1 a relative index of refraction is taken as index-matched (a float32 ulp at 1
/// is 1.2e-7; 1.0001, a stiff but real case, stays glass).
pub(crate) const INDEX_MATCHED: f32 = 1e-6;

/// glTF metallic-roughness parameters (with their textures).
#[derive(Clone, Debug)]
pub struct PbrParams {
    /// Base colour (linear RGB).
    pub base_color: Rgb,
    /// Multiplies `base_color` (sRGB-decoded).
    pub base_color_texture: Option<TexRef>,
    /// Metalness, 0 (dielectric) to 1 (conductor).
    pub metallic: f32,
    /// Multiplies `metallic` (glTF: the B channel of the metallic-roughness image).
    pub metallic_texture: Option<ChannelRef>,
    /// Perceptual roughness; the GGX α is its square.
    pub roughness: f32,
    /// Multiplies `roughness` (glTF: the G channel of the metallic-roughness image).
    pub roughness_texture: Option<ChannelRef>,
    /// Fraction of light transmitted (KHR_materials_transmission).
    pub transmission: f32,
    /// Multiplies `transmission` (the R channel).
    pub transmission_texture: Option<ChannelRef>,
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
            metallic_texture: None,
            roughness,
            roughness_texture: None,
            transmission: 0.0,
            transmission_texture: None,
            ior: 1.5,
            thin_walled: false,
        }
    }
}

/// What scatters light at a surface.
#[derive(Clone, Debug)]
// A scene has few materials and they are read in place, so the larger Pbr variant costs
// nothing worth a box.
#[allow(clippy::large_enum_variant)]
pub enum Scattering {
    /// An explicit Mitsuba description (`extras.mitsuba` or `mitsuba:*` attributes).
    Explicit(Bsdf),
    /// Mapped from metallic-roughness.
    Pbr(PbrParams),
}

/// Emitted radiance of a surface: `factor × strength`, times a texture if any.
#[derive(Clone, Debug)]
pub struct Emission {
    /// Emitted radiance (linear RGB).
    pub radiance: Rgb,
    /// Multiplies `radiance` (sRGB-decoded).
    pub texture: Option<TexRef>,
    /// Emits from both faces (glTF `doubleSided`); otherwise only from the front face.
    pub two_sided: bool,
}

#[derive(Clone, Debug)]
/// A surface's material: how it scatters, what it emits, its cut-outs and normal map.
pub struct Material {
    /// The name in the scene file (errors and the bake plan name materials by it).
    pub name: String,
    /// How it scatters light.
    pub scattering: Scattering,
    /// What it emits, if anything.
    pub emission: Option<Emission>,
    /// Holes cut by the alpha channel (glTF `alphaMode: MASK`, USD `opacityThreshold`).
    pub cutout: Option<Cutout>,
    /// A tangent-space normal map (glTF `normalTexture`, UsdPreviewSurface `normal`).
    pub normal_map: Option<NormalMap>,
}

/// An alpha cut-out: the surface is there where `alpha` (times the texture's channel) is at
/// least `cutoff` and a hole elsewhere, for every ray (camera, shadow, bounce) and for the
/// bake's surfels.
#[derive(Clone, Copy, Debug)]
pub struct Cutout {
    /// Opacity (glTF `baseColorFactor` alpha, USD `opacity`).
    pub alpha: f32,
    /// Multiplies `alpha` (the alpha channel).
    pub texture: Option<ChannelRef>,
    /// The opacity below which the surface is a hole.
    pub cutoff: f32,
}

impl Cutout {
    /// Whether the surface is there at texture coordinate `uv`.
    pub fn keeps(&self, textures: &[Texture], uv: Vec2) -> bool {
        let a = self.alpha * self.texture.map_or(1.0, |t| t.sample(textures, uv));
        a >= self.cutoff
    }

    /// `Some(kept)` where no texture varies the answer.
    pub fn constant(&self) -> Option<bool> {
        self.texture.is_none().then_some(self.alpha >= self.cutoff)
    }
}

impl Material {
    /// Clear, non-emitting glass of relative index 1 everywhere: it neither reflects nor bends
    /// nor tints light, so it is invisible.
    pub(crate) fn is_index_matched(&self) -> bool {
        let matched = |eta: f32| (eta - 1.0).abs() <= INDEX_MATCHED;
        let glass = match &self.scattering {
            Scattering::Explicit(Bsdf::Dielectric(d)) => {
                matched(d.eta) && d.specular_transmittance == Rgb::ONE
            }
            Scattering::Explicit(Bsdf::ThinDielectric(d)) => {
                matched(d.eta) && d.specular_transmittance == Rgb::ONE
            }
            Scattering::Explicit(_) => false,
            Scattering::Pbr(p) => {
                matched(p.ior)
                    && p.transmission > 0.0
                    && p.transmission_texture.is_none()
                    && p.metallic < 0.5
                    && p.metallic_texture.is_none()
                    && p.base_color == Rgb::ONE
                    && p.base_color_texture.is_none()
            }
        };
        glass && self.emission.is_none()
    }

    /// Whether a texture varies the roughness (the bake snaps such roughness to a few levels).
    pub fn has_textured_roughness(&self) -> bool {
        matches!(&self.scattering, Scattering::Pbr(p) if p.roughness_texture.is_some())
    }

    /// The BSDF at a shading point with texture coordinate `uv`.
    pub fn bsdf_at(&self, textures: &[Texture], uv: Vec2) -> Bsdf {
        match &self.scattering {
            Scattering::Explicit(b) => *b,
            Scattering::Pbr(p) => {
                let mut base = p.base_color;
                if let Some(t) = &p.base_color_texture {
                    base *= t.sample(textures, uv).truncate();
                }
                let scalar = |value: f32, texture: &Option<ChannelRef>| match texture {
                    Some(t) => value * t.sample(textures, uv),
                    None => value,
                };
                let metallic = scalar(p.metallic, &p.metallic_texture);
                let roughness = scalar(p.roughness, &p.roughness_texture);
                let transmission = scalar(p.transmission, &p.transmission_texture);
                let alpha = roughness.clamp(0.0, 1.0).powi(2);
                let distr = Microfacet::new(Distribution::Ggx, alpha, alpha);
                if metallic >= 0.5 {
                    Bsdf::Conductor(RoughConductor {
                        distr,
                        eta: Rgb::ZERO,
                        k: Rgb::ONE,
                        specular_reflectance: base,
                    })
                } else if transmission > 0.0 && p.thin_walled {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Metal wins over transmission (docs/design.md §4's order; glTF's transmission is a lobe of
    /// the dielectric part only), and transmission over diffuse.
    #[test]
    fn metal_then_transmission_then_diffuse() {
        let bsdf = |metallic: f32, transmission: f32| {
            Material {
                name: "m".into(),
                scattering: Scattering::Pbr(PbrParams {
                    transmission,
                    ..PbrParams::constant(Rgb::splat(0.8), metallic, 0.3)
                }),
                cutout: None,
                normal_map: None,
                emission: None,
            }
            .bsdf_at(&[], Vec2::ZERO)
        };
        assert!(matches!(bsdf(1.0, 1.0), Bsdf::Conductor(_)));
        assert!(matches!(bsdf(0.0, 1.0), Bsdf::Dielectric(_)));
        assert!(matches!(bsdf(0.0, 0.0), Bsdf::Diffuse(_)));
    }
}

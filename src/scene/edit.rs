//! Edits to a scene's materials and lights after its bake, in the `--set` syntax of
//! `wpbgi relight`: `NAME.PARAMETER=VALUE` sets a parameter, `NAME.PARAMETER*=VALUE`
//! multiplies it. NAME is a material, a punctual light or the environment, by the name the
//! scene gives it; VALUE is one number or three (`r,g,b`).
//!
//! | target | parameter | what it changes |
//! |---|---|---|
//! | any material | `emission` | emitted radiance (an emitter's, or a new one, untextured and front-facing) |
//! | `diffuse` | `reflectance` | the albedo |
//! | `roughconductor` | `specular_reflectance`, `alpha` | the Fresnel tint; the roughness |
//! | `roughdielectric`, thin dielectric | `specular_reflectance`, `specular_transmittance`, `alpha` | the tints; the roughness |
//! | glTF metallic-roughness | `base_color`, `metallic`, `roughness` | its parameters (textures still multiply them) |
//! | punctual light | `intensity` | `intensity × color` |
//! | environment | `intensity` | the scale of its radiance |
//!
//! A roughness (`alpha`) sets or multiplies both axes of an anisotropic distribution. Every
//! value must be finite and not negative, and an `alpha` positive. An edit that names nothing
//! in the scene, or a parameter the target does not have, is an error that lists what the
//! scene or the target has.

use super::model::Scene;
use crate::bsdf::{Bsdf, Microfacet};
use crate::error::{Error, Result};
use crate::spectrum::Rgb;
use std::fmt;
use std::str::FromStr;

/// One edit: `target.parameter` set to, or multiplied by, `value`.
#[derive(Clone, Debug, PartialEq)]
pub struct Edit {
    /// The material, light or environment, by name.
    pub target: String,
    /// The parameter's name (see the module docs).
    pub parameter: String,
    /// Set or multiply.
    pub op: EditOp,
    /// One number (the same for each channel) or three.
    pub value: Rgb,
    /// Whether the value was one number (an `alpha` takes only one).
    pub scalar: bool,
}

/// How an edit changes its parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EditOp {
    /// `=`: the value replaces the parameter.
    Set,
    /// `*=`: the value multiplies it.
    Scale,
}

impl fmt::Display for Edit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let op = match self.op {
            EditOp::Set => "=",
            EditOp::Scale => "*=",
        };
        write!(f, "{}.{}{op}", self.target, self.parameter)?;
        if self.scalar {
            write!(f, "{}", self.value.x)
        } else {
            write!(f, "{},{},{}", self.value.x, self.value.y, self.value.z)
        }
    }
}

impl FromStr for Edit {
    type Err = Error;

    /// Parse `NAME.PARAMETER=VALUE` or `NAME.PARAMETER*=VALUE` (the name may hold dots: the
    /// parameter is what follows the last one).
    fn from_str(s: &str) -> Result<Edit> {
        let refuse = |reason: String| Error::Edit {
            edit: s.to_string(),
            reason,
        };
        let (lhs, op, rhs) = if let Some((l, r)) = s.split_once("*=") {
            (l, EditOp::Scale, r)
        } else if let Some((l, r)) = s.split_once('=') {
            (l, EditOp::Set, r)
        } else {
            return Err(refuse(
                "expected NAME.PARAMETER=VALUE or NAME.PARAMETER*=VALUE".into(),
            ));
        };
        let Some((target, parameter)) = lhs.trim().rsplit_once('.') else {
            return Err(refuse(format!(
                "\"{}\" names no parameter: expected NAME.PARAMETER",
                lhs.trim()
            )));
        };
        if target.is_empty() || parameter.is_empty() {
            return Err(refuse("expected NAME.PARAMETER before the '='".into()));
        }
        let numbers: Vec<f32> = rhs
            .split(',')
            .map(|x| x.trim().parse::<f32>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| {
                refuse(format!(
                    "\"{}\" is not one number or three (r,g,b)",
                    rhs.trim()
                ))
            })?;
        let (value, scalar) = match numbers[..] {
            [x] => (Rgb::splat(x), true),
            [r, g, b] => (Rgb::new(r, g, b), false),
            _ => {
                return Err(refuse(format!(
                    "\"{}\" is not one number or three (r,g,b)",
                    rhs.trim()
                )))
            }
        };
        if !value.is_finite() || value.min_element() < 0.0 {
            return Err(refuse(format!(
                "{} must be finite and not negative",
                rhs.trim()
            )));
        }
        Ok(Edit {
            target: target.to_string(),
            parameter: parameter.to_string(),
            op,
            value,
            scalar,
        })
    }
}

impl Edit {
    /// `old` changed by this edit.
    fn rgb(&self, old: Rgb) -> Rgb {
        match self.op {
            EditOp::Set => self.value,
            EditOp::Scale => old * self.value,
        }
    }

    /// The scalar `old` changed by this edit (refused for three numbers).
    fn scalar(&self, old: f32) -> Result<f32> {
        if !self.scalar {
            return Err(self.refuse(format!("{} takes one number", self.parameter)));
        }
        Ok(match self.op {
            EditOp::Set => self.value.x,
            EditOp::Scale => old * self.value.x,
        })
    }

    /// A parameter in [0, 1] changed by this edit.
    fn unit(&self, old: f32) -> Result<f32> {
        let new = self.scalar(old)?;
        if new > 1.0 {
            return Err(self.refuse(format!(
                "{} would be {new}; it must be in [0, 1]",
                self.parameter
            )));
        }
        Ok(new)
    }

    fn refuse(&self, reason: String) -> Error {
        Error::Edit {
            edit: self.to_string(),
            reason,
        }
    }

    /// A roughness distribution with both axes changed by this edit.
    fn microfacet(&self, d: Microfacet) -> Result<Microfacet> {
        let alpha_u = self.scalar(d.alpha_u)?;
        let alpha_v = self.scalar(d.alpha_v)?;
        if !(alpha_u > 0.0 && alpha_v > 0.0) {
            return Err(self.refuse("alpha must be positive".into()));
        }
        Ok(Microfacet {
            alpha_u,
            alpha_v,
            ..d
        })
    }

    /// Apply this edit to `scene`.
    pub fn apply(&self, scene: &mut Scene) -> Result<()> {
        let materials: Vec<usize> = (0..scene.materials.len())
            .filter(|&i| scene.materials[i].name == self.target)
            .collect();
        let lights: Vec<usize> = (0..scene.lights.len())
            .filter(|&i| scene.lights[i].name == self.target)
            .collect();
        let environment = scene
            .environment
            .as_ref()
            .is_some_and(|e| e.name == self.target);
        match (materials.len(), lights.len(), environment) {
            (0, 0, false) => Err(self.refuse(format!(
                "the scene has no material, light or environment named \"{}\" ({})",
                self.target,
                names(scene)
            ))),
            (_, 0, false) => {
                for i in materials {
                    self.apply_to_material(scene, i)?;
                }
                Ok(())
            }
            (0, _, false) => {
                for i in lights {
                    let light = &mut scene.lights[i];
                    match self.parameter.as_str() {
                        "intensity" => light.intensity = self.rgb(light.intensity),
                        _ => return Err(self.no_parameter("a light", &["intensity"])),
                    }
                }
                Ok(())
            }
            (0, 0, true) => match (self.parameter.as_str(), scene.environment.as_mut()) {
                ("intensity", Some(e)) => {
                    e.scale = self.rgb(e.scale);
                    Ok(())
                }
                _ => Err(self.no_parameter("the environment", &["intensity"])),
            },
            _ => Err(self.refuse(format!(
                "\"{}\" names more than one kind of thing (a material, a light, the \
                 environment); rename one in the scene",
                self.target
            ))),
        }
    }

    fn no_parameter(&self, what: &str, has: &[&str]) -> Error {
        self.refuse(format!(
            "{what} has no parameter \"{}\"; it has {}",
            self.parameter,
            has.join(", ")
        ))
    }

    /// Apply this edit to a dielectric (`what`, for errors): its reflection and transmission
    /// tints, its roughness.
    fn dielectric(
        &self,
        what: &str,
        [reflect, transmit]: [&mut Rgb; 2],
        distr: &mut Microfacet,
    ) -> Result<()> {
        match self.parameter.as_str() {
            "specular_reflectance" => *reflect = self.rgb(*reflect),
            "specular_transmittance" => *transmit = self.rgb(*transmit),
            "alpha" => *distr = self.microfacet(*distr)?,
            _ => {
                return Err(self.no_parameter(
                    what,
                    &[
                        "specular_reflectance",
                        "specular_transmittance",
                        "alpha",
                        "emission",
                    ],
                ))
            }
        }
        Ok(())
    }

    fn apply_to_material(&self, scene: &mut Scene, i: usize) -> Result<()> {
        use super::material::{Emission, Scattering};
        let material = &mut scene.materials[i];
        if self.parameter == "emission" {
            let emission = material.emission.get_or_insert(Emission {
                radiance: Rgb::ZERO,
                texture: None,
                two_sided: false,
            });
            emission.radiance = self.rgb(emission.radiance);
            return Ok(());
        }
        let p = self.parameter.as_str();
        match &mut material.scattering {
            Scattering::Explicit(Bsdf::Diffuse(d)) => match p {
                "reflectance" => d.reflectance = self.rgb(d.reflectance),
                _ => {
                    return Err(
                        self.no_parameter("a diffuse material", &["reflectance", "emission"])
                    )
                }
            },
            Scattering::Explicit(Bsdf::Conductor(c)) => match p {
                "specular_reflectance" => c.specular_reflectance = self.rgb(c.specular_reflectance),
                "alpha" => c.distr = self.microfacet(c.distr)?,
                _ => {
                    return Err(self.no_parameter(
                        "a roughconductor",
                        &["specular_reflectance", "alpha", "emission"],
                    ))
                }
            },
            Scattering::Explicit(Bsdf::Dielectric(d)) => self.dielectric(
                "a roughdielectric",
                [&mut d.specular_reflectance, &mut d.specular_transmittance],
                &mut d.distr,
            )?,
            Scattering::Explicit(Bsdf::ThinDielectric(d)) => self.dielectric(
                "a thin dielectric",
                [&mut d.specular_reflectance, &mut d.specular_transmittance],
                &mut d.distr,
            )?,
            Scattering::Pbr(pbr) => match p {
                "base_color" => pbr.base_color = self.rgb(pbr.base_color),
                "metallic" => pbr.metallic = self.unit(pbr.metallic)?,
                "roughness" => pbr.roughness = self.unit(pbr.roughness)?,
                _ => {
                    return Err(self.no_parameter(
                        "a metallic-roughness material",
                        &["base_color", "metallic", "roughness", "emission"],
                    ))
                }
            },
        }
        Ok(())
    }
}

/// What a scene has to edit, for an error.
fn names(scene: &Scene) -> String {
    let list = |v: Vec<&str>| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.join(", ")
        }
    };
    let mut out = format!(
        "materials: {}; lights: {}",
        list(scene.materials.iter().map(|m| m.name.as_str()).collect()),
        list(scene.lights.iter().map(|l| l.name.as_str()).collect())
    );
    if let Some(e) = &scene.environment {
        out += &format!("; environment: {}", e.name);
    }
    out
}

impl Scene {
    /// Apply `edits` to this scene, in order (stopping at the first refused).
    pub fn apply_edits(&mut self, edits: &[Edit]) -> Result<()> {
        edits.iter().try_for_each(|e| e.apply(self))
    }

    /// This scene with `edits` applied, in order.
    pub fn edited(&self, edits: &[Edit]) -> Result<Scene> {
        let mut scene = self.clone();
        scene.apply_edits(edits)?;
        Ok(scene)
    }
}

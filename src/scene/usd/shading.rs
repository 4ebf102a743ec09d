//! Materials (docs/design.md §4): `UsdPreviewSurface` read into the same parameters as glTF's
//! metallic-roughness, with its `UsdUVTexture` networks, unless explicit `mitsuba:*`
//! attributes on the material say otherwise.
//!
//! - Each input is its authored value, or what it is connected to: a `UsdUVTexture` output
//!   (`rgb`, `rgba` or one of `r`, `g`, `b`, `a`), through material interface inputs.
//! - A texture reads its `file` (anchored to the layer that authored it, so files inside a
//!   usdz resolve), `sourceColorSpace` (`auto` reads 8-bit RGB and RGBA images as sRGB, as the
//!   UsdPreviewSurface specification says), `wrapS`/`wrapT` (`useMetadata` repeats), `scale`
//!   and `bias`. Its `st` comes from a `UsdPrimvarReader_float2`, optionally through a
//!   `UsdTransform2d`; the primvar it names is the mesh's texture coordinate set.
//! - `opacity` < 1 is transmission with `ior` (docs/design.md §4); with `opacityThreshold` > 0 the
//!   material is an alpha cut-out: opaque where `opacity` reaches the threshold, a hole
//!   elsewhere ([`Cutout`]).

use super::stage::{sample, Importer};
use crate::error::Result;
use crate::scene::material::{Cutout, Emission, Material, PbrParams, Scattering};
use crate::scene::normal_map::NormalMap;
use crate::scene::texture::{ChannelRef, TexRef, Texture, Wrap};
use crate::scene::Warning;
use crate::spectrum::Rgb;
use glam::{Affine2, Vec2, Vec4};
use openusd::gf;
use openusd::schemas::shade::{Material as UsdMaterial, MaterialBindingAPI, Shader};
use openusd::sdf;

/// Connection hops followed through interface inputs before giving up (cycles).
const MAX_HOPS: usize = 8;

/// The texture coordinate set a material reads when it names none.
pub(super) const DEFAULT_UV_SET: &str = "st";

/// One `UsdPreviewSurface` input.
enum Input {
    Unset,
    Value(sdf::Value),
    /// Connected to a `UsdUVTexture` output: `channel` 0–3 for `r`…`a`, `None` for `rgb(a)`.
    Texture {
        texture: TexRef,
        channel: Option<usize>,
    },
}

impl Importer<'_> {
    /// The index of the material bound to `prim` (imported on first use).
    pub(super) fn material_of(&mut self, prim: &sdf::Path, double_sided: bool) -> Result<usize> {
        let bound = match MaterialBindingAPI::get(self.stage, prim.clone()) {
            Ok(Some(api)) => api
                .compute_bound_material("")
                .map_err(|e| self.prim_err(prim, format!("material binding: {e:#}")))?,
            _ => None,
        };
        // openusd 0.6 recurses without end on a binding to a path that is not made of
        // identifiers (found by fuzzing).
        if let Some(b) = &bound {
            if !super::stage::is_plain_prim_path(b.as_str()) {
                return Err(self.prim_err(
                    prim,
                    format!(
                        "its material binding names {}, which is not a prim path",
                        super::stage::shown(b.as_str())
                    ),
                ));
            }
        }
        let key = format!(
            "{}{}",
            bound.as_ref().map_or("", |p| p.as_str()),
            if double_sided { " (double-sided)" } else { "" }
        );
        if let Some(&i) = self.materials.get(&key) {
            return Ok(i);
        }
        self.uv_sets.clear();
        let material = match &bound {
            Some(m) => self.preview_material(m, double_sided)?,
            None => default_material(),
        };
        // The IR has one texture coordinate set per mesh.
        self.uv_sets.sort();
        self.uv_sets.dedup();
        if self.uv_sets.len() > 1 {
            self.scene.warnings.push(Warning(format!(
                "material {}: its textures read the primvars {}; only {} is used",
                material.name,
                self.uv_sets.join(", "),
                self.uv_sets[0]
            )));
        }
        let uv_set = self
            .uv_sets
            .first()
            .cloned()
            .unwrap_or_else(|| DEFAULT_UV_SET.to_string());
        self.scene.materials.push(material);
        let i = self.scene.materials.len() - 1;
        self.materials.insert(key, i);
        self.uv_set_of.insert(i, uv_set);
        Ok(i)
    }

    /// The explicit Mitsuba BSDF of material prim `m` (its `mitsuba:*` attributes), if any.
    fn explicit_bsdf(&self, m: &sdf::Path) -> Result<Option<crate::bsdf::Bsdf>> {
        let prim = self.stage.prim(m.clone());
        let names = prim
            .property_names()
            .map_err(|e| self.prim_err(m, format!("{e:#}")))?;
        let mut desc = serde_json::Map::new();
        for name in names
            .iter()
            .filter_map(|n| n.as_str().strip_prefix("mitsuba:"))
        {
            let attr = prim.attribute(format!("mitsuba:{name}"));
            let Some(value) = attr
                .get::<sdf::Value>()
                .map_err(|e| self.prim_err(m, format!("mitsuba:{name}: {e:#}")))?
            else {
                continue;
            };
            let json = if let Ok(x) = value.clone().cast::<f64>() {
                serde_json::json!(x)
            } else if let Ok(v) = value.clone().cast::<gf::Vec3f>() {
                serde_json::json!([v.x, v.y, v.z])
            } else if let Ok(t) = value.clone().cast::<String>() {
                serde_json::json!(t)
            } else if let Ok(b) = value.clone().cast::<bool>() {
                serde_json::json!(b)
            } else {
                return Err(self.prim_err(
                    m,
                    format!("mitsuba:{name} must be a number, a colour, a string or a bool"),
                ));
            };
            desc.insert(name.to_string(), json);
        }
        if desc.is_empty() {
            return Ok(None);
        }
        crate::bsdf::mitsuba::parse_bsdf(&serde_json::Value::Object(desc))
            .map(Some)
            .map_err(|e| self.prim_err(m, e))
    }

    /// Refuse connection `source` of `prim`'s `what` unless it is a plain property path (see
    /// [`is_plain_property_path`]).
    fn require_property_path(
        &self,
        prim: &sdf::Path,
        what: &str,
        source: &sdf::Path,
    ) -> Result<()> {
        if is_plain_property_path(source) {
            return Ok(());
        }
        Err(self.prim_err(
            prim,
            format!(
                "{what} connects to {}, which is not a property path",
                super::stage::shown(source.as_str())
            ),
        ))
    }

    /// The `UsdPreviewSurface` shader that is the surface of material prim `m`, if any.
    fn preview_surface(&self, m: &sdf::Path) -> Result<Option<Shader>> {
        let err = |e: anyhow::Error| self.prim_err(m, format!("surface shader: {e:#}"));
        let Some(material) = UsdMaterial::get(self.stage, m.clone()).map_err(err)? else {
            return Ok(None);
        };
        // The universal `outputs:surface` and its source, read here rather than by
        // `compute_surface_source`, which recurses without end on a target that is not a
        // property path (found by fuzzing).
        let output = material.surface_output();
        let Some(source) = output.connections().map_err(err)?.into_iter().next() else {
            return Ok(None);
        };
        self.require_property_path(m, "outputs:surface", &source)?;
        let Some(shader) = Shader::get(self.stage, source.prim_path()).map_err(err)? else {
            return Ok(None);
        };
        Ok((shader.id().map_err(err)?.as_deref() == Some("UsdPreviewSurface")).then_some(shader))
    }

    /// A material from the `UsdPreviewSurface` of material prim `m`; explicit `mitsuba:*`
    /// attributes on it win over the surface's scattering.
    fn preview_material(&mut self, m: &sdf::Path, double_sided: bool) -> Result<Material> {
        let explicit = self.explicit_bsdf(m)?;
        let Some(surface) = self.preview_surface(m)? else {
            if explicit.is_none() {
                self.scene.warnings.push(Warning(format!(
                    "material {}: no UsdPreviewSurface; grey diffuse used",
                    m.as_str()
                )));
            }
            return Ok(Material {
                name: m.as_str().to_string(),
                scattering: explicit.map_or(default_material().scattering, Scattering::Explicit),
                cutout: None,
                normal_map: None,
                emission: None,
            });
        };
        let sp = surface.path().clone();
        let emission = self.colour_input(&surface, "emissiveColor", Rgb::ZERO)?;
        if !emission.0.is_finite() || emission.0.min_element() < 0.0 {
            return Err(self.prim_err(
                &sp,
                format!(
                    "emissiveColor {} must be finite and non-negative",
                    emission.0
                ),
            ));
        }
        let mut cutout = None;
        let scattering = match explicit {
            Some(b) => Scattering::Explicit(b),
            // UsdPreviewSurface's defaults: diffuse 0.18, metallic 0, roughness 0.5,
            // opacity 1, ior 1.5.
            None => {
                let (base_color, base_color_texture) =
                    self.colour_input(&surface, "diffuseColor", Rgb::splat(0.18))?;
                let (metallic, metallic_texture) = self.scalar_input(&surface, "metallic", 0.0)?;
                let (roughness, roughness_texture) =
                    self.scalar_input(&surface, "roughness", 0.5)?;
                let (opacity, opacity_texture) = self.scalar_input(&surface, "opacity", 1.0)?;
                let (threshold, _) = self.scalar_input(&surface, "opacityThreshold", 0.0)?;
                let (ior, _) = self.scalar_input(&surface, "ior", 1.5)?;
                let cut_out = threshold > 0.0;
                // opacityThreshold > 0: the surface is there where opacity reaches it (an
                // alpha cut-out), and opaque.
                cutout = Some(Cutout {
                    alpha: if opacity_texture.is_some() {
                        1.0
                    } else {
                        opacity
                    },
                    texture: opacity_texture,
                    cutoff: threshold,
                })
                .filter(|c| cut_out && c.constant() != Some(true));
                // Transmission is 1 − opacity; through a texture, its scale and bias turn
                // v·s + b into 1 − (v·s + b).
                let transmission_texture = opacity_texture.filter(|_| !cut_out).map(|mut t| {
                    t.texture.scale = -t.texture.scale;
                    t.texture.bias = Vec4::ONE - t.texture.bias;
                    t
                });
                let transmission = match (cut_out, &transmission_texture) {
                    (true, _) => 0.0,
                    (false, Some(_)) => 1.0,
                    (false, None) => 1.0 - opacity.clamp(0.0, 1.0),
                };
                Scattering::Pbr(PbrParams {
                    base_color: base_color.clamp(Rgb::ZERO, Rgb::ONE),
                    base_color_texture,
                    metallic: metallic.clamp(0.0, 1.0),
                    metallic_texture,
                    roughness: roughness.clamp(0.0, 1.0),
                    roughness_texture,
                    transmission,
                    transmission_texture,
                    ior: if ior.is_finite() && ior >= 1.0 {
                        ior
                    } else {
                        1.5
                    },
                    thin_walled: false,
                })
            }
        };
        let (radiance, texture) = emission;
        let normal_map = self.normal_map(&surface)?;
        Ok(Material {
            name: m.as_str().to_string(),
            scattering,
            cutout,
            normal_map,
            emission: (radiance.max_element() > 0.0).then_some(Emission {
                radiance,
                texture,
                two_sided: double_sided,
            }),
        })
    }

    /// The `normal` input connected to a texture: a tangent-space normal map, its values
    /// after the texture node's scale and bias (UsdPreviewSurface: "the expected range is
    /// [-1, 1]", which an 8-bit image reaches through scale 2 and bias −1). Always read as
    /// raw data. An authored constant normal is the default (0, 0, 1), a no-op.
    fn normal_map(&mut self, shader: &Shader) -> Result<Option<NormalMap>> {
        let sp = shader.path().clone();
        Ok(match self.input(shader, "normal")? {
            Input::Texture {
                texture,
                channel: None,
            } => Some(NormalMap {
                texture: TexRef {
                    srgb: false,
                    ..texture
                },
            }),
            Input::Texture {
                channel: Some(_), ..
            } => {
                self.scene.warnings.push(Warning(format!(
                    "{}: inputs:normal reads one channel of a texture; the normal map is ignored",
                    sp.as_str()
                )));
                None
            }
            _ => None,
        })
    }

    /// A colour input: its value (or `default`), or 1 and the texture it is connected to.
    fn colour_input(
        &mut self,
        shader: &Shader,
        name: &str,
        default: Rgb,
    ) -> Result<(Rgb, Option<TexRef>)> {
        let sp = shader.path().clone();
        match self.input(shader, name)? {
            Input::Unset => Ok((default, None)),
            Input::Value(v) => {
                let c = v
                    .cast::<gf::Vec3f>()
                    .map_err(|_| self.prim_err(&sp, format!("inputs:{name} must be a colour")))?;
                Ok((Rgb::new(c.x, c.y, c.z), None))
            }
            Input::Texture {
                texture,
                channel: None,
            } => Ok((Rgb::ONE, Some(texture))),
            Input::Texture {
                channel: Some(_), ..
            } => {
                self.scene.warnings.push(Warning(format!(
                    "{}: inputs:{name} reads one channel of a texture, which a colour cannot; \
                     {default} used",
                    sp.as_str()
                )));
                Ok((default, None))
            }
        }
    }

    /// A scalar input: its value (or `default`), or 1 and the texture channel it is connected
    /// to (the red one for `rgb`).
    fn scalar_input(
        &mut self,
        shader: &Shader,
        name: &str,
        default: f32,
    ) -> Result<(f32, Option<ChannelRef>)> {
        let sp = shader.path().clone();
        match self.input(shader, name)? {
            Input::Unset => Ok((default, None)),
            Input::Value(v) => v
                .cast::<f32>()
                .ok()
                .filter(|x| x.is_finite())
                .map(|x| (x, None))
                .ok_or_else(|| {
                    self.prim_err(&sp, format!("inputs:{name} must be a finite number"))
                }),
            Input::Texture { texture, channel } => Ok((
                1.0,
                Some(ChannelRef {
                    texture,
                    channel: channel.unwrap_or(0),
                }),
            )),
        }
    }

    /// What input `inputs:name` of `shader` is: authored, or connected (through interface
    /// inputs) to a texture.
    fn input(&mut self, shader: &Shader, name: &str) -> Result<Input> {
        let sp = shader.path().clone();
        let err = |e: anyhow::Error| self.prim_err(&sp, format!("inputs:{name}: {e:#}"));
        let mut attr = self
            .stage
            .attribute(sp.append_property(format!("inputs:{name}")).map_err(&err)?);
        for _ in 0..MAX_HOPS {
            let Some(source) = attr.connections().map_err(err)?.into_iter().next() else {
                return Ok(match sample(&attr, self.time).map_err(err)? {
                    Some(v) => Input::Value(v),
                    None => Input::Unset,
                });
            };
            self.require_property_path(&sp, &format!("inputs:{name}"), &source)?;
            let (prim, property) = source
                .split_property()
                .map(|(p, n)| (p, n.to_string()))
                .ok_or_else(|| {
                    self.prim_err(
                        &sp,
                        format!(
                            "inputs:{name} connects to {}, not a property",
                            source.as_str()
                        ),
                    )
                })?;
            if let Some(output) = property.strip_prefix("outputs:") {
                return self.texture_output(&sp, name, &prim, output);
            }
            attr = self.stage.attribute(source);
        }
        Err(self.prim_err(
            &sp,
            format!("inputs:{name}: connections loop or nest too deep"),
        ))
    }

    /// Input `name` of `surface` connected to output `output` of shader `node`.
    fn texture_output(
        &mut self,
        surface: &sdf::Path,
        name: &str,
        node: &sdf::Path,
        output: &str,
    ) -> Result<Input> {
        let Some(tex) = Shader::get(self.stage, node.clone())
            .map_err(|e| self.prim_err(node, format!("{e:#}")))?
        else {
            return Err(self.prim_err(
                surface,
                format!(
                    "inputs:{name} connects to {}, which is not a shader",
                    node.as_str()
                ),
            ));
        };
        let id = tex
            .id()
            .map_err(|e| self.prim_err(node, format!("{e:#}")))?;
        if id.as_deref() != Some("UsdUVTexture") {
            self.scene.warnings.push(Warning(format!(
                "{}: inputs:{name} connects to a {} shader, which is not supported; its \
                 value is left at the default",
                surface.as_str(),
                id.as_deref().unwrap_or("typeless")
            )));
            return Ok(Input::Unset);
        }
        let channel = match output {
            "rgb" | "rgba" => None,
            "r" => Some(0),
            "g" => Some(1),
            "b" => Some(2),
            "a" => Some(3),
            other => return Err(self.prim_err(node, format!("UsdUVTexture has no output {other}"))),
        };
        let texture = self.uv_texture(&tex)?;
        Ok(Input::Texture { texture, channel })
    }

    /// A `UsdUVTexture` node as a texture reference (its image loaded on first use).
    fn uv_texture(&mut self, tex: &Shader) -> Result<TexRef> {
        let node = tex.path().clone();
        let value = |this: &Self, input: &str| -> Result<Option<sdf::Value>> {
            let attr = this.stage.attribute(
                node.append_property(format!("inputs:{input}"))
                    .map_err(|e| this.prim_err(&node, format!("{e:#}")))?,
            );
            sample(&attr, this.time)
                .map_err(|e| this.prim_err(&node, format!("inputs:{input}: {e:#}")))
        };
        let token = |this: &Self, input: &str, default: &str| -> Result<String> {
            Ok(value(this, input)?
                .and_then(|v| v.cast::<String>().ok())
                .unwrap_or_else(|| default.to_string()))
        };
        let float4 = |this: &Self, input: &str, default: Vec4| -> Result<Vec4> {
            Ok(match value(this, input)? {
                Some(sdf::Value::Vec4f(c)) => Vec4::new(c.x, c.y, c.z, c.w),
                Some(_) => {
                    return Err(this.prim_err(&node, format!("inputs:{input} must be a float4")))
                }
                None => default,
            })
        };
        let Some(file) = value(self, "file")?.and_then(|v| match v {
            sdf::Value::AssetPath(a) => Some(a),
            _ => None,
        }) else {
            return Err(self.prim_err(&node, "UsdUVTexture has no inputs:file"));
        };
        let Some(resolved) = file.resolved_path().map(str::to_string) else {
            return Err(self.prim_err(&node, format!("texture file @{}@ not found", file.as_str())));
        };
        let (index, auto_srgb) = self.load_texture(&node, &resolved)?;
        let srgb = match token(self, "sourceColorSpace", "auto")?.as_str() {
            "raw" => false,
            "sRGB" => true,
            _ => auto_srgb,
        };
        let wrap = |mode: String| match mode.as_str() {
            "black" => Wrap::Black,
            "clamp" => Wrap::Clamp,
            "mirror" => Wrap::Mirror,
            _ => Wrap::Repeat,
        };
        let (transform, uv_set) = self.st_source(&node)?;
        self.uv_sets.push(uv_set);
        Ok(TexRef {
            texture: index,
            wrap_s: wrap(token(self, "wrapS", "useMetadata")?),
            wrap_t: wrap(token(self, "wrapT", "useMetadata")?),
            // USD's t runs up the image, the IR's image rows down.
            transform: Affine2::from_cols_array(&[1.0, 0.0, 0.0, -1.0, 0.0, 1.0]) * transform,
            srgb,
            scale: float4(self, "scale", Vec4::ONE)?,
            bias: float4(self, "bias", Vec4::ZERO)?,
        })
    }

    /// The image at `resolved` (a file, or a member of a usdz package), loaded once; and
    /// whether `auto` reads it as sRGB.
    fn load_texture(&mut self, node: &sdf::Path, resolved: &str) -> Result<(usize, bool)> {
        if let Some(&t) = self.textures.get(resolved) {
            return Ok(t);
        }
        let (texture, auto_srgb) = self.read_image(node, resolved)?;
        self.scene.textures.push(texture);
        let t = (self.scene.textures.len() - 1, auto_srgb);
        self.textures.insert(resolved.to_string(), t);
        Ok(t)
    }

    /// Decode the image at `resolved` (a file, or a member of a usdz package), which prim
    /// `node` names; also whether `auto` reads it as sRGB.
    pub(super) fn read_image(&self, node: &sdf::Path, resolved: &str) -> Result<(Texture, bool)> {
        use openusd::ar::Resolver;
        let bytes = openusd::ar::DefaultResolver::new()
            .open_asset(&openusd::ar::ResolvedPath::new(resolved))
            .and_then(|mut a| a.read_all())
            .map_err(|e| self.prim_err(node, format!("cannot read texture {resolved}: {e}")))?;
        Texture::decode(resolved, &bytes)
            .map_err(|e| self.prim_err(node, format!("texture {resolved} does not decode: {e}")))
    }

    /// Where texture node `node` gets its `st`: the texture transform (UsdTransform2d, or
    /// identity) and the primvar a `UsdPrimvarReader_float2` names.
    fn st_source(&mut self, node: &sdf::Path) -> Result<(Affine2, String)> {
        let mut transform = Affine2::IDENTITY;
        let mut at = node.clone();
        let mut input = "st";
        for _ in 0..MAX_HOPS {
            let attr = self.stage.attribute(
                at.append_property(format!("inputs:{input}"))
                    .map_err(|e| self.prim_err(&at, format!("{e:#}")))?,
            );
            let Some(source) = attr
                .connections()
                .map_err(|e| self.prim_err(&at, format!("{e:#}")))?
                .into_iter()
                .next()
            else {
                return Ok((transform, DEFAULT_UV_SET.to_string()));
            };
            self.require_property_path(&at, &format!("inputs:{input}"), &source)?;
            let prim = source.prim_path();
            let id = Shader::get(self.stage, prim.clone())
                .ok()
                .flatten()
                .and_then(|s| s.id().ok().flatten());
            let value = |this: &Self, name: &str| {
                prim.append_property(format!("inputs:{name}"))
                    .ok()
                    .and_then(|p| sample(&this.stage.attribute(p), this.time).ok().flatten())
            };
            match id.as_deref() {
                Some(reader) if reader.starts_with("UsdPrimvarReader_") => {
                    let name = value(self, "varname")
                        .and_then(|v| v.cast::<String>().ok())
                        .unwrap_or_else(|| DEFAULT_UV_SET.to_string());
                    return Ok((transform, name));
                }
                Some("UsdTransform2d") => {
                    let v2 = |this: &Self, name: &str, default: Vec2| {
                        value(this, name)
                            .and_then(|v| match v {
                                sdf::Value::Vec2f(v) => Some(Vec2::new(v.x, v.y)),
                                _ => None,
                            })
                            .unwrap_or(default)
                    };
                    let rotation = value(self, "rotation")
                        .and_then(|v| v.cast::<f32>().ok())
                        .unwrap_or(0.0);
                    // Scale, then rotate (degrees, counter-clockwise), then translate.
                    let local = Affine2::from_scale_angle_translation(
                        v2(self, "scale", Vec2::ONE),
                        rotation.to_radians(),
                        v2(self, "translation", Vec2::ZERO),
                    );
                    transform *= local;
                    at = prim;
                    input = "in";
                }
                other => {
                    self.scene.warnings.push(Warning(format!(
                        "{}: st comes from a {} shader, which is not supported; primvars:st used",
                        node.as_str(),
                        other.unwrap_or("typeless")
                    )));
                    return Ok((transform, DEFAULT_UV_SET.to_string()));
                }
            }
        }
        Err(self.prim_err(node, "inputs:st: connections loop or nest too deep"))
    }
}

/// Whether `path` is an absolute prim path of identifiers followed by a namespaced property
/// name. openusd 0.6's parser accepts connection targets that are not, and then recurses
/// without end resolving them (found by fuzzing), so they are refused first.
fn is_plain_property_path(path: &sdf::Path) -> bool {
    let Some((prim, property)) = path.as_str().rsplit_once('.') else {
        return false;
    };
    super::stage::is_plain_prim_path(prim) && sdf::Path::is_valid_namespace_identifier(property)
}

/// A grey (0.18) diffuse material, for meshes without a binding.
fn default_material() -> Material {
    Material {
        name: "default".into(),
        scattering: Scattering::Pbr(PbrParams::constant(Rgb::splat(0.18), 0.0, 1.0)),
        cutout: None,
        normal_map: None,
        emission: None,
    }
}

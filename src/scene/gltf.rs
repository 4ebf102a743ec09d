//! glTF 2.0 / GLB import into the scene IR.
//!
//! Validation happens here, up front, and every problem names the file and the object: a GLB
//! with the wrong magic or truncated, broken JSON, a missing or short buffer, an accessor that
//! reaches past its buffer, an index past the vertex count, a NaN or infinite position, a texture
//! that does not decode. Degenerate (zero-area) triangles are dropped with a warning.

use super::camera::{Camera, Projection};
use super::light::{LightKind, PunctualLight};
use super::material::{Cutout, Emission, Material, PbrParams, Scattering};
use super::mesh::{drop_degenerate, Mesh};
use super::model::{Scene, Warning};
use super::normal_map::NormalMap;
use super::texture::{ChannelRef, TexRef, Texture, Wrap};
use crate::bsdf::mitsuba::parse_bsdf;
use crate::error::{Error, Result};
use crate::spectrum::Rgb;
use ::gltf as g;
use glam::{Affine2, Mat3, Mat4, Vec2, Vec3, Vec4};
use std::path::Path;

pub(super) fn import(path: &Path, bytes: &[u8]) -> Result<Scene> {
    let fmt = |reason: String| Error::GltfFormat {
        path: path.to_path_buf(),
        reason,
    };
    let is_glb_name = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if is_glb_name && !bytes.starts_with(b"glTF") {
        return Err(fmt(
            "a .glb file must start with the magic bytes \"glTF\"".into()
        ));
    }
    // Parse, check what gltf-json's validation would index unchecked, then validate.
    let g::Gltf { document, blob } =
        g::Gltf::from_slice_without_validation(bytes).map_err(|e| fmt(describe_gltf_error(&e)))?;
    let json = document.into_json();
    check_unchecked_references(&json).map_err(fmt)?;
    let doc = g::Gltf {
        document: g::Document::from_json(json).map_err(|e| fmt(describe_gltf_error(&e)))?,
        blob,
    };
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = load_buffers(path, &doc, base)?;
    let mut scene = Scene {
        path: path.to_path_buf(),
        ..Default::default()
    };

    for ext in doc.extensions_used() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            scene.warnings.push(Warning(format!(
                "extension {ext} is not supported and is ignored"
            )));
        }
    }

    scene.textures = load_textures(path, &doc, base, &buffers)?;
    let image_of_texture: Vec<usize> = doc.textures().map(|t| t.source().index()).collect();
    for m in doc.materials() {
        scene.materials.push(convert_material(
            path,
            &m,
            &image_of_texture,
            &mut scene.warnings,
        )?);
    }
    // Primitives without a material use the glTF default (white, metallic 1, roughness 1).
    let default_material = scene.materials.len();
    scene.materials.push(Material {
        name: "(default)".into(),
        scattering: Scattering::Pbr(PbrParams::constant(Rgb::ONE, 1.0, 1.0)),
        cutout: None,
        normal_map: None,
        emission: None,
    });

    let roots: Vec<g::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(s) => s.nodes().collect(),
        None => doc.nodes().collect(),
    };
    // Depth-first in document order (children pushed in reverse), so cameras and meshes keep
    // the order the file gives them.
    let mut stack: Vec<(g::Node, Mat4, usize)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, Mat4::IDENTITY, 0))
        .collect();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > 256 {
            return Err(fmt("the node hierarchy is deeper than 256 levels".into()));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            return Err(fmt(format!(
                "node \"{}\" has a non-finite transform",
                node_name(&node)
            )));
        }
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                if let Some(m) = convert_primitive(
                    path,
                    &mesh,
                    &prim,
                    world,
                    &buffers,
                    default_material,
                    &mut scene.warnings,
                )? {
                    scene.meshes.push(m);
                }
            }
        }
        if let Some(cam) = node.camera() {
            if let Some(c) = convert_camera(&node, &cam, world) {
                scene.cameras.push(c);
            }
        }
        if let Some(light) = node.light() {
            scene.lights.push(convert_light(&node, &light, world));
        }
        let children: Vec<g::Node> = node.children().collect();
        for child in children.into_iter().rev() {
            stack.push((child, world, depth + 1));
        }
    }
    Ok(scene)
}

const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_volume",
    "KHR_materials_emissive_strength",
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "KHR_materials_specular",
];

fn describe_gltf_error(e: &g::Error) -> String {
    match e {
        g::Error::Binary(b) => format!("malformed or truncated GLB container ({b:?})"),
        g::Error::Deserialize(d) => format!("broken JSON: {d}"),
        g::Error::Validation(v) => {
            let list: Vec<String> = v
                .iter()
                .take(5)
                .map(|(p, err)| format!("{p}: {err}"))
                .collect();
            format!("invalid document: {}", list.join("; "))
        }
        other => other.to_string(),
    }
}

fn node_name(n: &g::Node) -> String {
    n.name()
        .map(str::to_string)
        .unwrap_or_else(|| format!("#{}", n.index()))
}

fn load_buffers(path: &Path, doc: &g::Gltf, base: &Path) -> Result<Vec<Vec<u8>>> {
    let mut blob = doc.blob.clone();
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let err = |reason: String| Error::Buffer {
            path: path.to_path_buf(),
            buffer: buffer.index(),
            reason,
        };
        let data = g::buffer::Data::from_source_and_blob(buffer.source(), Some(base), &mut blob)
            .map_err(|e| match (&buffer.source(), e) {
                (g::buffer::Source::Uri(uri), g::Error::Io(io)) => {
                    err(format!("cannot read \"{uri}\": {io}"))
                }
                (g::buffer::Source::Bin, _) => err("the GLB has no binary chunk".into()),
                (_, e) => err(e.to_string()),
            })?;
        if data.0.len() < buffer.length() {
            return Err(err(format!(
                "holds {} bytes but declares {}",
                data.0.len(),
                buffer.length()
            )));
        }
        out.push(data.0);
    }
    Ok(out)
}

fn load_textures(
    path: &Path,
    doc: &g::Gltf,
    base: &Path,
    buffers: &[Vec<u8>],
) -> Result<Vec<Texture>> {
    let data: Vec<g::buffer::Data> = buffers.iter().map(|b| g::buffer::Data(b.clone())).collect();
    let mut out = Vec::new();
    for image in doc.images() {
        let name = image
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| match image.source() {
                g::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => uri.to_string(),
                _ => format!("#{}", image.index()),
            });
        if let g::image::Source::View { view, .. } = image.source() {
            if view.offset() + view.length()
                > buffers.get(view.buffer().index()).map_or(0, Vec::len)
            {
                return Err(Error::Texture {
                    path: path.to_path_buf(),
                    image: name,
                    reason: "its buffer view reaches past the end of its buffer".into(),
                });
            }
        }
        let img = g::image::Data::from_source(image.source(), Some(base), &data).map_err(|e| {
            Error::Texture {
                path: path.to_path_buf(),
                image: name.clone(),
                reason: format!("does not decode: {e}"),
            }
        })?;
        out.push(
            to_texture(name, img).map_err(|(image, reason)| Error::Texture {
                path: path.to_path_buf(),
                image,
                reason,
            })?,
        );
    }
    Ok(out)
}

fn to_texture(name: String, img: g::image::Data) -> std::result::Result<Texture, (String, String)> {
    use g::image::Format as F;
    let n = (img.width as usize) * (img.height as usize);
    let (channels, bytes_per) = match img.format {
        F::R8 => (1, 1),
        F::R8G8 => (2, 1),
        F::R8G8B8 => (3, 1),
        F::R8G8B8A8 => (4, 1),
        F::R16 => (1, 2),
        F::R16G16 => (2, 2),
        F::R16G16B16 => (3, 2),
        F::R16G16B16A16 => (4, 2),
        F::R32G32B32FLOAT => (3, 4),
        F::R32G32B32A32FLOAT => (4, 4),
    };
    if n == 0 || img.pixels.len() < n * channels * bytes_per {
        return Err((name, "decoded to an empty or short image".into()));
    }
    let value = |i: usize| -> f32 {
        let o = i * bytes_per;
        match bytes_per {
            1 => img.pixels[o] as f32 / 255.0,
            2 => u16::from_le_bytes([img.pixels[o], img.pixels[o + 1]]) as f32 / 65535.0,
            _ => {
                let v = f32::from_le_bytes([
                    img.pixels[o],
                    img.pixels[o + 1],
                    img.pixels[o + 2],
                    img.pixels[o + 3],
                ]);
                if v.is_finite() {
                    v
                } else {
                    0.0
                }
            }
        }
    };
    let texels = (0..n)
        .map(|p| {
            let c = |k: usize| value(p * channels + k);
            match channels {
                1 => Vec4::new(c(0), c(0), c(0), 1.0),
                2 => Vec4::new(c(0), c(0), c(0), c(1)),
                3 => Vec4::new(c(0), c(1), c(2), 1.0),
                _ => Vec4::new(c(0), c(1), c(2), c(3)),
            }
        })
        .collect();
    Ok(Texture {
        name,
        width: img.width,
        height: img.height,
        texels,
    })
}

fn tex_ref(
    info: &g::texture::Info,
    image_of_texture: &[usize],
    srgb: bool,
    warnings: &mut Vec<Warning>,
    what: &str,
) -> Option<TexRef> {
    let reference = (info.texture(), info.tex_coord(), info.texture_transform());
    texture_ref(reference, image_of_texture, srgb, warnings, what)
}

/// A material's normal map: glTF's `normalTexture`, 2 × texel − 1 with x and y times its
/// `scale` (the glTF crate reads no KHR_texture_transform on it).
fn normal_map(
    m: &g::Material,
    image_of_texture: &[usize],
    warnings: &mut Vec<Warning>,
    what: &str,
) -> Option<NormalMap> {
    let n = m.normal_texture()?;
    let s = n.scale();
    let reference = (n.texture(), n.tex_coord(), None);
    let texture = texture_ref(reference, image_of_texture, false, warnings, what)?;
    Some(NormalMap {
        texture: TexRef {
            scale: Vec4::new(2.0 * s, 2.0 * s, 2.0, 1.0),
            bias: Vec4::new(-s, -s, -1.0, 0.0),
            ..texture
        },
    })
}

/// A texture reference from a glTF texture, its TEXCOORD set and its KHR_texture_transform.
fn texture_ref(
    (tex, tex_coord, texture_transform): (
        g::texture::Texture,
        u32,
        Option<g::texture::TextureTransform>,
    ),
    image_of_texture: &[usize],
    srgb: bool,
    warnings: &mut Vec<Warning>,
    what: &str,
) -> Option<TexRef> {
    let sampler = tex.sampler();
    let wrap = |w: g::texture::WrappingMode| match w {
        g::texture::WrappingMode::ClampToEdge => Wrap::Clamp,
        g::texture::WrappingMode::MirroredRepeat => Wrap::Mirror,
        g::texture::WrappingMode::Repeat => Wrap::Repeat,
    };
    let mut transform = Affine2::IDENTITY;
    let mut tex_coord = tex_coord;
    if let Some(t) = texture_transform {
        // KHR_texture_transform: T · R · S, with the rotation's sign as the extension defines it.
        let [ox, oy] = t.offset();
        let [sx, sy] = t.scale();
        let (s, c) = t.rotation().sin_cos();
        let rot = Mat3::from_cols(Vec3::new(c, -s, 0.0), Vec3::new(s, c, 0.0), Vec3::Z);
        let m =
            Mat3::from_translation(Vec2::new(ox, oy)) * rot * Mat3::from_scale(Vec2::new(sx, sy));
        transform = Affine2::from_mat3(m);
        if let Some(tc) = t.tex_coord() {
            tex_coord = tc;
        }
    }
    if tex_coord != 0 {
        warnings.push(Warning(format!(
            "{what} uses TEXCOORD_{tex_coord}; only TEXCOORD_0 is read, so the texture is ignored"
        )));
        return None;
    }
    Some(TexRef {
        texture: *image_of_texture.get(tex.index())?,
        wrap_s: wrap(sampler.wrap_s()),
        wrap_t: wrap(sampler.wrap_t()),
        transform,
        srgb,
        scale: Vec4::ONE,
        bias: Vec4::ZERO,
    })
}

fn convert_material(
    path: &Path,
    m: &g::Material,
    image_of_texture: &[usize],
    warnings: &mut Vec<Warning>,
) -> Result<Material> {
    let name = m
        .name()
        .map(str::to_string)
        .unwrap_or_else(|| format!("#{}", m.index().unwrap_or(0)));
    let err = |reason: String| Error::Material {
        path: path.to_path_buf(),
        material: name.clone(),
        reason,
    };
    let extras: Option<serde_json::Value> = match m.extras() {
        Some(raw) => Some(
            serde_json::from_str(raw.get())
                .map_err(|e| err(format!("extras are not valid JSON: {e}")))?,
        ),
        None => None,
    };
    let what = format!("material \"{name}\"");
    let pbr = m.pbr_metallic_roughness();
    let scattering = match extras.as_ref().and_then(|x| x.get("mitsuba")) {
        // Emitter descriptions carry their BSDF in `mitsuba_bsdf`.
        Some(desc) if desc.get("type").and_then(|t| t.as_str()) == Some("area") => {
            match extras.as_ref().and_then(|x| x.get("mitsuba_bsdf")) {
                Some(b) => Scattering::Explicit(parse_bsdf(b).map_err(err)?),
                None => pbr_scattering(m, &pbr, image_of_texture, warnings, &what),
            }
        }
        Some(desc) => Scattering::Explicit(parse_bsdf(desc).map_err(err)?),
        None => pbr_scattering(m, &pbr, image_of_texture, warnings, &what),
    };
    let strength = m.emissive_strength().unwrap_or(1.0);
    let mut radiance = Rgb::from(m.emissive_factor()) * strength;
    if let Some(r) = extras
        .as_ref()
        .and_then(|x| x.get("mitsuba"))
        .filter(|d| d.get("type").and_then(|t| t.as_str()) == Some("area"))
        .and_then(|d| d.get("radiance"))
    {
        // The explicit area emitter wins over emissiveFactor × strength.
        let v: Vec<f32> = match r {
            serde_json::Value::Array(a) => a
                .iter()
                .filter_map(|x| x.as_f64())
                .map(|x| x as f32)
                .collect(),
            x => x.as_f64().map(|x| vec![x as f32; 3]).unwrap_or_default(),
        };
        if v.len() != 3 {
            return Err(err(
                "extras.mitsuba.radiance must be a number or an [r, g, b] list".into(),
            ));
        }
        radiance = Rgb::from_slice(&v);
    }
    if !radiance.is_finite() || radiance.min_element() < 0.0 {
        return Err(err(format!(
            "emitted radiance {radiance} must be finite and non-negative"
        )));
    }
    let texture = m
        .emissive_texture()
        .and_then(|t| tex_ref(&t, image_of_texture, true, warnings, &what));
    let emission = (radiance.max_element() > 0.0).then_some(Emission {
        radiance,
        texture,
        two_sided: m.double_sided(),
    });
    // glTF's alpha: the base colour's, MASK cutting at alphaCutoff (0.5 by default). BLEND
    // is drawn opaque (docs/scene.md): wpbgi has no partial coverage.
    let cutout = match m.alpha_mode() {
        g::material::AlphaMode::Mask => {
            let pbr = m.pbr_metallic_roughness();
            Some(Cutout {
                alpha: pbr.base_color_factor()[3].clamp(0.0, 1.0),
                texture: pbr
                    .base_color_texture()
                    .and_then(|t| tex_ref(&t, image_of_texture, false, warnings, &what))
                    .map(|texture| ChannelRef {
                        texture,
                        channel: 3,
                    }),
                cutoff: m.alpha_cutoff().unwrap_or(0.5),
            })
            .filter(|c| c.constant() != Some(true))
        }
        _ => None,
    };
    Ok(Material {
        name,
        scattering,
        emission,
        cutout,
        normal_map: normal_map(m, image_of_texture, warnings, &what),
    })
}

fn pbr_scattering(
    m: &g::Material,
    pbr: &g::material::PbrMetallicRoughness,
    image_of_texture: &[usize],
    warnings: &mut Vec<Warning>,
    what: &str,
) -> Scattering {
    let [r, g_, b, _] = pbr.base_color_factor();
    let transmission = m.transmission();
    // Roughness in G, metalness in B of one image.
    let metallic_roughness = pbr
        .metallic_roughness_texture()
        .and_then(|t| tex_ref(&t, image_of_texture, false, warnings, what));
    Scattering::Pbr(PbrParams {
        base_color: Rgb::new(r, g_, b).clamp(Rgb::ZERO, Rgb::ONE),
        base_color_texture: pbr
            .base_color_texture()
            .and_then(|t| tex_ref(&t, image_of_texture, true, warnings, what)),
        metallic: pbr.metallic_factor().clamp(0.0, 1.0),
        metallic_texture: metallic_roughness.map(|texture| ChannelRef {
            texture,
            channel: 2,
        }),
        roughness: pbr.roughness_factor().clamp(0.0, 1.0),
        roughness_texture: metallic_roughness.map(|texture| ChannelRef {
            texture,
            channel: 1,
        }),
        transmission: transmission
            .as_ref()
            .map_or(0.0, |t| t.transmission_factor().clamp(0.0, 1.0)),
        transmission_texture: transmission
            .as_ref()
            .and_then(|t| t.transmission_texture())
            .and_then(|t| tex_ref(&t, image_of_texture, false, warnings, what))
            .map(|texture| ChannelRef {
                texture,
                channel: 0,
            }),
        ior: m
            .ior()
            .filter(|x| x.is_finite() && *x >= 1.0)
            .unwrap_or(1.5),
        // glTF: without a volume, or with zero thickness, the surface is thin-walled.
        thin_walled: m.volume().is_none_or(|v| v.thickness_factor() <= 0.0),
    })
}

/// What gltf 1.4 reads unchecked and panics on (found by fuzzing): gltf-json's validation
/// indexes the accessor a primitive's POSITION names without a bounds check, and images are
/// assumed complete. Checked before validation.
fn check_unchecked_references(root: &g::json::Root) -> std::result::Result<(), String> {
    use g::json::validation::Checked;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let Some(position) = prim
                .attributes
                .get(&Checked::Valid(g::json::mesh::Semantic::Positions))
            else {
                continue;
            };
            if position.value() >= root.accessors.len() {
                return Err(format!(
                    "mesh {m}, primitive {p}: POSITION names accessor {}, but the file has {} \
                     accessors",
                    position.value(),
                    root.accessors.len()
                ));
            }
        }
    }
    // The gltf crate's `Image::source` unwraps the MIME type of an image in a buffer view and
    // the URI of any other (found by fuzzing).
    for (i, image) in root.images.iter().enumerate() {
        let complete = match &image.buffer_view {
            Some(view) => image.mime_type.is_some() && view.value() < root.buffer_views.len(),
            None => image.uri.is_some(),
        };
        if !complete {
            return Err(format!(
                "image {i} needs a bufferView with a mimeType, or a uri"
            ));
        }
    }
    Ok(())
}

/// Check that an accessor's elements lie inside its buffer before anything reads them.
fn check_accessor(a: &g::Accessor, buffers: &[Vec<u8>]) -> std::result::Result<(), String> {
    if a.sparse().is_some() {
        return Err(format!(
            "accessor {} is sparse, which is not supported for geometry",
            a.index()
        ));
    }
    let Some(view) = a.view() else {
        return Err(format!("accessor {} has no buffer view", a.index()));
    };
    let buf_len = buffers.get(view.buffer().index()).map_or(0, Vec::len);
    if view
        .offset()
        .checked_add(view.length())
        .is_none_or(|end| end > buf_len)
    {
        return Err(format!(
            "buffer view {} reaches past the end of buffer {}",
            view.index(),
            view.buffer().index()
        ));
    }
    let elem = a.size();
    let stride = view.stride().unwrap_or(elem);
    if a.count() > 0 {
        let need = stride
            .checked_mul(a.count() - 1)
            .and_then(|n| n.checked_add(a.offset()))
            .and_then(|n| n.checked_add(elem));
        if need.is_none_or(|need| need > view.length()) {
            return Err(format!(
                "accessor {} reads past the end of buffer view {} ({} elements of {elem} bytes, \
                 stride {stride}, from byte {})",
                a.index(),
                view.index(),
                a.count(),
                a.offset()
            ));
        }
    }
    Ok(())
}

/// Refuse an accessor whose element type the glTF specification does not allow for its use
/// (the gltf crate's readers assume the allowed types and panic on others).
fn check_element_type(
    a: &g::Accessor,
    what: &str,
    dimensions: g::accessor::Dimensions,
    components: &[g::accessor::DataType],
) -> std::result::Result<(), String> {
    if a.dimensions() != dimensions || !components.contains(&a.data_type()) {
        return Err(format!(
            "{what} accessor {} holds {:?} of {:?}, where glTF allows {dimensions:?} of {}",
            a.index(),
            a.dimensions(),
            a.data_type(),
            components
                .iter()
                .map(|c| format!("{c:?}"))
                .collect::<Vec<_>>()
                .join(" or ")
        ));
    }
    Ok(())
}

fn convert_primitive(
    path: &Path,
    mesh: &g::Mesh,
    prim: &g::Primitive,
    world: Mat4,
    buffers: &[Vec<u8>],
    default_material: usize,
    warnings: &mut Vec<Warning>,
) -> Result<Option<Mesh>> {
    let mesh_name = mesh
        .name()
        .map(str::to_string)
        .unwrap_or_else(|| format!("#{}", mesh.index()));
    let err = |reason: String| Error::Mesh {
        path: path.to_path_buf(),
        mesh: mesh_name.clone(),
        primitive: prim.index(),
        reason,
    };
    use g::mesh::Mode;
    let mode = prim.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        warnings.push(Warning(format!(
            "mesh \"{mesh_name}\" primitive {} is {mode:?}, not triangles, and is skipped",
            prim.index()
        )));
        return Ok(None);
    }
    use g::accessor::{DataType as C, Dimensions as D};
    let pos_acc = prim
        .get(&g::Semantic::Positions)
        .ok_or_else(|| err("has no POSITION attribute".into()))?;
    check_accessor(&pos_acc, buffers).map_err(&err)?;
    check_element_type(&pos_acc, "POSITION", D::Vec3, &[C::F32]).map_err(&err)?;
    let mut accessors = vec![];
    for (sem, dimensions, components) in [
        (g::Semantic::Normals, D::Vec3, &[C::F32][..]),
        (
            g::Semantic::TexCoords(0),
            D::Vec2,
            &[C::F32, C::U8, C::U16][..],
        ),
    ] {
        if let Some(a) = prim.get(&sem) {
            check_accessor(&a, buffers).map_err(&err)?;
            check_element_type(&a, &format!("{sem:?}"), dimensions, components).map_err(&err)?;
            if a.count() != pos_acc.count() {
                return Err(err(format!(
                    "attribute {sem:?} has {} elements but POSITION has {}",
                    a.count(),
                    pos_acc.count()
                )));
            }
            accessors.push(a);
        }
    }
    if let Some(a) = prim.indices() {
        check_accessor(&a, buffers).map_err(&err)?;
        check_element_type(&a, "index", D::Scalar, &[C::U8, C::U16, C::U32]).map_err(&err)?;
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let local: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(|| err("cannot read POSITION".into()))?
        .map(Vec3::from)
        .collect();
    let positions: Vec<Vec3> = local.iter().map(|p| world.transform_point3(*p)).collect();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(err(format!(
            "vertex {i} has a NaN or infinite position {}",
            local[i]
        )));
    }
    let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
    let normals = reader.read_normals().map(|it| {
        it.map(|n| {
            let w = normal_matrix * Vec3::from(n);
            w.try_normalize().unwrap_or(Vec3::ZERO)
        })
        .collect::<Vec<_>>()
    });
    let uvs = reader
        .read_tex_coords(0)
        .map(|t| t.into_f32().map(Vec2::from).collect::<Vec<_>>());
    let flat: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..positions.len() as u32).collect(),
    };
    let n = positions.len() as u32;
    if let Some(&bad) = flat.iter().find(|&&i| i >= n) {
        return Err(err(format!(
            "index {bad} is out of range (the primitive has {n} vertices)"
        )));
    }
    let mut tris: Vec<[u32; 3]> = match mode {
        Mode::Triangles => flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        Mode::TriangleStrip => (2..flat.len())
            .map(|i| {
                if i % 2 == 0 {
                    [flat[i - 2], flat[i - 1], flat[i]]
                } else {
                    [flat[i - 1], flat[i - 2], flat[i]]
                }
            })
            .collect(),
        _ => (2..flat.len())
            .map(|i| [flat[0], flat[i - 1], flat[i]])
            .collect(),
    };
    // A mirroring transform flips the winding; restore counter-clockwise front faces.
    if Mat3::from_mat4(world).determinant() < 0.0 {
        for t in &mut tris {
            t.swap(1, 2);
        }
    }
    let dropped = drop_degenerate(&positions, &mut tris);
    if dropped > 0 {
        warnings.push(Warning(format!(
            "mesh \"{mesh_name}\" primitive {}: dropped {dropped} degenerate (zero-area) triangles",
            prim.index(),
        )));
    }
    if tris.is_empty() {
        return Ok(None);
    }
    Ok(Some(Mesh {
        name: mesh_name.clone(),
        positions,
        normals: normals.filter(|n| n.iter().all(|v| *v != Vec3::ZERO)),
        uvs,
        triangles: tris,
        material: prim.material().index().unwrap_or(default_material),
    }))
}

fn rigid_axes(world: Mat4) -> (Vec3, Vec3, Vec3, Vec3) {
    let right = world.transform_vector3(Vec3::X).normalize_or_zero();
    let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
    let back = world.transform_vector3(Vec3::Z).normalize_or_zero();
    (world.transform_point3(Vec3::ZERO), right, up, -back)
}

fn convert_camera(node: &g::Node, cam: &g::Camera, world: Mat4) -> Option<Camera> {
    let (position, right, up, forward) = rigid_axes(world);
    if right == Vec3::ZERO || up == Vec3::ZERO || forward == Vec3::ZERO {
        return None;
    }
    let projection = match cam.projection() {
        g::camera::Projection::Perspective(p) => Projection::Perspective { yfov: p.yfov() },
        g::camera::Projection::Orthographic(o) => Projection::Orthographic {
            xmag: o.xmag(),
            ymag: o.ymag(),
        },
    };
    let name = cam
        .name()
        .map(str::to_string)
        .unwrap_or_else(|| node_name(node));
    Some(Camera {
        name,
        position,
        right,
        up,
        forward,
        projection,
        width: Camera::DEFAULT_SIZE.0,
        height: Camera::DEFAULT_SIZE.1,
    })
}

fn convert_light(
    node: &g::Node,
    light: &g::khr_lights_punctual::Light,
    world: Mat4,
) -> PunctualLight {
    use g::khr_lights_punctual::Kind;
    let (position, _, _, forward) = rigid_axes(world);
    let kind = match light.kind() {
        Kind::Point => LightKind::Point,
        Kind::Directional => LightKind::Directional,
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => LightKind::Spot {
            cos_inner: inner_cone_angle.cos(),
            cos_outer: outer_cone_angle.cos(),
        },
    };
    let intensity = Rgb::from(light.color()) * light.intensity().max(0.0);
    PunctualLight {
        name: light
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| node_name(node)),
        kind,
        position,
        direction: forward,
        intensity: if intensity.is_finite() {
            intensity
        } else {
            Rgb::ZERO
        },
    }
}

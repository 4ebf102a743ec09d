//! USD import (`.usda`, `.usdc`, `.usdz`) through `openusd` 0.6 into the same scene IR as
//! glTF (docs/design.md §3–§4).
//!
//! - The stage is composed by openusd (sublayers, references, instancing); every active,
//!   loaded, defined `Mesh` that is visible and not of `proxy` or `guide` purpose becomes a
//!   mesh, with instance proxies expanded.
//! - World transforms compose each prim's `xformOpOrder` (row vectors, USD's convention) up to
//!   the root, stopping at `!resetXformStack!`. The stage's `upAxis` and `metersPerUnit` are
//!   folded in: the IR is Y-up in metres, so a Z-up stage in centimetres renders as its Y-up
//!   metre twin.
//! - Polygons are fanned into triangles; `orientation = "leftHanded"` and mirroring
//!   transforms flip the winding so that front faces stay counter-clockwise.
//! - Materials come from `compute_bound_material` ([`shading`]); UsdLux lights become
//!   emitters ([`lights`]).
//! - Cameras: the focal length and vertical aperture give the vertical field of view.
//!
//! Attributes are read at their default value, or where they only have time samples, at the
//! stage's start time code; with an explicit time code (`--time`), at that time. Transforms
//! are composed at that time code.

mod lights;
mod shading;
mod stage;

use super::camera::{Camera, Projection};
use super::mesh::{drop_degenerate, Mesh};
use super::model::{Scene, Warning};
use crate::error::{Error, Result};
use glam::{DMat4, DVec3, Vec3};
use openusd::gf;
use openusd::schemas::geom::{
    self as ug, Gprim, Imageable, PointBased, Purpose, Visibility, Xformable,
};
use openusd::sdf;
use openusd::usd::{PrimPredicate, Stage, TimeCode};
use stage::{is_plain_prim_path, sample, shown, stage_is_z_up, Importer, Time};
use std::collections::HashMap;
use std::path::Path;

/// Import the USD stage at `path`, at time code `time` (none: the default time, see the
/// module docs).
///
/// openusd 0.6's crate (usdc) reader still panics on some malformed files (indices past the
/// end of its tables, lz4 chunking it does not implement; found by fuzzing). Such a panic is
/// caught here and reported as the file's error. Its allocations of sizes read from the file,
/// which aborted the process, are bounded by the patch in vendor/openusd.
pub fn import(path: &Path, time: Option<f64>) -> Result<Scene> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        import_unguarded(path, time)
    }))
    .unwrap_or_else(|payload| {
        let what = crate::error::panic_message(payload.as_ref());
        Err(Error::Usd {
            path: path.to_path_buf(),
            reason: format!(
                "openusd failed reading it ({}); the file is probably malformed",
                shown(&what)
            ),
        })
    })
}

fn import_unguarded(path: &Path, time: Option<f64>) -> Result<Scene> {
    let file = path.to_string_lossy().into_owned();
    let usd_err = |what: String| Error::Usd {
        path: path.to_path_buf(),
        reason: what,
    };
    if !path.exists() {
        return Err(Error::Io {
            path: path.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        });
    }
    check_names(path).map_err(&usd_err)?;
    let stage = Stage::open(&file).map_err(|e| usd_err(format!("cannot open the stage: {e:#}")))?;
    let warnings = Vec::new();
    let mut importer = Importer {
        path,
        stage: &stage,
        time: Time {
            code: TimeCode::new(time.unwrap_or_else(|| stage.start_time_code())),
            explicit: time.is_some(),
        },
        to_ir: stage_to_ir(&stage),
        scene: Scene {
            path: path.to_path_buf(),
            warnings,
            ..Default::default()
        },
        materials: HashMap::new(),
        textures: HashMap::new(),
        uv_sets: Vec::new(),
        uv_set_of: HashMap::new(),
        world: HashMap::new(),
    };
    let mut prims = Vec::new();
    stage
        .traverse(PrimPredicate::DEFAULT_PROXIES, |p| prims.push(p.clone()))
        .map_err(|e| usd_err(format!("cannot traverse the stage: {e:#}")))?;
    for p in prims {
        let prim = stage.prim(p.clone());
        let ty = prim
            .type_name()
            .map_err(|e| usd_err(format!("prim {}: {e:#}", p.as_str())))?;
        match ty.as_ref().map(|t| t.as_str()) {
            Some("Mesh") => importer.mesh(&p)?,
            Some("Camera") => importer.camera(&p)?,
            Some("RenderSettings") => importer.render_settings(&p)?,
            Some(
                t @ ("RectLight" | "DiskLight" | "SphereLight" | "DistantLight" | "DomeLight"
                | "DomeLight_1" | "CylinderLight"),
            ) => importer.light(&p, t)?,
            _ => {}
        }
    }
    // A layer or reference that cannot be read leaves the scene incomplete: an error. (Prims
    // compose lazily, so the errors are known once the stage has been traversed.)
    if let Some(e) = stage.composition_errors().first() {
        return Err(usd_err(format!("cannot compose the stage: {e}")));
    }
    Ok(importer.scene)
}

impl Importer<'_> {
    fn prim_err(&self, prim: &sdf::Path, reason: impl std::fmt::Display) -> Error {
        Error::UsdPrim {
            path: self.path.to_path_buf(),
            prim: prim.as_str().to_string(),
            reason: reason.to_string(),
        }
    }

    /// The local-to-world matrix of `prim` (column vectors, stage units).
    fn world(&mut self, prim: &sdf::Path) -> Result<DMat4> {
        if let Some(m) = self.world.get(prim.as_str()) {
            return Ok(*m);
        }
        let p = self.stage.prim(prim.clone());
        let (local, resets) =
            xformable_of(&p, self.time.code).map_err(|e| self.prim_err(prim, format!("{e:#}")))?;
        let local = column_matrix(&local);
        let parent = prim.parent();
        let m = match parent {
            Some(parent) if !resets && parent != sdf::Path::abs_root() => {
                self.world(&parent)? * local
            }
            _ => local,
        };
        self.world.insert(prim.as_str().to_string(), m);
        Ok(m)
    }

    fn mesh(&mut self, prim: &sdf::Path) -> Result<()> {
        let stage = self.stage;
        let Some(mesh) = ug::Mesh::get(stage, prim.clone()).map_err(|e| self.prim_err(prim, e))?
        else {
            return Ok(());
        };
        let visible = mesh
            .compute_visibility()
            .map_err(|e| self.prim_err(prim, e))?;
        let purpose = mesh.compute_purpose().map_err(|e| self.prim_err(prim, e))?;
        if visible == Visibility::Invisible || matches!(purpose, Purpose::Proxy | Purpose::Guide) {
            return Ok(());
        }
        let read_err = |what: &str, e: anyhow::Error| self.prim_err(prim, format!("{what}: {e:#}"));
        let points: Vec<gf::Vec3f> = sample(&mesh.points_attr(), self.time)
            .and_then(|v| {
                v.map(|v| v.cast::<Vec<gf::Vec3f>>())
                    .transpose()
                    .map_err(Into::into)
            })
            .map_err(|e| read_err("points", e))?
            .unwrap_or_default();
        let ints = |attr, what: &str| -> Result<Vec<i32>> {
            match sample(&attr, self.time).map_err(|e| read_err(what, e))? {
                None => Ok(vec![]),
                Some(sdf::Value::IntVec(v)) => Ok(v),
                Some(other) => {
                    Err(self.prim_err(prim, format!("{what} is {other:?}, not an array of ints")))
                }
            }
        };
        let counts = ints(mesh.face_vertex_counts_attr(), "faceVertexCounts")?;
        let indices = ints(mesh.face_vertex_indices_attr(), "faceVertexIndices")?;
        let holes = ints(mesh.hole_indices_attr(), "holeIndices")?;
        if !holes.is_empty() {
            self.scene.warnings.push(Warning(format!(
                "mesh {}: {} hole faces are drawn filled (holes are not supported)",
                prim.as_str(),
                holes.len()
            )));
        }
        let world = self.to_ir * self.world(prim)?;
        let positions: Vec<Vec3> = points
            .iter()
            .map(|p| {
                world
                    .transform_point3(DVec3::new(p.x as f64, p.y as f64, p.z as f64))
                    .as_vec3()
            })
            .collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(self.prim_err(prim, format!("point {i} is NaN or infinite")));
        }
        let n = positions.len();
        // Every face's vertices, validated, in face order.
        let mut faces: Vec<&[i32]> = Vec::with_capacity(counts.len());
        let mut at = 0usize;
        for (face, &c) in counts.iter().enumerate() {
            if c < 0 || at + c as usize > indices.len() {
                return Err(self.prim_err(
                    prim,
                    format!(
                        "face {face} has {c} vertices, past the {} face-vertex indices",
                        indices.len()
                    ),
                ));
            }
            let f = &indices[at..at + c as usize];
            if let Some(&bad) = f.iter().find(|&&i| i < 0 || i as usize >= n) {
                return Err(self.prim_err(
                    prim,
                    format!("face {face} has vertex index {bad}, out of range (the mesh has {n} points)"),
                ));
            }
            faces.push(f);
            at += c as usize;
        }
        let normal_matrix = glam::DMat3::from_mat4(world).inverse().transpose();
        let normals = self
            .primvar3(&mesh.normals_attr(), prim, at, n)?
            .map(|(v, fv)| {
                let v = v
                    .iter()
                    .map(|p| {
                        let d = DVec3::new(p.x as f64, p.y as f64, p.z as f64);
                        (normal_matrix * d)
                            .as_vec3()
                            .try_normalize()
                            .unwrap_or(Vec3::ZERO)
                    })
                    .collect::<Vec<_>>();
                (v, fv)
            });
        let double_sided = mesh
            .double_sided_attr()
            .get::<bool>()
            .ok()
            .flatten()
            .unwrap_or(false);
        let material = self.material_of(prim, double_sided)?;
        let uv_set = format!(
            "primvars:{}",
            self.uv_set_of
                .get(&material)
                .map_or(shading::DEFAULT_UV_SET, String::as_str)
        );
        let uvs = self.primvar2(
            &openusd::usd::SchemaBase::prim(&mesh).attribute(uv_set.as_str()),
            prim,
            at,
            n,
        )?;
        // Face-varying primvars get one vertex per face corner; otherwise points are shared.
        let face_varying =
            normals.as_ref().is_some_and(|x| x.1) || uvs.as_ref().is_some_and(|x| x.1);
        let corner_points: Vec<u32> = faces
            .iter()
            .flat_map(|f| f.iter().map(|&i| i as u32))
            .collect();
        let (positions, normals, uvs) = if face_varying {
            (
                spread(positions, false, &corner_points),
                normals.map(|(v, fv)| spread(v, fv, &corner_points)),
                uvs.map(|(v, fv)| spread(v, fv, &corner_points)),
            )
        } else {
            (positions, normals.map(|x| x.0), uvs.map(|x| x.0))
        };
        let mut triangles = Vec::new();
        let mut corner = 0u32;
        for f in &faces {
            let id = |k: usize| {
                if face_varying {
                    corner + k as u32
                } else {
                    f[k] as u32
                }
            };
            for k in 2..f.len() {
                triangles.push([id(0), id(k - 1), id(k)]);
            }
            corner += f.len() as u32;
        }
        let left_handed = mesh
            .orientation_attr()
            .cast::<String>()
            .ok()
            .flatten()
            .is_some_and(|o| o == "leftHanded");
        if left_handed != (world.determinant() < 0.0) {
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        let dropped = drop_degenerate(&positions, &mut triangles);
        if dropped > 0 {
            self.scene.warnings.push(Warning(format!(
                "mesh {}: dropped {dropped} degenerate (zero-area) triangles",
                prim.as_str()
            )));
        }
        if triangles.is_empty() {
            return Ok(());
        }
        self.scene.meshes.push(Mesh {
            name: prim.as_str().to_string(),
            positions,
            normals: normals.filter(|n| n.iter().all(|v| *v != Vec3::ZERO)),
            uvs,
            triangles,
            material,
        });
        Ok(())
    }

    /// A primvar's values and whether they are face-varying (one per face corner, of which
    /// the mesh has `corners`), or per point (`points` of them); `None` where it is absent or
    /// constant or uniform (left out).
    fn primvar<T: Copy>(
        &self,
        attr: &openusd::usd::Attribute,
        prim: &sdf::Path,
        (corners, points): (usize, usize),
        read: impl Fn(sdf::Value) -> Option<Vec<T>>,
    ) -> Result<Option<(Vec<T>, bool)>> {
        let name = attr
            .path()
            .as_str()
            .rsplit('.')
            .next()
            .unwrap_or("primvar")
            .to_string();
        let Some(value) =
            sample(attr, self.time).map_err(|e| self.prim_err(prim, format!("{name}: {e:#}")))?
        else {
            return Ok(None);
        };
        let mut values = read(value)
            .ok_or_else(|| self.prim_err(prim, format!("{name} has an unexpected type")))?;
        // An indexed primvar: its values are a table, its `:indices` say which entry each
        // element takes.
        let indices_path = sdf::Path::new(&format!("{}:indices", attr.path().as_str()))
            .map_err(|e| self.prim_err(prim, format!("{name}: {e:#}")))?;
        let indices = sample(&self.stage.attribute(indices_path), self.time)
            .map_err(|e| self.prim_err(prim, format!("{name}:indices: {e:#}")))?;
        if let Some(indices) = indices {
            let sdf::Value::IntVec(indices) = indices else {
                return Err(self.prim_err(prim, format!("{name}:indices must be an int array")));
            };
            values = indices
                .iter()
                .map(|&i| usize::try_from(i).ok().and_then(|i| values.get(i).copied()))
                .collect::<Option<Vec<T>>>()
                .ok_or_else(|| {
                    self.prim_err(
                        prim,
                        format!("{name}:indices reach past its {} values", values.len()),
                    )
                })?;
        }
        let interpolation = attr
            .get_metadata::<sdf::Value>("interpolation")
            .ok()
            .flatten()
            .and_then(|v| v.cast::<String>().ok())
            .unwrap_or_else(|| "vertex".into());
        let (expected, face_varying) = match interpolation.as_str() {
            "faceVarying" => (corners, true),
            "vertex" | "varying" => (points, false),
            _ => return Ok(None),
        };
        if values.len() != expected {
            return Err(self.prim_err(
                prim,
                format!(
                    "{name} ({interpolation}) has {} values where the mesh needs {expected}",
                    values.len()
                ),
            ));
        }
        Ok(Some((values, face_varying)))
    }

    fn primvar3(
        &self,
        attr: &openusd::usd::Attribute,
        prim: &sdf::Path,
        corners: usize,
        points: usize,
    ) -> Result<Option<(Vec<gf::Vec3f>, bool)>> {
        self.primvar(attr, prim, (corners, points), |v| {
            v.cast::<Vec<gf::Vec3f>>().ok()
        })
    }

    fn primvar2(
        &self,
        attr: &openusd::usd::Attribute,
        prim: &sdf::Path,
        corners: usize,
        points: usize,
    ) -> Result<Option<(Vec<glam::Vec2>, bool)>> {
        self.primvar(attr, prim, (corners, points), |v| match v {
            sdf::Value::Vec2fVec(v) => Some(v.iter().map(|p| glam::Vec2::new(p.x, p.y)).collect()),
            _ => None,
        })
    }

    /// The first `RenderSettings` prim and its first product (UsdRender): camera, resolution
    /// and product name. Later settings prims are named in a warning and left alone.
    fn render_settings(&mut self, prim: &sdf::Path) -> Result<()> {
        if let Some(first) = &self.scene.render_product {
            self.scene.warnings.push(Warning(format!(
                "{} is a second RenderSettings prim; {} is used",
                prim.as_str(),
                first.settings
            )));
            return Ok(());
        }
        let settings = self.stage.prim(prim.clone());
        let target = |p: &openusd::usd::Prim, name: &str| -> Result<Option<sdf::Path>> {
            Ok(p.relationship(name)
                .targets()
                .map_err(|e| self.prim_err(prim, format!("{name}: {e:#}")))?
                .into_iter()
                .next())
        };
        let resolution = |p: &openusd::usd::Prim| -> Result<Option<(u32, u32)>> {
            match sample(&p.attribute("resolution"), self.time)
                .map_err(|e| self.prim_err(prim, format!("resolution: {e:#}")))?
            {
                None => Ok(None),
                Some(sdf::Value::Vec2i(v))
                    if Camera::check_size(v.x.max(0) as u32, v.y.max(0) as u32).is_ok() =>
                {
                    Ok(Some((v.x as u32, v.y as u32)))
                }
                Some(other) => Err(self.prim_err(
                    p.path(),
                    format!(
                        "resolution {other:?} must be two numbers from 1 to {}",
                        Camera::MAX_SIDE
                    ),
                )),
            }
        };
        let mut product = crate::scene::RenderProduct {
            settings: prim.as_str().to_string(),
            camera: target(&settings, "camera")?.map(|c| c.as_str().to_string()),
            resolution: resolution(&settings)?,
            name: None,
        };
        if let Some(p) = target(&settings, "products")? {
            let p = self.stage.prim(p);
            if let Some(c) = target(&p, "camera")? {
                product.camera = Some(c.as_str().to_string());
            }
            if let Some(r) = resolution(&p)? {
                product.resolution = Some(r);
            }
            product.name = sample(&p.attribute("productName"), self.time)
                .map_err(|e| self.prim_err(p.path(), format!("productName: {e:#}")))?
                .and_then(|v| v.cast::<String>().ok())
                .filter(|n| !n.is_empty());
        }
        self.scene.render_product = Some(product);
        Ok(())
    }

    fn camera(&mut self, prim: &sdf::Path) -> Result<()> {
        let Some(cam) =
            ug::Camera::get(self.stage, prim.clone()).map_err(|e| self.prim_err(prim, e))?
        else {
            return Ok(());
        };
        let f = |a: openusd::usd::Attribute, default: f32| -> f32 {
            a.cast::<f32>().ok().flatten().unwrap_or(default)
        };
        let focal = f(cam.focal_length_attr(), 50.0);
        let vertical = f(cam.vertical_aperture_attr(), 15.2908);
        if !(focal > 0.0 && vertical > 0.0) {
            return Err(self.prim_err(
                prim,
                format!("focal length {focal} and vertical aperture {vertical} must be positive"),
            ));
        }
        let world = self.to_ir * self.world(prim)?;
        let position = world.transform_point3(DVec3::ZERO).as_vec3();
        let axis = |v: DVec3| world.transform_vector3(v).as_vec3().try_normalize();
        let (Some(right), Some(up), Some(forward)) =
            (axis(DVec3::X), axis(DVec3::Y), axis(DVec3::NEG_Z))
        else {
            return Err(self.prim_err(prim, "the camera's transform is singular"));
        };
        let ortho = cam
            .projection_attr()
            .cast::<String>()
            .ok()
            .flatten()
            .is_some_and(|p| p == "orthographic");
        let projection = if ortho {
            // Apertures are in tenths of a scene unit for orthographic cameras.
            let horizontal = f(cam.horizontal_aperture_attr(), 20.955);
            let scale = 0.05 * meters_per_unit(self.stage) as f32;
            Projection::Orthographic {
                xmag: horizontal * scale,
                ymag: vertical * scale,
            }
        } else {
            Projection::Perspective {
                yfov: 2.0 * (0.5 * vertical / focal).atan(),
            }
        };
        self.scene.cameras.push(Camera {
            name: prim.as_str().to_string(),
            position,
            right,
            up,
            forward,
            projection,
            width: Camera::DEFAULT_SIZE.0,
            height: Camera::DEFAULT_SIZE.1,
        });
        Ok(())
    }
}

/// Per-point `values` spread to one per face corner (`corner_points`), or face-varying ones
/// (`face_varying`) as they are.
fn spread<T: Copy>(values: Vec<T>, face_varying: bool, corner_points: &[u32]) -> Vec<T> {
    if face_varying {
        values
    } else {
        corner_points.iter().map(|&i| values[i as usize]).collect()
    }
}

/// Refuse a root layer whose prims or properties are not named by identifiers. openusd 0.6
/// reads such names (`def Shader "a}b"`) and then recurses without end composing them (found
/// by fuzzing), so the layer is parsed once on its own and checked first. A layer that does
/// not parse is left to `Stage::open`, which says why. Layers it brings in by sublayer or
/// reference are not checked.
fn check_names(path: &Path) -> std::result::Result<(), String> {
    use openusd::sdf::AbstractData;
    let Ok(bytes) = std::fs::read(path) else {
        return Ok(());
    };
    let data: Box<dyn AbstractData> = if bytes.starts_with(b"PK") {
        match openusd::usdz::Archive::from_reader(std::io::Cursor::new(bytes))
            .and_then(|mut a| a.read_first_layer())
        {
            Ok(d) => d,
            Err(_) => return Ok(()),
        }
    } else if bytes.starts_with(openusd::usdc::MAGIC) {
        match openusd::usdc::CrateData::open(std::io::Cursor::new(bytes), true) {
            Ok(d) => Box::new(d),
            Err(_) => return Ok(()),
        }
    } else {
        match std::str::from_utf8(&bytes).ok().map(openusd::usda::parse) {
            Some(Ok(d)) => Box::new(d),
            _ => return Ok(()),
        }
    };
    for spec in data.spec_paths() {
        // Arcs to prim paths that are not made of identifiers make openusd 0.6 compose
        // without end too.
        for field in ["references", "payload", "inherits", "specializes"] {
            let targets: Vec<String> = match data.try_field(&spec, field).ok().flatten().as_deref()
            {
                Some(sdf::Value::ReferenceListOp(op)) => op
                    .iter()
                    .map(|r| r.prim_path.as_str().to_string())
                    .collect(),
                Some(sdf::Value::PayloadListOp(op)) => op
                    .iter()
                    .map(|r| r.prim_path.as_str().to_string())
                    .collect(),
                Some(sdf::Value::PathListOp(op)) => {
                    op.iter().map(|p| p.as_str().to_string()).collect()
                }
                _ => Vec::new(),
            };
            if let Some(bad) = targets
                .iter()
                .find(|t| !t.is_empty() && !is_plain_prim_path(t))
            {
                return Err(format!(
                    "{} has {field} to {}, which is not a prim path",
                    spec.as_str(),
                    shown(bad)
                ));
            }
        }
        // Children listed under names that are not identifiers (an empty one names the prim
        // itself) make openusd 0.6's traversal run without end.
        for (field, valid) in [
            (
                "primChildren",
                sdf::Path::is_valid_identifier as fn(&str) -> bool,
            ),
            ("properties", sdf::Path::is_valid_namespace_identifier),
        ] {
            let names: Vec<String> = match data.try_field(&spec, field).ok().flatten().as_deref() {
                Some(sdf::Value::TokenVec(v)) => v.iter().map(|t| t.as_str().to_string()).collect(),
                Some(sdf::Value::StringVec(v)) => v.clone(),
                _ => Vec::new(),
            };
            if let Some(bad) = names.iter().find(|n| !valid(n)) {
                return Err(format!(
                    "{} lists a child named {}, which is not an identifier",
                    spec.as_str(),
                    shown(bad)
                ));
            }
        }
        let text = spec.as_str();
        // Variant selections and relationship or connection targets have syntax of their own.
        if text.contains('{') || text.contains('[') || spec.is_abs_root() {
            continue;
        }
        let (prim, property) = match spec.split_property() {
            Some((prim, property)) => (prim, Some(property.to_string())),
            None => (spec.clone(), None),
        };
        let prim_ok = is_plain_prim_path(prim.as_str());
        let property_ok = property
            .as_deref()
            .is_none_or(sdf::Path::is_valid_namespace_identifier);
        if !(prim_ok && property_ok) {
            return Err(format!(
                "the layer names a spec {}, which is not a valid path",
                shown(text)
            ));
        }
    }
    Ok(())
}

/// A prim's local transform and whether it resets the transform stack, for any prim type
/// (the ops are plain attributes; typeless prims, such as a reference's root, have them too).
fn xformable_of(prim: &openusd::usd::Prim, time: TimeCode) -> anyhow::Result<(gf::Matrix4d, bool)> {
    let view = XformableView(prim.clone());
    // Op names become property paths; openusd 0.6 can hang on a name that is not a
    // namespaced identifier (found by fuzzing: a token holding a newline and a brace).
    for op in view.xform_op_order()?.unwrap_or_default() {
        let name = op.strip_prefix("!invert!").unwrap_or(&op);
        let valid = op == "!resetXformStack!"
            || (name.starts_with("xformOp:") && sdf::Path::is_valid_namespace_identifier(name));
        if !valid {
            anyhow::bail!("xformOpOrder names {}, which is not an xformOp", shown(&op));
        }
    }
    Ok((
        view.local_to_parent_transform(time)?,
        view.resets_xform_stack()?,
    ))
}

/// Any prim, seen as xformable.
struct XformableView(openusd::usd::Prim);

impl openusd::usd::SchemaBase for XformableView {
    const KIND: openusd::usd::SchemaKind = openusd::usd::SchemaKind::AbstractTyped;
    fn prim(&self) -> &openusd::usd::Prim {
        &self.0
    }
}

impl Imageable for XformableView {}
impl Xformable for XformableView {}

/// A USD matrix (row vectors, row-major) as a column-vector matrix.
fn column_matrix(m: &gf::Matrix4d) -> DMat4 {
    // Row-major storage of the row-vector matrix M is column-major storage of Mᵀ, the
    // column-vector matrix.
    DMat4::from_cols_array(&m.0)
}

fn meters_per_unit(stage: &Stage) -> f64 {
    stage
        .stage_metadata("metersPerUnit")
        .ok()
        .flatten()
        .and_then(|v| v.cast::<f64>().ok())
        .filter(|m| m.is_finite() && *m > 0.0)
        .unwrap_or(0.01)
}

/// Stage coordinates to the IR's: scaled to metres, and a Z-up stage turned Y-up
/// ((x, y, z) → (x, z, −y)).
fn stage_to_ir(stage: &Stage) -> DMat4 {
    let axes = if stage_is_z_up(stage) {
        DMat4::from_cols(
            glam::DVec4::X,
            glam::DVec4::new(0.0, 0.0, -1.0, 0.0),
            glam::DVec4::Y,
            glam::DVec4::W,
        )
    } else {
        DMat4::IDENTITY
    };
    DMat4::from_scale(DVec3::splat(meters_per_unit(stage))) * axes
}

//! The scene IR: world-space triangle meshes, materials, textures, emitters and cameras. One IR
//! for every importer (glTF now, USD later), validated on import (DESIGN.md §4).

pub mod camera;
pub mod environment;
mod gltf;
pub mod light;
pub mod material;
pub mod normal_map;
pub mod texture;
#[cfg(feature = "usd")]
mod usd;

pub use camera::{Camera, Projection, RenderProduct};
pub use environment::Environment;
pub use light::{LightKind, PunctualLight};
pub use material::{Cutout, Emission, Material, PbrParams, Scattering};
pub use normal_map::NormalMap;
pub use texture::{ChannelRef, TexRef, Texture, Wrap};

use crate::error::{Error, Result};
use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};

/// A triangle mesh in world space.
#[derive(Clone, Debug)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    /// Unit shading normals per vertex; `None` means flat shading with the face normal.
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub triangles: Vec<[u32; 3]>,
    pub material: usize,
}

impl Mesh {
    /// Whether the mesh is closed and consistently wound: with vertices welded by position,
    /// every edge of a non-degenerate triangle is met once in each direction. Such a surface
    /// bounds a volume, and from outside it its back faces lie behind its front faces.
    pub fn is_closed(&self) -> bool {
        use std::collections::HashMap;
        let mut weld: HashMap<[u32; 3], u32> = HashMap::new();
        let ids: Vec<u32> = self
            .positions
            .iter()
            .map(|p| {
                let next = weld.len() as u32;
                *weld.entry(p.to_array().map(f32::to_bits)).or_insert(next)
            })
            .collect();
        // Per undirected edge (low, high): how often it is met low → high and high → low.
        let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
        for t in &self.triangles {
            let Some(v) = t
                .iter()
                .map(|&i| ids.get(i as usize).copied())
                .collect::<Option<Vec<_>>>()
            else {
                return false;
            };
            if v[0] == v[1] || v[1] == v[2] || v[2] == v[0] {
                continue;
            }
            for (a, b) in [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])] {
                let e = edges.entry((a.min(b), a.max(b))).or_default();
                if a < b {
                    e.0 += 1;
                } else {
                    e.1 += 1;
                }
            }
        }
        !edges.is_empty() && edges.values().all(|&c| c == (1, 1))
    }

    /// The texture coordinate at barycentric weights `b` of triangle `tri` ((0, 0) without UVs).
    pub fn uv_at(&self, tri: u32, b: [f32; 3]) -> Vec2 {
        interpolate_uv(self.uvs.as_deref(), self.triangles[tri as usize], b)
    }

    /// The unit interpolated vertex normal at barycentric weights `b` of triangle `tri`, or
    /// `None` for a flat mesh (or normals that cancel there).
    pub fn normal_at(&self, tri: u32, b: [f32; 3]) -> Option<Vec3> {
        let n = self.normals.as_ref()?;
        let t = self.triangles[tri as usize];
        (b[0] * n[t[0] as usize] + b[1] * n[t[1] as usize] + b[2] * n[t[2] as usize])
            .try_normalize()
    }
}

/// The texture coordinate at barycentric weights `b` of the triangle with vertices `t`, from
/// per-vertex `uvs` ((0, 0) without them): [`Mesh::uv_at`] for data kept apart from its mesh.
pub fn interpolate_uv(uvs: Option<&[Vec2]>, t: [u32; 3], b: [f32; 3]) -> Vec2 {
    match uvs {
        Some(uv) => b[0] * uv[t[0] as usize] + b[1] * uv[t[1] as usize] + b[2] * uv[t[2] as usize],
        None => Vec2::ZERO,
    }
}

/// Something the importer noticed and worked around.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning(pub String);

/// Remove the zero-area (and non-finite) triangles of `triangles` over `positions`; returns
/// how many were removed.
pub(crate) fn drop_degenerate(positions: &[Vec3], triangles: &mut Vec<[u32; 3]>) -> usize {
    let before = triangles.len();
    triangles.retain(|t| {
        let (a, b, c) = (
            positions[t[0] as usize],
            positions[t[1] as usize],
            positions[t[2] as usize],
        );
        let area2 = (b - a).cross(c - a).length();
        area2 > 0.0 && area2.is_finite()
    });
    before - triangles.len()
}

#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// The file the scene came from (named in every error).
    pub path: PathBuf,
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<PunctualLight>,
    /// Radiance from far away (a USD dome light).
    pub environment: Option<Environment>,
    pub cameras: Vec<Camera>,
    /// What a USD stage's render settings ask of the image, when it has them.
    pub render_product: Option<RenderProduct>,
    pub warnings: Vec<Warning>,
}

impl Scene {
    /// Load a `.gltf` or `.glb` file, or (with the `usd` feature) a `.usd`, `.usda`, `.usdc`
    /// or `.usdz` stage.
    pub fn load(path: &Path) -> Result<Scene> {
        Scene::load_at(path, None)
    }

    /// [`Scene::load`] at USD time code `time` (none: the default time). glTF scenes have no
    /// time and ignore it.
    pub fn load_at(path: &Path, time: Option<f64>) -> Result<Scene> {
        #[cfg(not(feature = "usd"))]
        let _ = time;
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let mut scene = match ext.as_deref() {
            #[cfg(feature = "usd")]
            Some("usd") | Some("usda") | Some("usdc") | Some("usdz") => usd::import(path, time)?,
            Some("gltf") | Some("glb") => {
                let bytes = std::fs::read(path).map_err(|source| Error::Io {
                    path: path.to_path_buf(),
                    source,
                })?;
                gltf::import(path, &bytes)?
            }
            _ => {
                return Err(Error::UnsupportedFormat {
                    path: path.to_path_buf(),
                })
            }
        };
        scene.drop_invisible_meshes();
        Ok(scene)
    }

    /// Load a glTF/GLB from memory; `path` names it in errors and anchors relative URIs.
    pub fn from_gltf_bytes(path: &Path, bytes: &[u8]) -> Result<Scene> {
        let mut scene = gltf::import(path, bytes)?;
        scene.drop_invisible_meshes();
        Ok(scene)
    }

    /// Leave out meshes that do not interact with light: clear glass of index 1 (index-matched
    /// with the air around it: no reflection, no bending), which DESIGN.md §10 requires to
    /// vanish. Kept, they would still stop shadow rays and hold surfels. A warning each.
    /// Meshes whose material's alpha cut-out removes them whole (a constant alpha below the
    /// cutoff) are left out too.
    pub fn drop_invisible_meshes(&mut self) {
        let materials = &self.materials;
        let mut dropped = Vec::new();
        self.meshes.retain(|m| {
            let material = materials.get(m.material);
            let why = if material.is_some_and(Material::is_index_matched) {
                Some("its material is clear glass of index 1, which does not interact with light")
            } else if material.and_then(|x| x.cutout).and_then(|c| c.constant()) == Some(false) {
                Some("its material's alpha is below its cutoff everywhere (a hole)")
            } else {
                None
            };
            if let Some(why) = why {
                dropped.push((m.name.clone(), why));
            }
            why.is_none()
        });
        for (name, why) in dropped {
            self.warnings
                .push(Warning(format!("mesh {name}: {why}; left out")));
        }
    }

    /// Number of triangles over all meshes.
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.triangles.len()).sum()
    }

    /// Axis-aligned bounds `(min, max)` of all geometry.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in self.meshes.iter().flat_map(|m| &m.positions) {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        (lo, hi)
    }

    /// True when anything emits light.
    pub fn has_emitters(&self) -> bool {
        !self.lights.is_empty()
            || self.environment.is_some()
            || self.meshes.iter().any(|m| {
                self.materials[m.material]
                    .emission
                    .as_ref()
                    .is_some_and(|e| e.radiance.max_element() > 0.0)
            })
    }

    /// Refuse scenes that would render black or empty, with a sentence that says why.
    pub fn check_renderable(&self) -> Result<()> {
        if self.triangle_count() == 0 {
            return Err(Error::EmptyScene {
                path: self.path.clone(),
            });
        }
        if !self.has_emitters() {
            return Err(Error::NoEmitter {
                path: self.path.clone(),
            });
        }
        Ok(())
    }

    /// The named camera (or the first one) at the given size.
    pub fn camera(&self, name: Option<&str>, width: u32, height: u32) -> Result<Camera> {
        match name {
            Some(n) => self
                .cameras
                .iter()
                .find(|c| c.name == n)
                .map(|c| c.clone().with_size(width, height))
                .ok_or_else(|| Error::Camera {
                    path: self.path.clone(),
                    reason: format!(
                        "no camera named \"{n}\" (cameras: {})",
                        if self.cameras.is_empty() {
                            "none".to_string()
                        } else {
                            self.cameras
                                .iter()
                                .map(|c| format!("\"{}\"", c.name))
                                .collect::<Vec<_>>()
                                .join(", ")
                        }
                    ),
                }),
            None => self.default_camera(width, height),
        }
    }

    /// The scene's first camera, or one that frames the whole scene from +Z.
    pub fn default_camera(&self, width: u32, height: u32) -> Result<Camera> {
        if let Some(c) = self.cameras.first() {
            return Ok(c.clone().with_size(width, height));
        }
        self.framing_camera(width, height)
    }

    /// A camera on the +Z side looking at the centre of the bounding sphere, far enough back
    /// (with a 10 % margin) that the sphere fits a 40° vertical field of view.
    pub fn framing_camera(&self, width: u32, height: u32) -> Result<Camera> {
        let (lo, hi) = self.bounds();
        if !(lo.is_finite() && hi.is_finite()) {
            return Err(Error::EmptyScene {
                path: self.path.clone(),
            });
        }
        Camera::framing(0.5 * (lo + hi), 0.5 * (hi - lo).length(), width, height).ok_or_else(|| {
            Error::Camera {
                path: self.path.clone(),
                reason: "cannot frame the scene automatically".into(),
            }
        })
    }
}

//! The scene IR itself: the meshes, materials, textures, lights and cameras one import
//! produces, and the queries on the whole (bounds, cameras, whether it can be rendered).
//! The importers that fill it are in `super::gltf` and `super::usd`.

use super::camera::{Camera, RenderProduct};
use super::environment::Environment;
use super::light::PunctualLight;
use super::material::Material;
use super::mesh::Mesh;
use super::texture::Texture;
use crate::error::{Error, Result};
use glam::Vec3;
use std::path::PathBuf;

/// Something the importer noticed and worked around.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning(pub String);

/// A scene as wpbgi renders it: world-space triangle meshes (Y up, metres), Mitsuba
/// materials, textures, lights and cameras, whatever file it came from. Load one with
/// [`Scene::load`].
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// The file the scene came from (named in every error).
    pub path: PathBuf,
    /// The triangle meshes, in world space.
    pub meshes: Vec<Mesh>,
    /// The materials the meshes index.
    pub materials: Vec<Material>,
    /// The textures the materials index.
    pub textures: Vec<Texture>,
    /// Point, spot and directional lights (area lights are emissive meshes).
    pub lights: Vec<PunctualLight>,
    /// Radiance from far away (a USD dome light).
    pub environment: Option<Environment>,
    /// The scene's cameras, by name.
    pub cameras: Vec<Camera>,
    /// What a USD stage's render settings ask of the image, when it has them.
    pub render_product: Option<RenderProduct>,
    /// What the importer noticed and worked around.
    pub warnings: Vec<Warning>,
}

impl Scene {
    /// Leave out meshes that do not interact with light: clear glass of index 1 (index-matched
    /// with the air around it: no reflection, no bending), which docs/design.md §10 requires to
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

    /// Whether mesh `m`'s material emits light (its triangles are emitters).
    pub fn emits(&self, m: &Mesh) -> bool {
        self.materials
            .get(m.material)
            .is_some_and(|material| material.emission.is_some())
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

//! The scene IR: world-space triangle meshes, materials, textures, emitters and cameras. One IR
//! for every importer (glTF now, USD later), validated on import (docs/design.md §4).

pub mod camera;
pub mod edit;
pub mod environment;
mod gltf;
pub mod light;
pub mod material;
pub mod mesh;
pub mod model;
pub mod normal_map;
pub mod texture;
#[cfg(feature = "usd")]
mod usd;

pub use camera::{Camera, Projection, RenderProduct};
pub use environment::Environment;
pub use light::{LightKind, PunctualLight};
pub use material::{Cutout, Emission, Material, PbrParams, Scattering};
pub use mesh::{interpolate_uv, Mesh};
pub use model::{Scene, Warning};
pub use normal_map::NormalMap;
pub use texture::{ChannelRef, TexRef, Texture, Wrap};

use crate::error::{Error, Result};
use std::path::Path;

/// Loading, by file type: the importers fill the IR of [`model`].
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
}

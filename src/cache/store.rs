//! A bake in a `.wpc` cache (docs/design.md §6): which sections hold what, and the records' layout.
//!
//! Sections, coarse to fine: `plan` (JSON: format, crate version, settings, plan, statistics),
//! `nodes` (the tree, breadth-first), `map_index` and `maps` (the coded tree's and the surfels'
//! wavelet maps), `surfels`, `order`. Records are little-endian `#[repr(C)]` structs of 4-byte
//! fields, readable in place from a memory map.

use crate::cache::{self, Cache, CacheError};
use crate::haar::{Coefficient, SparseHaar};
use crate::scene::Scene;
use crate::surfels::tree::Node;
use bytemuck::{Pod, Zeroable};
use serde_json::Value;
use std::path::Path;

/// No map.
pub const NO_MAP: u32 = u32::MAX;

/// No node: a leaf's children, the root's parent, as the records store them (the surfel
/// tree's own sentinel, so that readers of a cache need not import the bake).
pub(crate) const NO_NODE: u32 = crate::surfels::tree::NONE;

/// One surfel in the `surfels` section.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SurfelRecord {
    /// Its centre.
    pub p: [f32; 3],
    /// Its unit normal.
    pub n: [f32; 3],
    /// Its disc's area.
    pub area: f32,
    /// The scene mesh it lies on.
    pub mesh: u32,
    /// Diffuse: the outgoing radiance. Directional: the radiance towards the normal (for
    /// previews and point-cloud export).
    pub rgb: [f32; 3],
    /// Index into `map_index` of the surfel's directional map, or [`NO_MAP`].
    pub map: u32,
    /// The emitted part of `rgb` and of the map (front face), so that a gather can tell
    /// reflected light from emission, which the final render lights directly.
    pub emitted: [f32; 3],
    /// Bit 0 ([`SOLID`]): the surfel bounds a solid, whose inward light only the solid's own
    /// surface sees (see [`crate::surfels::radiance::mesh_flags`]). Bit 1: [`BACK_SIDED`]; bit 2:
    /// [`CLOSED`].
    pub flags: u32,
}

pub use crate::surfels::radiance::{BACK_SIDED, CLOSED, SOLID};

/// The layout of the bake's sections; caches of another layout are refused (bake again).
pub(crate) const BAKE_FORMAT: u32 = 3;

/// One tree node in the `nodes` section: the surfel tree's node as the build made it, and
/// where its maps are in `map_index`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct NodeRecord {
    /// The node: bounds, normal cone, area and links.
    pub node: Node,
    /// Index into `map_index` of the stored G (the node's own map) of the radiant
    /// intensity, or [`NO_MAP`].
    pub g: u32,
    /// The same for its H (the detail between its children).
    pub h: u32,
    /// The same as `g` for the projected area (a scalar map).
    pub area_g: u32,
    /// The same as `h` for the projected area.
    pub area_h: u32,
}

/// The content hash of a bake: everything the importer read from the scene (geometry,
/// materials, textures, lights; so a changed external buffer or image counts, not only the main
/// file), the settings and the crate version. Cameras do not change a bake and are left out.
pub fn bake_hash(scene: &Scene, settings: &Value) -> [u8; 16] {
    // Debug formatting prints every float so that it parses back to the same value.
    let materials = format!("{:?}", scene.materials);
    let lights = format!("{:?}", scene.lights);
    cache::content_hash(&[
        &geometry_bytes(scene),
        &texture_bytes(scene),
        materials.as_bytes(),
        lights.as_bytes(),
        &environment_bytes(scene),
        settings.to_string().as_bytes(),
        crate::VERSION.as_bytes(),
    ])
}

/// The hash of what a bake's surfels and their shadow rays depend on besides how the
/// materials scatter and what emits: the geometry, the textures, each material's cut-outs,
/// the settings and the crate version (see [`bake_hash`]).
pub fn geometry_hash(scene: &Scene, settings: &Value) -> [u8; 16] {
    let cutouts: Vec<_> = scene.materials.iter().map(|m| m.cutout).collect();
    cache::content_hash(&[
        &geometry_bytes(scene),
        &texture_bytes(scene),
        format!("{cutouts:?}").as_bytes(),
        settings.to_string().as_bytes(),
        crate::VERSION.as_bytes(),
    ])
}

/// The hash of everything that emits light in `scene`: each material's emission, the
/// lights and the environment.
pub fn emitters_hash(scene: &Scene) -> [u8; 16] {
    let emission: Vec<_> = scene.materials.iter().map(|m| &m.emission).collect();
    cache::content_hash(&[
        format!("{emission:?}").as_bytes(),
        format!("{:?}", scene.lights).as_bytes(),
        &environment_bytes(scene),
    ])
}

/// The hash of one material's whole description (see [`bake_hash`]).
pub fn material_hash(material: &crate::scene::Material) -> [u8; 16] {
    cache::content_hash(&[format!("{material:?}").as_bytes()])
}

fn geometry_bytes(scene: &Scene) -> Vec<u8> {
    let mut geometry = Vec::new();
    for m in &scene.meshes {
        geometry.extend_from_slice(bytemuck::cast_slice(&m.positions));
        geometry.extend_from_slice(bytemuck::cast_slice(&m.triangles));
        if let Some(n) = &m.normals {
            geometry.extend_from_slice(bytemuck::cast_slice(n));
        }
        if let Some(uv) = &m.uvs {
            geometry.extend_from_slice(bytemuck::cast_slice(uv));
        }
        geometry.extend_from_slice(&(m.material as u64).to_le_bytes());
    }
    geometry
}

fn texture_bytes(scene: &Scene) -> Vec<u8> {
    let mut textures = Vec::new();
    for t in &scene.textures {
        textures.extend_from_slice(&t.width.to_le_bytes());
        textures.extend_from_slice(bytemuck::cast_slice(&t.texels));
    }
    textures
}

fn environment_bytes(scene: &Scene) -> Vec<u8> {
    match &scene.environment {
        Some(e) => {
            let mut bytes = format!("{:?} {:?} {}", e.scale, e.to_local, e.name).into_bytes();
            if let Some(m) = &e.map {
                bytes.extend_from_slice(&m.width.to_le_bytes());
                bytes.extend_from_slice(bytemuck::cast_slice(&m.texels));
            }
            bytes
        }
        None => Vec::new(),
    }
}

/// A cache's records, read back and checked (the bake's `bake::store` writes them).
pub struct BakedCache {
    /// The file's sections, checked.
    pub cache: Cache,
    /// The bake's plan and statistics, as the cache records them (`wpbgi inspect` prints it).
    pub plan: Value,
    /// The surfels.
    pub surfels: Vec<SurfelRecord>,
    /// The tree's nodes, breadth-first from the root.
    pub nodes: Vec<NodeRecord>,
    /// Surfel indices in leaf order: node `j`'s surfels are `order[first .. first + count]`.
    pub order: Vec<u32>,
}

impl BakedCache {
    /// Read and check the cache at `path` (memory-mapped); with `expected_hash`, refuse it
    /// as stale unless it was baked with that hash.
    pub fn read(path: &Path, expected_hash: Option<[u8; 16]>) -> Result<BakedCache, CacheError> {
        Self::from_cache(Cache::read(path, expected_hash)?)
    }

    /// Read the cache at `path`, refusing it if `scene` or the bake settings stored in it
    /// changed since it was baked.
    pub fn open_fresh(scene: &Scene, path: &Path) -> Result<BakedCache, CacheError> {
        let cache = Self::read(path, None)?;
        cache.check_scene(scene)?;
        Ok(cache)
    }

    /// Refuse the cache as stale unless it was baked from `scene` as it is now (with the
    /// settings it records).
    pub fn check_scene(&self, scene: &Scene) -> Result<(), CacheError> {
        self.cache.check_fresh(bake_hash(scene, self.settings()))
    }

    /// The bake settings the cache records, as their canonical JSON (what the hash covers).
    pub fn settings(&self) -> &Value {
        &self.plan["settings"]
    }

    /// The indirect bounces the bake ran (0: a cache of direct light only).
    pub fn bounces(&self) -> u32 {
        self.plan["plan"]["bounces"]["bounces"]
            .as_u64()
            .map_or(0, |b| u32::try_from(b).unwrap_or(u32::MAX))
    }

    /// The side, in texels, of the finest directional map the tree holds (none recorded: a
    /// cache of diffuse surfels only).
    pub(crate) fn map_resolution(&self) -> Option<u32> {
        self.plan["plan"]["map_resolution"]
            .as_u64()
            .and_then(|r| u32::try_from(r).ok())
    }

    /// Validate `bytes` as a cache file's contents (`path` only names it in errors).
    pub fn from_bytes(path: &Path, bytes: Vec<u8>) -> Result<BakedCache, CacheError> {
        Self::from_cache(Cache::parse(path, bytes, None)?)
    }

    fn from_cache(cache: Cache) -> Result<BakedCache, CacheError> {
        let path = cache.path.clone();
        let bad = |what: &str| CacheError::Malformed {
            path: path.to_path_buf(),
            what: what.to_string(),
        };
        let plan: Value = serde_json::from_slice(cache.section("plan")?)
            .map_err(|_| bad("the plan section is not JSON"))?;
        if plan["bake_format"].as_u64() != Some(BAKE_FORMAT as u64) {
            return Err(bad(&format!(
                "it holds bake layout {} where this wpbgi reads {BAKE_FORMAT} (bake the scene again)",
                plan["bake_format"]
            )));
        }
        let records = |name: &str, size: usize| -> Result<&[u8], CacheError> {
            let b = cache.section(name)?;
            if b.len() % size != 0 {
                return Err(bad(&format!(
                    "the {name} section is not a whole number of records"
                )));
            }
            Ok(b)
        };
        let surfels: Vec<SurfelRecord> =
            bytemuck::pod_collect_to_vec(records("surfels", std::mem::size_of::<SurfelRecord>())?);
        let nodes: Vec<NodeRecord> =
            bytemuck::pod_collect_to_vec(records("nodes", std::mem::size_of::<NodeRecord>())?);
        let maps = (cache.section("map_index")?.len() / 8) as u32;
        let in_range = |i: u32, n: usize| i == u32::MAX || (i as usize) < n;
        for n in &nodes {
            if !(in_range(n.node.children[0], nodes.len())
                && in_range(n.node.children[1], nodes.len())
                && in_range(n.g, maps as usize)
                && in_range(n.h, maps as usize)
                && in_range(n.area_g, maps as usize)
                && in_range(n.area_h, maps as usize)
                && (n.node.first as u64 + n.node.count as u64) <= surfels.len() as u64)
            {
                return Err(bad("a tree node points outside the file"));
            }
        }
        let order: Vec<u32> = records("order", 4)?
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        if order.len() != surfels.len() || order.iter().any(|&i| i as usize >= surfels.len()) {
            return Err(bad("the leaf order does not list the surfels"));
        }
        if surfels.iter().any(|s| !in_range(s.map, maps as usize)) {
            return Err(bad("a surfel points to a missing map"));
        }
        Ok(BakedCache {
            cache,
            plan,
            surfels,
            nodes,
            order,
        })
    }

    /// Decode map `index` of the pool (RGB for intensities and surfel radiance, f32 for
    /// projected areas: the caller knows which from where the index came).
    pub fn map<T: Coefficient>(&self, index: u32) -> Result<SparseHaar<T>, CacheError> {
        let bad = || CacheError::Malformed {
            path: self.cache.path.clone(),
            what: format!("map {index} cannot be decoded"),
        };
        let table = self.cache.section("map_index")?;
        let at = 8 * index as usize;
        let offset = table
            .get(at..at + 8)
            .and_then(|b| b.try_into().ok())
            .map(u64::from_le_bytes)
            .ok_or_else(bad)?;
        let maps = self.cache.section("maps")?;
        let bytes = maps.get(offset as usize..).ok_or_else(bad)?;
        SparseHaar::read_from(bytes).map(|(m, _)| m).ok_or_else(bad)
    }
}

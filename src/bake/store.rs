//! The bake's side of a `.wpc` cache: the node and surfel records of a [`Baked`] and its
//! sections, encoded and written atomically (the layout and the reader are
//! [`crate::cache::store`]'s).

use super::baked::Baked;
use crate::cache::store::{bake_hash, BakedCache, NodeRecord, SurfelRecord, BAKE_FORMAT, NO_MAP};
use crate::cache::{self, CacheError};
use crate::haar::{Coefficient, SparseHaar};
use crate::scene::Scene;
use crate::spectrum::Rgb;
use crate::surfels::radiance::SurfelRadiance;
use serde_json::{json, Value};
use std::path::Path;

/// Where the records' maps go: each gets the next index of the `maps` section.
trait MapSink {
    fn push<T: Coefficient>(&mut self, m: &SparseHaar<T>) -> u32;
}

/// The `maps` section under construction and its index.
#[derive(Default)]
struct MapPool {
    bytes: Vec<u8>,
    index: Vec<u64>,
}

impl MapSink for MapPool {
    fn push<T: Coefficient>(&mut self, m: &SparseHaar<T>) -> u32 {
        self.index.push(self.bytes.len() as u64);
        m.write_to(&mut self.bytes);
        (self.index.len() - 1) as u32
    }
}

/// Maps numbered as the file would number them, without encoding them.
#[derive(Default)]
struct MapCount(u32);

impl MapSink for MapCount {
    fn push<T: Coefficient>(&mut self, _: &SparseHaar<T>) -> u32 {
        self.0 += 1;
        self.0 - 1
    }
}

/// The node and surfel records of `baked`, as the cache holds them (map fields: the index each
/// map has in the file), without writing anything: what the bounces read the bake's tree
/// through while it is still in memory.
pub fn records_of(baked: &Baked) -> (Vec<NodeRecord>, Vec<SurfelRecord>) {
    records(baked, &mut MapCount::default())
}

/// The records of `baked`, their maps pushed to `maps` (nodes' G, H, projected G, H, then the
/// surfels').
fn records(baked: &Baked, maps: &mut impl MapSink) -> (Vec<NodeRecord>, Vec<SurfelRecord>) {
    let mut nodes = Vec::with_capacity(baked.tree.nodes.len());
    for ((n, c), a) in baked
        .tree
        .nodes
        .iter()
        .zip(&baked.coded.nodes)
        .zip(&baked.projected.nodes)
    {
        nodes.push(NodeRecord {
            node: *n,
            g: c.g.as_ref().map_or(NO_MAP, |m| maps.push(m)),
            h: c.h.as_ref().map_or(NO_MAP, |m| maps.push(m)),
            area_g: a.g.as_ref().map_or(NO_MAP, |m| maps.push(m)),
            area_h: a.h.as_ref().map_or(NO_MAP, |m| maps.push(m)),
        });
    }
    let mut surfels = Vec::with_capacity(baked.surfels.len());
    for ((s, r), e) in baked
        .surfels
        .iter()
        .zip(&baked.radiance)
        .zip(&baked.emitted)
    {
        let (rgb, map) = match r {
            SurfelRadiance::Rgb(c) => (*c, NO_MAP),
            SurfelRadiance::Map(m) => {
                let at = crate::haar::direction_to_square(s.n);
                (m.eval(at.x, at.y), maps.push(m))
            }
        };
        surfels.push(SurfelRecord {
            p: s.p.to_array(),
            n: s.n.to_array(),
            area: s.area,
            mesh: s.mesh,
            rgb: rgb.to_array(),
            map,
            emitted: e.to_array(),
            flags: baked.mesh_flags[s.mesh as usize],
        });
    }
    (nodes, surfels)
}

/// Save `baked`, a bake of `scene`, to `path` atomically, as `wpbgi bake` does: hashed with
/// its settings, with [`cache_stats`] in the plan.
pub fn save(path: &Path, scene: &Scene, baked: &Baked) -> Result<(), CacheError> {
    let hash = bake_hash(scene, &baked.settings.to_json());
    write(path, hash, baked, cache_stats(baked))
}

/// The figures of a bake that its inputs determine, kept in the cache's plan. Times and memory
/// are left out so that the same bake writes a byte-identical cache.
pub fn cache_stats(baked: &Baked) -> Value {
    let (maps, coefficients) = baked.coded.stored_counts();
    serde_json::json!({
        "surfels": baked.surfels.len(),
        "nodes": baked.tree.nodes.len(),
        "tree_depth": baked.tree.depth(),
        "stored_maps": maps,
        "coefficients": coefficients,
    })
}

/// Serialize `baked` to `path` atomically. `stats` is added to the plan section as is.
pub fn write(path: &Path, hash: [u8; 16], baked: &Baked, stats: Value) -> Result<(), CacheError> {
    let werr = |reason: String| CacheError::Write {
        path: path.to_path_buf(),
        reason,
    };
    let parts = Sections::of(baked, stats).map_err(werr)?;
    cache::write(path, hash, &parts.list())
}

/// The sections of a cache of `baked`, encoded.
struct Sections {
    plan: Vec<u8>,
    nodes: Vec<NodeRecord>,
    map_index: Vec<u8>,
    maps: Vec<u8>,
    surfels: Vec<SurfelRecord>,
    order: Vec<u8>,
}

impl Sections {
    fn list(&self) -> [(&str, &[u8]); 6] {
        [
            ("plan", &self.plan),
            ("nodes", bytemuck::cast_slice(&self.nodes)),
            ("map_index", &self.map_index),
            ("maps", &self.maps),
            ("surfels", bytemuck::cast_slice(&self.surfels)),
            ("order", &self.order),
        ]
    }

    fn of(baked: &Baked, stats: Value) -> Result<Sections, String> {
        let mut pool = MapPool::default();
        let (nodes, surfels) = records(baked, &mut pool);
        let plan = json!({
            "format": "wpbgi bake",
            "bake_format": BAKE_FORMAT,
            "crate_version": crate::VERSION,
            "settings": baked.settings.to_json(),
            "split_level": baked.coded.split_level,
            "plan": baked.plan.json,
            "stats": stats,
        });
        let plan = serde_json::to_vec_pretty(&plan).map_err(|e| e.to_string())?;
        let order: Vec<u8> = baked
            .tree
            .order
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let map_index: Vec<u8> = pool.index.iter().flat_map(|o| o.to_le_bytes()).collect();
        Ok(Sections {
            plan,
            nodes,
            map_index,
            maps: pool.bytes,
            surfels,
            order,
        })
    }
}

/// Write `cache` to `path` atomically, every radiance it records multiplied by `k` per
/// channel (the tree's intensity maps, the surfels' radiance, maps and emission; projected
/// areas stay), under `hash`, with `plan` as its plan section. The maps keep the order a bake
/// writes them in.
pub(crate) fn write_scaled(
    path: &Path,
    hash: [u8; 16],
    cache: &BakedCache,
    k: Rgb,
    plan: &Value,
) -> Result<(), CacheError> {
    let mut pool = MapPool::default();
    let scaled = |pool: &mut MapPool, index: u32| -> Result<u32, CacheError> {
        if index == NO_MAP {
            return Ok(NO_MAP);
        }
        let map: SparseHaar<Rgb> = cache.map(index)?;
        Ok(pool.push(&map.map_coefficients(|c| c * k)))
    };
    let kept = |pool: &mut MapPool, index: u32| -> Result<u32, CacheError> {
        if index == NO_MAP {
            return Ok(NO_MAP);
        }
        Ok(pool.push(&cache.map::<f32>(index)?))
    };
    let mut nodes = Vec::with_capacity(cache.nodes.len());
    for r in &cache.nodes {
        nodes.push(NodeRecord {
            node: r.node,
            g: scaled(&mut pool, r.g)?,
            h: scaled(&mut pool, r.h)?,
            area_g: kept(&mut pool, r.area_g)?,
            area_h: kept(&mut pool, r.area_h)?,
        });
    }
    let mut surfels = Vec::with_capacity(cache.surfels.len());
    for s in &cache.surfels {
        surfels.push(SurfelRecord {
            rgb: (Rgb::from(s.rgb) * k).to_array(),
            emitted: (Rgb::from(s.emitted) * k).to_array(),
            map: scaled(&mut pool, s.map)?,
            ..*s
        });
    }
    let werr = |reason: String| CacheError::Write {
        path: path.to_path_buf(),
        reason,
    };
    let plan = serde_json::to_vec_pretty(plan).map_err(|e| werr(e.to_string()))?;
    let map_index: Vec<u8> = pool.index.iter().flat_map(|o| o.to_le_bytes()).collect();
    let parts = Sections {
        plan,
        nodes,
        map_index,
        maps: pool.bytes,
        surfels,
        order: cache.cache.section("order")?.to_vec(),
    };
    cache::write(path, hash, &parts.list())
}

/// The cache that [`write()`] would write of `baked`, read back, without a file (`path` only
/// names it in errors).
pub fn in_memory(path: &Path, baked: &Baked) -> Result<BakedCache, CacheError> {
    let werr = |reason: String| CacheError::Write {
        path: path.to_path_buf(),
        reason,
    };
    let parts = Sections::of(baked, Value::Null).map_err(werr)?;
    let bytes = cache::to_bytes([0; 16], &parts.list()).map_err(werr)?;
    BakedCache::from_bytes(path, bytes)
}

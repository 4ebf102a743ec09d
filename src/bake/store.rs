//! The bake's side of a `.wpc` cache: the node and surfel records of a [`Baked`] and its
//! sections, encoded and written atomically (the layout and the reader are
//! [`crate::cache::store`]'s).

use super::baked::Baked;
use crate::cache::store::{bake_hash, BakedCache, NodeRecord, SurfelRecord, BAKE_FORMAT, NO_MAP};
use crate::cache::{self, CacheError};
use crate::haar::SparseHaar;
use crate::scene::Scene;
use crate::spectrum::Rgb;
use crate::surfels::radiance::SurfelRadiance;
use rayon::prelude::*;
use serde_json::{json, Value};
use std::borrow::Cow;
use std::path::Path;

/// A map of the `maps` section, borrowed from a bake or decoded and made anew (a rescaled
/// cache's): RGB for intensities and surfel radiance, scalar for projected areas.
enum StoredMap<'a> {
    Rgb(Cow<'a, SparseHaar<Rgb>>),
    Scalar(Cow<'a, SparseHaar<f32>>),
}

impl StoredMap<'_> {
    /// The same map, borrowed from this one.
    fn borrowed(&self) -> StoredMap<'_> {
        match self {
            StoredMap::Rgb(m) => StoredMap::Rgb(Cow::Borrowed(m)),
            StoredMap::Scalar(m) => StoredMap::Scalar(Cow::Borrowed(m)),
        }
    }

    fn encoded_len(&self) -> usize {
        match self {
            StoredMap::Rgb(m) => m.encoded_len(),
            StoredMap::Scalar(m) => m.encoded_len(),
        }
    }

    fn write_to(&self, out: &mut Vec<u8>) {
        match self {
            StoredMap::Rgb(m) => m.write_to(out),
            StoredMap::Scalar(m) => m.write_to(out),
        }
    }
}

/// Maps per piece of the `maps` section that one task encodes: a few megabytes, so that
/// every thread has pieces to take and each piece is one allocation of its exact size.
const MAPS_PER_PIECE: usize = 2048;

/// The `maps` section, encoded in pieces on all threads, and its index: where each map
/// starts in it (the pieces joined).
struct EncodedMaps {
    pieces: Vec<Vec<u8>>,
    index: Vec<u64>,
}

impl EncodedMaps {
    /// The maps that `map` makes of each of `sources`, in order. The bytes are those of
    /// encoding them one after the other on one thread (a cache of 91 MB spent 0.3 s in that
    /// single thread, most of it growing one buffer into fresh pages).
    fn of<S: Sync, E: Send>(
        sources: &[S],
        map: impl for<'s> Fn(&'s S) -> Result<StoredMap<'s>, E> + Sync,
    ) -> Result<EncodedMaps, E> {
        let pieces: Vec<(Vec<u8>, Vec<usize>)> = sources
            .par_chunks(MAPS_PER_PIECE)
            .map(|chunk| {
                let maps = chunk.iter().map(&map).collect::<Result<Vec<_>, E>>()?;
                let lengths: Vec<usize> = maps.iter().map(StoredMap::encoded_len).collect();
                let mut bytes = Vec::with_capacity(lengths.iter().sum());
                for m in &maps {
                    m.write_to(&mut bytes);
                }
                Ok((bytes, lengths))
            })
            .collect::<Result<_, E>>()?;
        let mut index = Vec::with_capacity(sources.len());
        let mut at = 0u64;
        for length in pieces.iter().flat_map(|(_, lengths)| lengths) {
            index.push(at);
            at += *length as u64;
        }
        Ok(EncodedMaps {
            pieces: pieces.into_iter().map(|(bytes, _)| bytes).collect(),
            index,
        })
    }
}

/// The records' maps in the order the file numbers them: pushing one gives its index.
#[derive(Default)]
struct MapList<'a>(Vec<StoredMap<'a>>);

impl<'a> MapList<'a> {
    fn push(&mut self, m: StoredMap<'a>) -> u32 {
        self.0.push(m);
        (self.0.len() - 1) as u32
    }

    fn rgb(&mut self, m: &'a SparseHaar<Rgb>) -> u32 {
        self.push(StoredMap::Rgb(Cow::Borrowed(m)))
    }

    fn scalar(&mut self, m: &'a SparseHaar<f32>) -> u32 {
        self.push(StoredMap::Scalar(Cow::Borrowed(m)))
    }
}

/// The node and surfel records of `baked`, as the cache holds them (map fields: the index each
/// map has in the file), without writing anything: what the bounces read the bake's tree
/// through while it is still in memory.
pub fn records_of(baked: &Baked) -> (Vec<NodeRecord>, Vec<SurfelRecord>) {
    let (nodes, surfels, _) = records(baked);
    (nodes, surfels)
}

/// The records of `baked` and their maps in file order (per node its G, H, projected G, H,
/// then the surfels').
fn records(baked: &Baked) -> (Vec<NodeRecord>, Vec<SurfelRecord>, MapList<'_>) {
    let mut maps = MapList::default();
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
            g: c.g.as_ref().map_or(NO_MAP, |m| maps.rgb(m)),
            h: c.h.as_ref().map_or(NO_MAP, |m| maps.rgb(m)),
            area_g: a.g.as_ref().map_or(NO_MAP, |m| maps.scalar(m)),
            area_h: a.h.as_ref().map_or(NO_MAP, |m| maps.scalar(m)),
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
                (m.eval(at.x, at.y), maps.rgb(m))
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
    (nodes, surfels, maps)
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
    parts.with_pieces(|sections| cache::write_pieces(path, hash, sections))
}

/// The sections of a cache of `baked`, encoded.
struct Sections<'a> {
    plan: Vec<u8>,
    nodes: Vec<NodeRecord>,
    map_index: Vec<u8>,
    maps: EncodedMaps,
    surfels: Vec<SurfelRecord>,
    order: Cow<'a, [u8]>,
}

impl<'a> Sections<'a> {
    /// `f` of the sections as [`cache::write_pieces`] takes them.
    fn with_pieces<R>(&self, f: impl FnOnce(&[(&str, &[&[u8]])]) -> R) -> R {
        let maps: Vec<&[u8]> = self.maps.pieces.iter().map(Vec::as_slice).collect();
        f(&[
            ("plan", &[&self.plan]),
            ("nodes", &[bytemuck::cast_slice(&self.nodes)]),
            ("map_index", &[&self.map_index]),
            ("maps", &maps),
            ("surfels", &[bytemuck::cast_slice(&self.surfels)]),
            ("order", &[&self.order]),
        ])
    }

    /// The sections of `baked`'s cache, with `stats` in its plan.
    fn of(baked: &Baked, stats: Value) -> Result<Sections<'a>, String> {
        let (nodes, surfels, maps) = records(baked);
        let maps = EncodedMaps::of(&maps.0, |m| Ok::<_, String>(m.borrowed()))?;
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
        Ok(Sections {
            plan,
            nodes,
            map_index: index_bytes(&maps.index),
            maps,
            surfels,
            order: Cow::Owned(order),
        })
    }
}

/// The `map_index` section of `index`.
fn index_bytes(index: &[u64]) -> Vec<u8> {
    index.iter().flat_map(|o| o.to_le_bytes()).collect()
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
    /// A map of the new cache: one of `cache`'s, scaled by `k` or kept.
    enum Source {
        Scaled(u32),
        Kept(u32),
    }
    let mut sources = Vec::new();
    let mut push = |source: fn(u32) -> Source, index: u32| {
        if index == NO_MAP {
            return NO_MAP;
        }
        sources.push(source(index));
        (sources.len() - 1) as u32
    };
    let mut nodes = Vec::with_capacity(cache.nodes.len());
    for r in &cache.nodes {
        nodes.push(NodeRecord {
            node: r.node,
            g: push(Source::Scaled, r.g),
            h: push(Source::Scaled, r.h),
            area_g: push(Source::Kept, r.area_g),
            area_h: push(Source::Kept, r.area_h),
        });
    }
    let mut surfels = Vec::with_capacity(cache.surfels.len());
    for s in &cache.surfels {
        surfels.push(SurfelRecord {
            rgb: (Rgb::from(s.rgb) * k).to_array(),
            emitted: (Rgb::from(s.emitted) * k).to_array(),
            map: push(Source::Scaled, s.map),
            ..*s
        });
    }
    let maps = EncodedMaps::of(&sources, |source| {
        Ok::<_, CacheError>(match *source {
            Source::Scaled(index) => StoredMap::Rgb(Cow::Owned(
                cache.map::<Rgb>(index)?.map_coefficients(|c| c * k),
            )),
            Source::Kept(index) => StoredMap::Scalar(Cow::Owned(cache.map::<f32>(index)?)),
        })
    })?;
    let werr = |reason: String| CacheError::Write {
        path: path.to_path_buf(),
        reason,
    };
    let plan = serde_json::to_vec_pretty(plan).map_err(|e| werr(e.to_string()))?;
    let parts = Sections {
        plan,
        nodes,
        map_index: index_bytes(&maps.index),
        maps,
        surfels,
        order: Cow::Borrowed(cache.cache.section("order")?),
    };
    parts.with_pieces(|sections| cache::write_pieces(path, hash, sections))
}

/// The cache that [`write()`] would write of `baked`, read back, without a file (`path` only
/// names it in errors).
pub fn in_memory(path: &Path, baked: &Baked) -> Result<BakedCache, CacheError> {
    let werr = |reason: String| CacheError::Write {
        path: path.to_path_buf(),
        reason,
    };
    let parts = Sections::of(baked, Value::Null).map_err(werr)?;
    let bytes = parts
        .with_pieces(|sections| cache::to_bytes([0; 16], sections))
        .map_err(werr)?;
    BakedCache::from_bytes(path, bytes)
}

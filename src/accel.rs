//! Ray tracing against all scene triangles: an obvhs compressed wide BVH (CWBVH) traversed with
//! the watertight triangle test of [`crate::geometry::triangle`] (obvhs's own test is not
//! watertight).
//!
//! Watertight triangles are not enough: the node culling must never reject a box the ray
//! touches. obvhs replaces direction components smaller than f32::EPSILON by ±EPSILON in its
//! slab test, so its culling ray can drift from the true ray by up to 1.2e-7 per unit of t, and a
//! ray lying exactly in a box's face plane (an axis-aligned ray through a vertex) gets an empty
//! slab interval. So the BVH is built over triangle boxes dilated by 1e-6 of the scene diagonal,
//! and every traversal uses a unit direction (t never exceeds the diagonal inside the scene), so
//! the dilation always covers the drift. Negative-zero direction components are made positive
//! (see [`unit`]), and the traversal ray starts slightly behind the true origin because obvhs
//! culls nodes that end before an absolute t of 1e-4 (see `ORIGIN_SHIFT`).
//!
//! Alpha cut-outs (glTF `MASK`) are tested at each candidate hit: a hit where the material's
//! alpha is below its cutoff is no hit, so every ray (camera, shadow, bounce) passes through
//! the holes.

use crate::geometry::triangle::{TriangleHit, WatertightRay};
use crate::scene::{interpolate_uv, Cutout, Scene, Texture};
use glam::{Vec2, Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use obvhs::{Boundable, BvhBuildParams};
use std::time::Duration;

/// A closest hit: which triangle, where along the ray, and its barycentrics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub mesh: u32,
    pub triangle: u32,
    /// Weights of the triangle's three vertices.
    pub b: [f32; 3],
}

/// A triangle's bounding box, dilated (see the module docs).
struct PaddedBox(Aabb);

impl Boundable for PaddedBox {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// The unit direction of `dir` and the factor that converts t along it back to t along `dir`.
/// Negative zeros become positive: obvhs takes the octant from `x < 0` but the inverse direction
/// from the sign bit, and a disagreement swaps a slab's near and far planes (empty interval).
#[inline]
fn unit(dir: Vec3) -> Option<(Vec3A, f32)> {
    let len = dir.length();
    (len > 0.0 && len.is_finite()).then(|| (Vec3A::from(dir / len) + Vec3A::ZERO, len))
}

/// The acceleration structure over every triangle of a scene.
pub struct Accel {
    bvh: CwBvh,
    tris: Vec<Triangle>,
    /// `(mesh, triangle within mesh)` of each entry of `tris`.
    ids: Vec<(u32, u32)>,
    /// Per mesh, its alpha cut-out where its material has one that varies (empty where no
    /// mesh has one): a hit in a hole is no hit.
    masks: Vec<Option<Mask>>,
}

/// A mesh's alpha cut-out, with what its test reads: the texture (alone, as texture 0), the
/// vertices' texture coordinates and the triangles (the accel owns no scene).
struct Mask {
    cutout: Cutout,
    textures: Vec<Texture>,
    uvs: Option<Vec<Vec2>>,
    triangles: Vec<[u32; 3]>,
}

impl Mask {
    fn of(scene: &Scene, mesh: &crate::scene::Mesh) -> Option<Mask> {
        let mut cutout = scene.materials.get(mesh.material)?.cutout?;
        if cutout.constant().is_some() {
            // Constant: kept whole (or left out of the scene whole).
            return None;
        }
        let textures = match &mut cutout.texture {
            Some(c) => {
                let t = scene.textures.get(c.texture.texture)?.clone();
                c.texture.texture = 0;
                vec![t]
            }
            None => Vec::new(),
        };
        Some(Mask {
            cutout,
            textures,
            uvs: mesh.uvs.clone(),
            triangles: mesh.triangles.clone(),
        })
    }

    /// Whether the surface is there at barycentrics `b` of triangle `triangle`.
    fn keeps(&self, triangle: u32, b: [f32; 3]) -> bool {
        let t = self.triangles[triangle as usize];
        let uv = interpolate_uv(self.uvs.as_deref(), t, b);
        self.cutout.keeps(&self.textures, uv)
    }
}

impl Accel {
    /// Build over all triangles of `scene` (PLOC, obvhs's "medium" preset).
    pub fn build(scene: &Scene) -> Accel {
        let mut tris = Vec::with_capacity(scene.triangle_count());
        let mut ids = Vec::with_capacity(scene.triangle_count());
        for (mi, m) in scene.meshes.iter().enumerate() {
            for (ti, t) in m.triangles.iter().enumerate() {
                let p = |i: u32| Vec3A::from(m.positions[i as usize]);
                tris.push(Triangle {
                    v0: p(t[0]),
                    v1: p(t[1]),
                    v2: p(t[2]),
                });
                ids.push((mi as u32, ti as u32));
            }
        }
        let mut accel = Self::from_triangles(tris, ids);
        let masks: Vec<Option<Mask>> = scene.meshes.iter().map(|m| Mask::of(scene, m)).collect();
        if masks.iter().any(Option::is_some) {
            accel.masks = masks;
        }
        accel
    }

    /// Whether the hit `h` on entry `id` is on the surface (not in a cut-out's hole).
    #[inline]
    fn solid(&self, id: usize, h: &TriangleHit) -> bool {
        if self.masks.is_empty() {
            return true;
        }
        let (mesh, triangle) = self.ids[id];
        self.masks[mesh as usize]
            .as_ref()
            .is_none_or(|m| m.keeps(triangle, h.b))
    }

    fn from_triangles(tris: Vec<Triangle>, ids: Vec<(u32, u32)>) -> Accel {
        let bvh = if tris.is_empty() {
            CwBvh::default()
        } else {
            let mut all = Aabb::empty();
            for t in &tris {
                all = all.union(&t.aabb());
            }
            let pad = Vec3A::splat(1e-6 * (all.max - all.min).length());
            let boxes: Vec<PaddedBox> = tris
                .iter()
                .map(|t| {
                    let b = t.aabb();
                    PaddedBox(Aabb::new(
                        b.min - pad - b.min.abs() * 1e-6,
                        b.max + pad + b.max.abs() * 1e-6,
                    ))
                })
                .collect();
            build_cwbvh(
                &boxes,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            )
        };
        Accel {
            bvh,
            tris,
            ids,
            masks: Vec::new(),
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// The traversal set-up shared by every query, or `None` when nothing can be hit.
    fn query(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Query> {
        if self.tris.is_empty() {
            return None;
        }
        let (d, len) = unit(dir)?;
        let o = Vec3A::from(origin);
        let (tmin, tmax) = (tmin * len, tmax * len);
        Some(Query {
            wt: WatertightRay::new(o, d),
            ray: Ray::new(
                o - d * ORIGIN_SHIFT,
                d,
                tmin + ORIGIN_SHIFT,
                tmax + ORIGIN_SHIFT,
            ),
            len,
            tmin,
            tmax,
        })
    }

    /// Closest intersection in `(tmin, tmax)` along `origin + t·dir` (`dir` need not be unit).
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        let q = self.query(origin, dir, tmin, tmax)?;
        let mut best: Option<(usize, TriangleHit)> = None;
        let mut closest = q.tmax;
        let mut hit = RayHit::none();
        hit.t = q.ray.tmax;
        self.bvh.ray_traverse(q.ray, &mut hit, |_, i| {
            let id = self.bvh.primitive_indices[i] as usize;
            let tri = &self.tris[id];
            match q.wt.intersect(tri.v0, tri.v1, tri.v2, q.tmin, closest) {
                Some(h) if self.solid(id, &h) => {
                    best = Some((id, h));
                    closest = h.t;
                    to_traversal_t(h.t)
                }
                _ => f32::INFINITY,
            }
        });
        best.map(|(id, h)| {
            let (mesh, triangle) = self.ids[id];
            Hit {
                t: h.t / q.len,
                mesh,
                triangle,
                b: h.b,
            }
        })
    }

    /// True when anything lies in `(tmin, tmax)` along the ray.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        let Some(q) = self.query(origin, dir, tmin, tmax) else {
            return false;
        };
        !self.bvh.ray_traverse_miss(q.ray, |_, i| {
            let id = self.bvh.primitive_indices[i] as usize;
            let tri = &self.tris[id];
            match q.wt.intersect(tri.v0, tri.v1, tri.v2, q.tmin, q.tmax) {
                Some(h) if self.solid(id, &h) => f32::NEG_INFINITY,
                _ => f32::INFINITY,
            }
        })
    }

    /// Every intersection along the ray in `(tmin, tmax)`, unsorted (for tests and diagnostics).
    pub fn all_hits(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Vec<Hit> {
        let mut out = Vec::new();
        let Some(q) = self.query(origin, dir, tmin, tmax) else {
            return out;
        };
        self.bvh.ray_traverse_anyhit(q.ray, |_, i| {
            let id = self.bvh.primitive_indices[i] as usize;
            let tri = &self.tris[id];
            if let Some(h) =
                q.wt.intersect(tri.v0, tri.v1, tri.v2, q.tmin, q.tmax)
                    .filter(|h| self.solid(id, h))
            {
                let (mesh, triangle) = self.ids[id];
                out.push(Hit {
                    t: h.t / q.len,
                    mesh,
                    triangle,
                    b: h.b,
                });
            }
        });
        out
    }
}

/// One query's rays: `wt` is the true ray for the triangle tests, `ray` the BVH traversal ray
/// (origin moved back by [`ORIGIN_SHIFT`]); `tmin`, `tmax` and `len` are along the unit direction.
struct Query {
    wt: WatertightRay,
    ray: Ray,
    len: f32,
    tmin: f32,
    tmax: f32,
}

/// obvhs culls every node whose slab interval ends before t = 1e-4 (an absolute constant in its
/// node test, ignoring the ray's tmin), which in a millimetre-scale scene throws away the wall a
/// ray leaving a corner is about to hit. The traversal ray therefore starts this far behind the
/// true origin, so every t ≥ 0 of the true ray is ≥ 2e-4 for the node test.
const ORIGIN_SHIFT: f32 = 2e-4;

/// A hit distance of the true ray as a traversal-ray distance, rounded up so the node culling
/// can never drop a node holding an equally close hit.
#[inline]
fn to_traversal_t(t: f32) -> f32 {
    (t + ORIGIN_SHIFT) * (1.0 + 4.0 * f32::EPSILON)
}

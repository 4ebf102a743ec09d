//! Ray tracing against all scene triangles: an eight-wide BVH (`bvh8`, built by collapsing
//! obvhs's binary PLOC tree) traversed with a conservative slab test, and the watertight
//! triangle test of [`crate::geometry::triangle`] (obvhs's own test is not watertight), run
//! on a leaf's four triangles at once; the rare triangle whose edge functions or distance
//! need double precision is finished one at a time.
//!
//! Watertight triangles are not enough: the node culling must never reject a box the ray
//! touches. The slab test rounds outwards as pbrt-v4's does and treats a ray lying in a slab's
//! plane as inside it (see `bvh8`), so the boxes are the triangles' own, undilated.
//!
//! Alpha cut-outs (glTF `MASK`) are tested at each candidate hit: a hit where the material's
//! alpha is below its cutoff is no hit, so every ray (camera, shadow, bounce) passes through
//! the holes.
//!
//! A query in a small scene is a few node visits and one or two packet tests, so its fixed
//! costs weigh as much as its tests. Every closure a query hands the traversal (the leaf
//! visit, the packet's lane iterator, the stack's set-up) is `#[inline(always)]`: LLVM kept
//! them as calls of their own, each saving and restoring registers (a query that meets nothing
//! in a one-triangle scene: about 100 ns with the calls, 87 without). So is the set-up of the
//! query's rays (`Accel::query`): the binary of `wpbgi` inlined it, but in a crate that used
//! this one (a scratch benchmark) LLVM kept it as a call whose 160-byte result was copied by
//! `memcpy` before every traversal, and closest hits on random rays ran at 0.8 of the speed.
//! And nothing a query
//! decides from its ray alone is a branch or a jump table: the triangle test's dominant axis
//! and the swap that keeps the winding are computed, the origin's coordinates along them
//! kept, and lanes and axes read through arrays (glam's `Vec3A` and `Vec4` indexing is a
//! `match`). Those decisions are as random as the rays, so a branch on them is mispredicted
//! about once a query (78 ns). Together: closest hits on random rays in a Cornell box
//! 1.27–1.31× and occlusion queries 1.16–1.23× as fast, the same hits bit for bit
//! (docs/benchmarks.md). The node test still picks each axis's near plane by a branch on the
//! ray's sign: a blend instead was slower (one ray takes the same branch at every node).

mod bvh8;

use crate::geometry::triangle::{TriangleHit, WatertightRay};
use crate::scene::{interpolate_uv, Cutout, Mesh, Scene, Texture};
use bvh8::{BoxRay, Bvh8, Packet, Visit, SET};
use glam::{Vec2, Vec3, Vec3A};
use obvhs::bvh2::builder::build_bvh2;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use std::time::Duration;

/// A closest hit: which triangle, where along the ray, and its barycentrics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray.
    pub t: f32,
    /// The mesh hit.
    pub mesh: u32,
    /// The triangle hit, within the mesh.
    pub triangle: u32,
    /// Weights of the triangle's three vertices.
    pub b: [f32; 3],
    /// The triangle's vertices, as tested (the mesh's positions bit for bit), so that the hit
    /// point is interpolated without fetching them again from the mesh.
    pub corners: [Vec3A; 3],
}

/// The unit direction of `dir` and the factor that converts t along it back to t along `dir`
/// (the triangle test runs on the unit direction, so its rounding does not depend on the
/// length a caller happens to pass).
#[inline]
fn unit(dir: Vec3) -> Option<(Vec3A, f32)> {
    let len = dir.length();
    (len > 0.0 && len.is_finite()).then(|| (Vec3A::from(dir / len), len))
}

/// A triangle of the scene: its mesh and its index within the mesh.
pub type TriangleId = (u32, u32);

/// How many segments [`Accel::occluded_set`] takes at once.
pub const OCCLUSION_SET: usize = SET;

/// A stretch of a ray to test for occlusion: `origin + t·dir` for `t` in `(tmin, tmax)`
/// (`dir` need not be unit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Where the ray starts.
    pub origin: Vec3,
    /// Its direction, of any length.
    pub dir: Vec3,
    /// The open range of `t` tested.
    pub tmin: f32,
    /// See `tmin`.
    pub tmax: f32,
}

/// The acceleration structure over every triangle of a scene.
pub struct Accel {
    bvh: Bvh8,
    /// How many triangles the tree holds.
    triangles: usize,
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
    fn of(scene: &Scene, mesh: &Mesh) -> Option<Mask> {
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
        Self::build_over(scene, |_| true)
    }

    /// Build over the triangles of the meshes of `scene` for which `keep` holds (their
    /// indices stay the scene's).
    pub fn build_over(scene: &Scene, keep: impl Fn(&Mesh) -> bool) -> Accel {
        let mut tris = Vec::with_capacity(scene.triangle_count());
        let mut ids = Vec::with_capacity(scene.triangle_count());
        for (mi, m) in scene.meshes.iter().enumerate() {
            if !keep(m) {
                continue;
            }
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

    /// Whether the hit `h` on lane `lane` of `packet` is on the surface (not in a cut-out's
    /// hole).
    #[inline]
    fn solid(&self, packet: &Packet, lane: usize, h: &TriangleHit) -> bool {
        if self.masks.is_empty() {
            return true;
        }
        self.masks[packet.mesh[lane] as usize]
            .as_ref()
            .is_none_or(|m| m.keeps(packet.triangle[lane], h.b))
    }

    fn from_triangles(tris: Vec<Triangle>, ids: Vec<(u32, u32)>) -> Accel {
        let bvh = if tris.is_empty() {
            Bvh8::from_bvh2(&Default::default(), &[], &[])
        } else {
            let bvh2 = build_bvh2(&tris, BUILD, &mut Duration::default());
            let vertices: Vec<[Vec3A; 3]> = tris.iter().map(|t| [t.v0, t.v1, t.v2]).collect();
            Bvh8::from_bvh2(&bvh2, &vertices, &ids)
        };
        Accel {
            bvh,
            triangles: tris.len(),
            masks: Vec::new(),
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles
    }

    /// Whether the scene has no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles == 0
    }

    /// The traversal set-up shared by every query, or `None` when nothing can be hit: an
    /// empty tree, a direction of no length or not finite, or an origin not finite (its slab
    /// distances would be NaN, so the node test would enter every box, and no triangle test
    /// can hit). `leaving`: the triangle the ray is spawned off, where the caller knows it.
    #[inline(always)]
    fn query(
        &self,
        leaving: Option<TriangleId>,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
    ) -> Option<Query> {
        let (d, len) = unit(dir)?;
        self.query_along(leaving, origin, d, len, tmin, tmax)
    }

    /// [`Accel::query`] along the unit direction `d`, of which the caller's is `len` times
    /// as long.
    #[inline(always)]
    fn query_along(
        &self,
        leaving: Option<TriangleId>,
        origin: Vec3,
        d: Vec3A,
        len: f32,
        tmin: f32,
        tmax: f32,
    ) -> Option<Query> {
        if self.is_empty() || !origin.is_finite() {
            return None;
        }
        let o = Vec3A::from(origin);
        Some(Query {
            wt: WatertightRay::new(o, d),
            boxes: BoxRay::new(o, d, tmin * len),
            len,
            tmin: tmin * len,
            tmax: tmax * len,
            leaving,
        })
    }

    /// The lanes of `packet` that `q` hits in `(q.tmin, tmax)`, in lane order, with their hits:
    /// the four lanes tested at once, the few the SIMD test leaves undecided one by one.
    #[inline(always)]
    fn packet_hits<'a>(
        &'a self,
        q: &'a Query,
        packet: &'a Packet,
        tmax: f32,
    ) -> impl Iterator<Item = (usize, TriangleHit)> + 'a {
        let found = q.wt.intersect4(&packet.v, q.tmin, tmax);
        let used = packet.used();
        let (hit, undecided) = (found.hit & used, found.undecided & used);
        let mut lanes = hit | undecided;
        std::iter::from_fn(
            #[inline(always)]
            move || {
                while lanes != 0 {
                    let lane = lanes.trailing_zeros() as usize;
                    lanes &= lanes - 1;
                    let h = if hit & (1 << lane) != 0 {
                        found.lane(lane)
                    } else {
                        // An undecided lane is mostly the triangle the ray leaves, its
                        // distance within rounding of zero, which the decision in double
                        // precision would reject: the origin lies off its plane on the
                        // ray's side.
                        if q.leaving == Some((packet.mesh[lane], packet.triangle[lane])) {
                            continue;
                        }
                        let [p0, p1, p2] = packet.triangle(lane);
                        match q.wt.intersect(p0, p1, p2, q.tmin, tmax) {
                            Some(h) => h,
                            None => continue,
                        }
                    };
                    if self.solid(packet, lane, &h) {
                        return Some((lane, h));
                    }
                }
                None
            },
        )
    }

    /// The hit `h` of lane `lane` of `packet`, its distance along the query's own direction.
    fn hit(q: &Query, packet: &Packet, lane: usize, h: TriangleHit) -> Hit {
        Hit {
            t: h.t / q.len,
            mesh: packet.mesh[lane],
            triangle: packet.triangle[lane],
            b: h.b,
            corners: packet.triangle(lane),
        }
    }

    /// Closest intersection in `(tmin, tmax)` along `origin + t·dir` (`dir` need not be unit).
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        self.closest_hit_of(&self.query(None, origin, dir, tmin, tmax)?)
    }

    /// [`Accel::closest_hit`] along a unit `dir` (as `Vec3::normalize` leaves it: within a few
    /// ulps of length 1), of a ray spawned off triangle `leaving` where it is `Some` (its
    /// origin offset off the triangle's plane towards `dir`), for a path tracer's rays. The
    /// direction is taken as it is, not normalised again (a square root and a division on
    /// the way from one vertex to the next: `wpbgi reference` 0.94–0.96 of the time without
    /// them, medians of ten alternated runs), so the hit's distance is along `dir` itself;
    /// and the triangle the ray leaves (a closest hit's most common undecided lane) is
    /// skipped, not decided in double precision. A `dir` not finite meets nothing.
    #[inline(always)]
    pub fn closest_hit_unit(
        &self,
        leaving: Option<TriangleId>,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
    ) -> Option<Hit> {
        debug_assert!(
            !dir.is_finite() || (dir.length_squared() - 1.0).abs() < 1e-5,
            "closest_hit_unit along {dir}, not of unit length"
        );
        if !dir.is_finite() {
            return None;
        }
        self.closest_hit_of(&self.query_along(
            leaving,
            origin,
            Vec3A::from(dir),
            1.0,
            tmin,
            tmax,
        )?)
    }

    #[inline(always)]
    fn closest_hit_of(&self, q: &Query) -> Option<Hit> {
        let mut best: Option<(&Packet, usize, TriangleHit)> = None;
        let mut closest = q.tmax;
        self.bvh.traverse(
            &q.boxes,
            q.tmax,
            true,
            #[inline(always)]
            |packets| {
                for packet in packets {
                    // The first of equally close hits wins, as in lane-by-lane order.
                    for (lane, h) in self.packet_hits(q, packet, closest) {
                        if h.t < closest {
                            best = Some((packet, lane, h));
                            closest = h.t;
                        }
                    }
                }
                Visit::Bound(rounded_up(closest))
            },
        );
        best.map(|(packet, lane, h)| Self::hit(q, packet, lane, h))
    }

    /// True when anything lies in `(tmin, tmax)` along the ray.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        self.query(None, origin, dir, tmin, tmax)
            .is_some_and(|q| self.occluded_of(&q))
    }

    /// [`Accel::occluded`] for a ray spawned off triangle `leaving` where it is `Some` (its
    /// origin offset off the triangle's plane towards `dir`): the same answer, without
    /// deciding in double precision that the ray does not meet the triangle it leaves.
    #[inline(always)]
    pub fn occluded_leaving(
        &self,
        leaving: Option<TriangleId>,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
    ) -> bool {
        self.query(leaving, origin, dir, tmin, tmax)
            .is_some_and(|q| self.occluded_of(&q))
    }

    fn occluded_of(&self, q: &Query) -> bool {
        !self.bvh.traverse(
            &q.boxes,
            q.tmax,
            false,
            #[inline(always)]
            |packets| {
                for packet in packets {
                    if self.packet_hits(q, packet, q.tmax).next().is_some() {
                        return Visit::Stop;
                    }
                }
                Visit::Bound(q.tmax)
            },
        )
    }

    /// Whether anything lies along each of `segments` (at most [`OCCLUSION_SET`]): bit `i` of
    /// the answer is [`Accel::occluded`] of segment `i`, the same test bit for bit, with the
    /// segments traversing the tree together (`Bvh8::traverse_set`): a pixel's shadow rays
    /// towards one light pass the same nodes, whose visits they then share.
    pub fn occluded_set(&self, segments: &[Segment]) -> u32 {
        debug_assert!(segments.len() <= OCCLUSION_SET);
        let queries: [Option<Query>; SET] = std::array::from_fn(|i| {
            let s = segments.get(i)?;
            self.query(None, s.origin, s.dir, s.tmin, s.tmax)
        });
        let unused = BoxRay::new(Vec3A::ZERO, Vec3A::X, 0.0);
        let boxes = queries
            .each_ref()
            .map(|q| q.as_ref().map_or(unused, |q| q.boxes));
        let tmax = queries
            .each_ref()
            .map(|q| q.as_ref().map_or(0.0, |q| q.tmax));
        let open = (0..SET)
            .filter(|&i| queries[i].is_some())
            .fold(0, |m, i| m | 1 << i);
        self.bvh.traverse_set(
            &boxes,
            &tmax,
            open,
            #[inline(always)]
            |packets, open| {
                let mut found = 0;
                let mut left = open;
                while left != 0 {
                    let i = left.trailing_zeros() as usize;
                    left &= left - 1;
                    if let Some(q) = &queries[i] {
                        if packets
                            .iter()
                            .any(|packet| self.packet_hits(q, packet, q.tmax).next().is_some())
                        {
                            found |= 1 << i;
                        }
                    }
                }
                found
            },
        )
    }

    /// Every intersection along the ray in `(tmin, tmax)`, unsorted (for tests and diagnostics).
    pub fn all_hits(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Vec<Hit> {
        let mut out = Vec::new();
        let Some(q) = self.query(None, origin, dir, tmin, tmax) else {
            return out;
        };
        self.bvh.traverse(&q.boxes, q.tmax, false, |packets| {
            for packet in packets {
                out.extend(
                    self.packet_hits(&q, packet, q.tmax)
                        .map(|(lane, h)| Self::hit(&q, packet, lane, h)),
                );
            }
            Visit::Bound(q.tmax)
        });
        out
    }
}

/// obvhs's "medium" build with leaves of at most four triangles (one [`Packet`]).
const BUILD: BvhBuildParams = BvhBuildParams {
    max_prims_per_leaf: 4,
    ..BvhBuildParams::medium_build()
};

/// One query's rays along the unit direction: `wt` for the triangle tests, `boxes` for the
/// node tests; `tmin` and `tmax` are along the unit direction and `len` converts back.
struct Query {
    wt: WatertightRay,
    boxes: BoxRay,
    len: f32,
    tmin: f32,
    tmax: f32,
    /// The triangle the ray is spawned off
    /// ([`offset_origin`](crate::geometry::offset::offset_origin)), where the caller knows
    /// it: the ray cannot meet it again.
    leaving: Option<TriangleId>,
}

/// A hit distance rounded up, as the far bound of the boxes still to visit: a box whose entry
/// rounds to just past the closest hit may still hold an equally close one.
#[inline]
fn rounded_up(t: f32) -> f32 {
    t * (1.0 + 4.0 * f32::EPSILON)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::Sampler;

    /// The closest of every triangle's own watertight test: what the tree must reproduce.
    fn brute_force(tris: &[Triangle], o: Vec3, d: Vec3, tmax: f32) -> Option<(usize, f32)> {
        let (u, len) = unit(d)?;
        let wt = WatertightRay::new(Vec3A::from(o), u);
        let mut best: Option<(usize, f32)> = None;
        for (i, t) in tris.iter().enumerate() {
            let limit = best.map_or(tmax * len, |b| b.1);
            if let Some(h) = wt.intersect(t.v0, t.v1, t.v2, 0.0, limit) {
                best = Some((i, h.t));
            }
        }
        best.map(|(i, t)| (i, t / len))
    }

    /// The accel over `tris`, its node test with AVX where `avx` and the CPU has it, else
    /// with SSE (so both paths are tested on a machine with AVX).
    fn accel_over(tris: &[Triangle], avx: bool) -> Accel {
        let ids = (0..tris.len() as u32).map(|i| (0, i)).collect();
        let mut accel = Accel::from_triangles(tris.to_vec(), ids);
        accel.bvh.use_avx(avx);
        accel
    }

    /// A uniform point of the cube of side `scale` centred on the origin.
    fn random_point(s: &mut Sampler, scale: f32) -> Vec3A {
        let (a, b) = (s.next_2d(), s.next_1d());
        Vec3A::new(a.x - 0.5, a.y - 0.5, b - 0.5) * scale
    }

    /// 3 000 triangles of about unit size scattered through a cube of side 10.
    fn random_triangles(point: &mut impl FnMut(f32) -> Vec3A) -> Vec<Triangle> {
        (0..3000)
            .map(|_| {
                let c = point(10.0);
                Triangle {
                    v0: c + point(1.0),
                    v1: c + point(1.0),
                    v2: c + point(1.0),
                }
            })
            .collect()
    }

    /// Random triangles in a cube and random rays: the tree finds exactly the brute-force
    /// closest hit (same triangle, same distance) and agrees on occlusion, with and without
    /// a far limit.
    #[test]
    fn closest_hit_and_occlusion_match_brute_force() {
        let mut s = Sampler::new(7, 0, 0);
        let mut point = |scale: f32| random_point(&mut s, scale);
        let tris = random_triangles(&mut point);
        for avx in [false, true] {
            let accel = accel_over(&tris, avx);
            let mut hits = 0;
            for _ in 0..4000 {
                let o = Vec3::from(point(12.0));
                let d = Vec3::from(point(2.0));
                for tmax in [f32::INFINITY, 3.0] {
                    let expected = brute_force(&tris, o, d, tmax);
                    let got = accel.closest_hit(o, d, 0.0, tmax);
                    assert_eq!(
                        got.map(|h| (h.triangle as usize, h.t)),
                        expected,
                        "ray {o} {d} tmax {tmax}"
                    );
                    assert_eq!(accel.occluded(o, d, 0.0, tmax), expected.is_some());
                    // The hit's corners are the triangle's own vertices, bit for bit.
                    if let Some(h) = got {
                        let t = &tris[h.triangle as usize];
                        assert_eq!(h.corners, [t.v0, t.v1, t.v2], "ray {o} {d}");
                    }
                    hits += usize::from(expected.is_some());
                }
            }
            assert!(hits > 1000, "{hits} hits: the test must exercise hits");
        }
    }

    /// A ray spawned off a triangle (a uniform point of it, offset towards a uniform
    /// direction as the path tracer offsets its rays) never meets that triangle again, and
    /// the queries told which triangle it leaves give the very hits and answers of those not
    /// told: skipping its undecided lane drops nothing. Half the rays leave the walls of a
    /// closed box around the triangles from next to an edge, most of them a corner, where
    /// the adjacent wall's lane is undecided too and must still be decided: skipping every
    /// undecided lane lets some of those rays through the adjacent wall.
    #[test]
    fn rays_leaving_a_triangle_find_what_they_would_otherwise() {
        use crate::geometry::offset::{interpolate_with_error, offset_origin};
        use crate::geometry::warp::{square_to_uniform_sphere, square_to_uniform_triangle};
        let mut s = Sampler::new(9, 0, 0);
        let mut point = |scale: f32| random_point(&mut s, scale);
        let mut tris = random_triangles(&mut point);
        let walls = tris.len();
        for axis in 0..3 {
            for side in [-12.0, 12.0] {
                let corner = |a: f32, b: f32| {
                    let mut c = [0.0; 3];
                    c[axis] = side;
                    c[(axis + 1) % 3] = a;
                    c[(axis + 2) % 3] = b;
                    Vec3A::from_array(c)
                };
                let (p, q, r, t) = (
                    corner(-12.0, -12.0),
                    corner(12.0, -12.0),
                    corner(12.0, 12.0),
                    corner(-12.0, 12.0),
                );
                tris.push(Triangle {
                    v0: p,
                    v1: q,
                    v2: r,
                });
                tris.push(Triangle {
                    v0: p,
                    v1: r,
                    v2: t,
                });
            }
        }
        let accel = accel_over(&tris, true);
        let mut s = Sampler::new(10, 0, 0);
        let (mut hits, mut occluded) = (0, 0);
        for k in 0..20_000 {
            let i = if k % 2 == 0 {
                walls + ((s.next_1d() * 12.0) as usize).min(11)
            } else {
                ((s.next_1d() * walls as f32) as usize).min(walls - 1)
            };
            let t = &tris[i];
            // A wall's rays start within a ten-thousandth of one of its triangle's edges, two
            // in three of them a corner of the box.
            let bary = if i >= walls {
                let (e, eps, v) = (
                    (s.next_1d() * 3.0) as usize % 3,
                    1e-4 * s.next_1d(),
                    s.next_1d(),
                );
                let mut bary = [0.0; 3];
                bary[e] = eps;
                bary[(e + 1) % 3] = (1.0 - eps) * v;
                bary[(e + 2) % 3] = (1.0 - eps) * (1.0 - v);
                bary
            } else {
                let b = square_to_uniform_triangle(s.next_2d());
                [1.0 - b.x - b.y, b.x, b.y]
            };
            let (p, err) = interpolate_with_error([t.v0, t.v1, t.v2], bary);
            let ng = (t.v1 - t.v0).cross(t.v2 - t.v0).normalize();
            let mut w = Vec3A::from(square_to_uniform_sphere(s.next_2d()));
            // From a wall, into the box.
            if i >= walls {
                let f = i - walls;
                let side = if (f / 2) % 2 == 0 { -1.0 } else { 1.0 };
                if w[f / 4] * side > 0.0 {
                    w = -w;
                }
            }
            let o = Vec3::from(offset_origin(p, err, ng, w));
            let w = Vec3::from(w).normalize();
            let leaving = Some((0, i as u32));
            let plain = accel.closest_hit(o, w, 0.0, f32::INFINITY);
            assert!(
                plain.is_none_or(|h| h.triangle as usize != i),
                "ray {o} {w} met its own triangle"
            );
            // Along the unit direction as it is: the same hit, its distance within rounding
            // of the one along the direction normalised again; and the same bit for bit
            // whether or not the query knows the triangle the ray leaves.
            let unit = accel.closest_hit_unit(None, o, w, 0.0, f32::INFINITY);
            assert_eq!(
                unit.map(|h| (h.mesh, h.triangle)),
                plain.map(|h| (h.mesh, h.triangle)),
                "ray {o} {w}"
            );
            if let (Some(u), Some(p)) = (unit, plain) {
                // Each test's distance is exact to a few ulps of the coordinates it works on
                // (the vertices less the origin: pbrt-v4 §6.8.4), not of the distance itself.
                let scale = o.abs().max_element().max(p.t);
                assert!(
                    (u.t - p.t).abs() <= 8.0 * f32::EPSILON * scale,
                    "ray {o} {w}: {} against {}",
                    u.t,
                    p.t
                );
            }
            assert_eq!(
                accel.closest_hit_unit(leaving, o, w, 0.0, f32::INFINITY),
                unit
            );
            let blocked = accel.occluded(o, w, 0.0, 3.0);
            assert_eq!(accel.occluded_leaving(leaving, o, w, 0.0, 3.0), blocked);
            hits += usize::from(plain.is_some());
            occluded += usize::from(blocked);
        }
        assert!(
            hits > 2000 && occluded > 1000,
            "{hits} hits, {occluded} occluded: the test must exercise both"
        );
    }

    /// A ray from an origin that is not finite meets nothing, even pointed straight at the
    /// triangles (and a finite one from nearby does, so the rays are aimed right).
    #[test]
    fn rays_from_non_finite_origins_meet_nothing() {
        let mut s = Sampler::new(3, 0, 0);
        let mut point = |scale: f32| random_point(&mut s, scale);
        let tris = random_triangles(&mut point);
        let accel = accel_over(&tris, true);
        let target = Vec3::from((tris[0].v0 + tris[0].v1 + tris[0].v2) / 3.0);
        let from = Vec3::new(0.0, 0.0, -20.0);
        assert!(accel
            .closest_hit(from, target - from, 0.0, f32::INFINITY)
            .is_some());
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            for axis in 0..3 {
                let mut o = from;
                o[axis] = bad;
                let d = target - from;
                assert_eq!(
                    accel.closest_hit(o, d, 0.0, f32::INFINITY),
                    None,
                    "origin {o}"
                );
                assert!(!accel.occluded(o, d, 0.0, f32::INFINITY), "origin {o}");
            }
        }
    }

    /// A set of segments traversing together finds each segment's own occlusion, bit for bit
    /// as one segment at a time: sets of one to eight, from one origin (shadow rays towards
    /// a patch) or from scattered ones, with far limits short and unbounded, and a few
    /// zero-length segments (never occluded), through random triangles.
    #[test]
    fn occlusion_of_a_set_is_each_segments_own() {
        let mut s = Sampler::new(9, 0, 0);
        let mut point = |scale: f32| random_point(&mut s, scale);
        let tris = random_triangles(&mut point);
        for avx in [false, true] {
            let accel = accel_over(&tris, avx);
            let (mut occluded, mut clear) = (0, 0);
            for round in 0..3000 {
                let shared = Vec3::from(point(12.0));
                let target = Vec3::from(point(12.0));
                let segments: Vec<Segment> = (0..1 + round % OCCLUSION_SET)
                    .map(|i| {
                        let origin = if round % 3 == 0 {
                            Vec3::from(point(12.0))
                        } else {
                            shared
                        };
                        let end = target + Vec3::from(point(2.0));
                        let dir = if (round + i) % 17 == 0 {
                            Vec3::ZERO
                        } else {
                            end - origin
                        };
                        let tmax = [1.0 - 1e-4, f32::INFINITY, 0.5][(round + i) % 3];
                        Segment {
                            origin,
                            dir,
                            tmin: 0.0,
                            tmax,
                        }
                    })
                    .collect();
                let set = accel.occluded_set(&segments);
                for (i, g) in segments.iter().enumerate() {
                    let alone = accel.occluded(g.origin, g.dir, g.tmin, g.tmax);
                    assert_eq!(set >> i & 1 == 1, alone, "round {round} segment {i}");
                    occluded += usize::from(alone);
                    clear += usize::from(!alone);
                }
                assert_eq!(set >> segments.len(), 0, "round {round}: bits past the set");
            }
            assert!(
                occluded > 2000 && clear > 2000,
                "{occluded} occluded, {clear} clear: the test must see both"
            );
        }
    }

    /// Axis-aligned rays lying exactly in the plane of a box face (a zero direction component
    /// and an origin on the slab's plane: 0 × ∞ in the slab test) are not culled: a grid of
    /// unit squares in z = 0 and z = 1 and a wall at x = 20 spanning y in [0, 8] and z in
    /// [0, 1], and rays along x in the planes y = k and z = 0 or 1, which are the planes of
    /// the wall's own box faces.
    #[test]
    fn rays_in_a_box_face_plane_are_not_culled() {
        let mut tris = Vec::new();
        for j in 0..8 {
            for i in 0..8 {
                for z in [0.0, 1.0] {
                    let p = |x: f32, y: f32| Vec3A::new(i as f32 + x, j as f32 + y, z);
                    tris.push(Triangle {
                        v0: p(0.0, 0.0),
                        v1: p(1.0, 0.0),
                        v2: p(1.0, 1.0),
                    });
                    tris.push(Triangle {
                        v0: p(0.0, 0.0),
                        v1: p(1.0, 1.0),
                        v2: p(0.0, 1.0),
                    });
                }
            }
        }
        let w = |y: f32, z: f32| Vec3A::new(20.0, y, z);
        tris.push(Triangle {
            v0: w(0.0, 0.0),
            v1: w(8.0, 0.0),
            v2: w(8.0, 1.0),
        });
        tris.push(Triangle {
            v0: w(0.0, 0.0),
            v1: w(8.0, 1.0),
            v2: w(0.0, 1.0),
        });
        let wall = tris.len() - 2..tris.len();
        for avx in [false, true] {
            let accel = accel_over(&tris, avx);
            let mut hits = 0;
            for j in 0..=8 {
                for z in [0.0, 1.0, 0.5] {
                    for dir in [
                        Vec3::X,
                        Vec3::new(1.0, -0.0, 0.0),
                        Vec3::new(1.0, 0.0, -0.0),
                    ] {
                        let o = Vec3::new(-5.0, j as f32, z);
                        let hit = accel.closest_hit(o, dir, 0.0, f32::INFINITY);
                        let expected = brute_force(&tris, o, dir, f32::INFINITY);
                        assert_eq!(hit.map(|h| h.t), expected.map(|e| e.1), "ray from {o}");
                        assert_eq!(
                            accel.occluded(o, dir, 0.0, f32::INFINITY),
                            expected.is_some()
                        );
                        if let Some(h) = hit {
                            assert!(wall.contains(&(h.triangle as usize)), "ray from {o}: {h:?}");
                            hits += 1;
                        }
                    }
                }
            }
            // Every ray meets the wall, those along its edges too: the watertight test counts a
            // point on an edge (edge function exactly 0) as inside.
            assert_eq!(hits, 81, "{hits} of 81 rays hit the wall");
        }
    }
}

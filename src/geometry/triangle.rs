//! Watertight ray–triangle intersection (Woop, Benthin & Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2013).
//!
//! The ray is sheared so it runs along +z from the origin; the three 2D edge functions are then
//! computed from the same sheared vertex coordinates for every triangle that shares an edge, so a
//! ray through a shared edge or vertex can never slip between two triangles (obvhs's own
//! Möller–Trumbore test can). Edge functions that round to exactly zero are recomputed in double
//! precision, as the paper prescribes. Both faces are hit (no culling).

use super::offset::gamma;
use glam::{Vec3A, Vec4};

/// Per-ray constants of the shear transform.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WatertightRay {
    /// The ray's origin.
    pub origin: Vec3A,
    dir: Vec3A,
    kx: usize,
    ky: usize,
    kz: usize,
    /// The origin's coordinates along `kx`, `ky` and `kz`.
    o: [f32; 3],
    sx: f32,
    sy: f32,
    sz: f32,
}

/// Where a ray met a triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TriangleHit {
    /// Distance along the ray (in units of its direction's length).
    pub t: f32,
    /// Barycentric weights of the three vertices, summing to 1.
    pub b: [f32; 3],
}

/// What [`WatertightRay::intersect4`] found in a packet of four triangles.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hits4 {
    /// Bit `i` set where lane `i` is hit, at distance `t[i]` with barycentrics `b[·][i]`.
    pub hit: u32,
    /// Bit `i` set where lane `i` must be decided by [`WatertightRay::intersect`].
    pub undecided: u32,
    /// Per lane, the hit distance (meaningful where `hit` is set).
    pub t: Vec4,
    /// Per vertex and lane, the barycentric weight.
    pub b: [Vec4; 3],
}

impl Hits4 {
    const NONE: Hits4 = Hits4 {
        hit: 0,
        undecided: 0,
        t: Vec4::ZERO,
        b: [Vec4::ZERO; 3],
    };

    /// Lane `lane`'s hit.
    #[inline]
    pub fn lane(&self, lane: usize) -> TriangleHit {
        // Through arrays: glam's `Vec4` indexing is a `match`, a jump table.
        TriangleHit {
            t: self.t.as_ref()[lane],
            b: [
                self.b[0].as_ref()[lane],
                self.b[1].as_ref()[lane],
                self.b[2].as_ref()[lane],
            ],
        }
    }
}

impl WatertightRay {
    /// The constants of the ray from `origin` along `dir`.
    pub fn new(origin: Vec3A, dir: Vec3A) -> Self {
        // The axis of the largest |component| (x where it exceeds both others, else y where
        // it exceeds z, else z) and the swap that keeps the winding (so the sign of the
        // determinant still tells the face), chosen without branches: both are as random as
        // the ray. Arrays rather than glam's indexing, which is a `match`.
        let a = dir.abs();
        let x_over_y = usize::from(a.x > a.y);
        let kz = x_over_y * (2 - 2 * usize::from(a.x > a.z))
            + (1 - x_over_y) * (2 - usize::from(a.y > a.z));
        let d = dir.to_array();
        let o = origin.to_array();
        let swap = 0usize.wrapping_sub(usize::from(d[kz] < 0.0));
        let (next, after) = ((kz + 1) % 3, (kz + 2) % 3);
        let kx = next ^ (swap & (next ^ after));
        let ky = after ^ (swap & (next ^ after));
        WatertightRay {
            origin,
            dir,
            kx,
            ky,
            kz,
            o: [o[kx], o[ky], o[kz]],
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            sz: 1.0 / d[kz],
        }
    }

    /// Intersect the triangle `(p0, p1, p2)` within the open interval `(tmin, tmax)`.
    #[inline]
    pub fn intersect(
        &self,
        p0: Vec3A,
        p1: Vec3A,
        p2: Vec3A,
        tmin: f32,
        tmax: f32,
    ) -> Option<TriangleHit> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let a = (p0 - self.origin).to_array();
        let b = (p1 - self.origin).to_array();
        let c = (p2 - self.origin).to_array();
        let ax = a[kx] - self.sx * a[kz];
        let ay = a[ky] - self.sy * a[kz];
        let bx = b[kx] - self.sx * b[kz];
        let by = b[ky] - self.sy * b[kz];
        let cx = c[kx] - self.sx * c[kz];
        let cy = c[ky] - self.sy * c[kz];
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let f =
                |p: f32, q: f32, r: f32, s: f32| (p as f64 * q as f64 - r as f64 * s as f64) as f32;
            u = f(cx, by, cy, bx);
            v = f(ax, cy, ay, cx);
            w = f(bx, ay, by, ax);
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let az = self.sz * a[kz];
        let bz = self.sz * b[kz];
        let cz = self.sz * c[kz];
        let t_scaled = u * az + v * bz + w * cz;
        // Reject hits beyond tmax without dividing (the common case in closest-hit traversal).
        let (ts, d) = if det < 0.0 {
            (-t_scaled, -det)
        } else {
            (t_scaled, det)
        };
        if !(ts < tmax * d) {
            return None;
        }
        let inv = 1.0 / det;
        let mut t = t_scaled * inv;
        // pbrt-v4 §6.8.6: t must be conservatively positive given the rounding of every step
        // above; together with `offset::offset_origin` this rules out self-intersection.
        let max_zt = az.abs().max(bz.abs()).max(cz.abs());
        let max_xt = ax.abs().max(bx.abs()).max(cx.abs());
        let max_yt = ay.abs().max(by.abs()).max(cy.abs());
        let delta_z = gamma(3) * max_zt;
        let delta_x = gamma(5) * (max_xt + max_zt);
        let delta_y = gamma(5) * (max_yt + max_zt);
        let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
        let max_e = u.abs().max(v.abs()).max(w.abs());
        let delta_t =
            3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv.abs();
        if !(t > delta_t) {
            if t <= -delta_t {
                // Certainly behind the origin (the common case: triangles behind the ray).
                return None;
            }
            // The bound grows with the triangle's extent as seen from the origin, so for a large
            // triangle it can exceed the distance to a genuine hit (a ray leaving a box's wall
            // near a corner towards the adjacent wall) and the ray would leak. Decide such
            // hits in double precision, where the same bound is 2²⁹ times tighter. The inside
            // test above stays in single precision, so watertightness is untouched.
            t = self.refined_t(p0, p1, p2)?;
        }
        if !(t > tmin && t < tmax) {
            return None;
        }
        Some(TriangleHit {
            t,
            b: [u * inv, v * inv, w * inv],
        })
    }

    /// [`intersect`](Self::intersect) on four triangles at once (`v[vertex][axis]`, one
    /// triangle per lane), within `(tmin, tmax)`. Lane by lane, the same operations in the same
    /// order as `intersect`, so a lane in [`Hits4::hit`] carries the distance and barycentrics
    /// `intersect` returns, bit for bit, and every lane in neither mask is one `intersect`
    /// rejects. The rare lanes whose edge functions need the double-precision retry, or whose
    /// distance is too close to the origin for the single-precision bound to decide, are left
    /// to `intersect` ([`Hits4::undecided`]).
    #[inline(always)]
    pub fn intersect4(&self, v: &[[Vec4; 3]; 3], tmin: f32, tmax: f32) -> Hits4 {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let (ox, oy, oz) = (
            Vec4::splat(self.o[0]),
            Vec4::splat(self.o[1]),
            Vec4::splat(self.o[2]),
        );
        let (sx, sy, sz) = (
            Vec4::splat(self.sx),
            Vec4::splat(self.sy),
            Vec4::splat(self.sz),
        );
        let shear = |p: &[Vec4; 3]| {
            let (x, y, z) = (p[kx] - ox, p[ky] - oy, p[kz] - oz);
            (x - sx * z, y - sy * z, sz * z)
        };
        let (ax, ay, az) = shear(&v[0]);
        let (bx, by, bz) = shear(&v[1]);
        let (cx, cy, cz) = shear(&v[2]);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let zero = Vec4::ZERO;
        let retry = u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero);
        let outside = (u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero))
            & (u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero));
        let det = u + v + w;
        let t_scaled = u * az + v * bz + w * cz;
        let negative = det.cmplt(zero);
        let ts = Vec4::select(negative, -t_scaled, t_scaled);
        let d = Vec4::select(negative, -det, det);
        let near = ts.cmplt(Vec4::splat(tmax) * d);
        let plausible = !outside & det.cmpne(zero) & near;
        if (retry | plausible).bitmask() == 0 {
            // The common case: all four missed.
            return Hits4::NONE;
        }
        let inv = Vec4::ONE / det;
        let t = t_scaled * inv;
        let max3 = |a: Vec4, b: Vec4, c: Vec4| a.abs().max(b.abs()).max(c.abs());
        let max_zt = max3(az, bz, cz);
        let max_xt = max3(ax, bx, cx);
        let max_yt = max3(ay, by, cy);
        let delta_z = Vec4::splat(gamma(3)) * max_zt;
        let delta_x = Vec4::splat(gamma(5)) * (max_xt + max_zt);
        let delta_y = Vec4::splat(gamma(5)) * (max_yt + max_zt);
        let delta_e = Vec4::splat(2.0)
            * (Vec4::splat(gamma(2)) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
        let max_e = max3(u, v, w);
        let delta_t = Vec4::splat(3.0)
            * (Vec4::splat(gamma(3)) * max_e * max_zt + delta_e * max_zt + delta_z * max_e)
            * inv.abs();
        let certain = t.cmpgt(delta_t);
        let behind = t.cmple(-delta_t);
        let within = t.cmpgt(Vec4::splat(tmin)) & t.cmplt(Vec4::splat(tmax));
        Hits4 {
            hit: (plausible & !retry & certain & within).bitmask(),
            undecided: (retry | (plausible & !certain & !behind)).bitmask(),
            t,
            b: [u * inv, v * inv, w * inv],
        }
    }

    /// The hit distance to the plane of `(p0, p1, p2)` computed in double precision, or `None`
    /// when it is not conservatively positive (pbrt-v4's bound with f64 rounding). The f32
    /// vertices and origin convert exactly, so only the f64 operations contribute error.
    #[cold]
    fn refined_t(&self, p0: Vec3A, p1: Vec3A, p2: Vec3A) -> Option<f32> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let o = self.origin.as_dvec3();
        let dir = self.dir.as_dvec3();
        let (sx, sy, sz) = (dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]);
        let shear = |p: Vec3A| {
            let a = p.as_dvec3() - o;
            (a[kx] - sx * a[kz], a[ky] - sy * a[kz], sz * a[kz])
        };
        let (ax, ay, az) = shear(p0);
        let (bx, by, bz) = shear(p1);
        let (cx, cy, cz) = shear(p2);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t = (u * az + v * bz + w * cz) / det;
        let g = |n: f64| {
            let e = f64::EPSILON * 0.5;
            n * e / (1.0 - n * e)
        };
        // As in `intersect`, with one more rounding in each sheared coordinate (the shear
        // constants are computed here rather than given).
        let max_zt = az.abs().max(bz.abs()).max(cz.abs());
        let max_xt = ax.abs().max(bx.abs()).max(cx.abs());
        let max_yt = ay.abs().max(by.abs()).max(cy.abs());
        let delta_z = g(4.0) * max_zt;
        let delta_x = g(6.0) * (max_xt + max_zt);
        let delta_y = g(6.0) * (max_yt + max_zt);
        let delta_e = 2.0 * (g(2.0) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
        let max_e = u.abs().max(v.abs()).max(w.abs());
        let delta_t =
            3.0 * (g(3.0) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) / det.abs();
        let t32 = t as f32;
        (t > delta_t && t32 > 0.0).then_some(t32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3a;

    #[test]
    fn hits_inside_misses_outside() {
        let (p0, p1, p2) = (vec3a(0., 0., 0.), vec3a(1., 0., 0.), vec3a(0., 1., 0.));
        let r = WatertightRay::new(vec3a(0.25, 0.25, 1.0), vec3a(0., 0., -1.));
        let h = r.intersect(p0, p1, p2, 0.0, f32::INFINITY).unwrap();
        assert_eq!(h.t, 1.0);
        assert!((h.b[0] - 0.5).abs() < 1e-6 && (h.b[1] - 0.25).abs() < 1e-6);
        let r = WatertightRay::new(vec3a(0.75, 0.75, 1.0), vec3a(0., 0., -1.));
        assert!(r.intersect(p0, p1, p2, 0.0, f32::INFINITY).is_none());
        // From behind too, and respecting tmax.
        let r = WatertightRay::new(vec3a(0.25, 0.25, -1.0), vec3a(0., 0., 1.));
        assert!(r.intersect(p0, p1, p2, 0.0, 2.0).is_some());
        assert!(r.intersect(p0, p1, p2, 0.0, 0.5).is_none());
    }

    /// `intersect4` agrees with `intersect` lane by lane, bit for bit: every lane it reports
    /// hit carries `intersect`'s distance and barycentrics, every lane it leaves out
    /// `intersect` misses. The triangles share vertices with their neighbours and lie on
    /// the rays' origins or along their axes often enough to reach the undecided lanes
    /// (zero edge functions, distances within the rounding bound).
    #[test]
    fn four_at_once_agree_with_one_at_a_time() {
        let mut s = crate::sampler::Sampler::new(3, 0, 0);
        let mut point = |grid: bool| {
            let (a, b) = (s.next_2d(), s.next_1d());
            let p = vec3a(a.x, a.y, b) * 4.0 - 2.0;
            if grid {
                p.round()
            } else {
                p
            }
        };
        let (mut hits, mut undecided, mut lanes) = (0, 0, 0);
        for round in 0..20_000 {
            let grid = round % 3 == 0;
            let origin = point(grid);
            let mut dir = point(grid);
            if dir == Vec3A::ZERO {
                dir = Vec3A::X;
            }
            let ray = WatertightRay::new(origin, dir);
            let shared = point(grid);
            // Lane 0 sometimes starts at the origin (a ray leaving its own surface).
            let tris: [[Vec3A; 3]; 4] = std::array::from_fn(|lane| {
                let first = if lane == 0 && round % 5 == 0 {
                    origin
                } else {
                    shared
                };
                [first, point(grid), point(grid)]
            });
            let mut v = [[Vec4::ZERO; 3]; 3];
            for (lane, t) in tris.iter().enumerate() {
                for vertex in 0..3 {
                    for axis in 0..3 {
                        v[vertex][axis][lane] = t[vertex][axis];
                    }
                }
            }
            let tmax = if round % 2 == 0 { f32::INFINITY } else { 2.5 };
            let four = ray.intersect4(&v, 0.0, tmax);
            assert_eq!(four.hit & four.undecided, 0);
            for (lane, [p0, p1, p2]) in tris.into_iter().enumerate() {
                let one = ray.intersect(p0, p1, p2, 0.0, tmax);
                let bit = 1 << lane;
                lanes += 1;
                if four.hit & bit != 0 {
                    let h = four.lane(lane);
                    assert_eq!(Some(h), one, "round {round} lane {lane}");
                    assert_eq!(h.t.to_bits(), one.map_or(0, |o| o.t.to_bits()));
                    hits += 1;
                } else if four.undecided & bit != 0 {
                    undecided += 1;
                } else {
                    assert_eq!(one, None, "round {round} lane {lane}");
                }
            }
        }
        // The test must reach all three outcomes.
        assert!(hits > 1000, "{hits} hits of {lanes}");
        assert!(undecided > 100, "{undecided} undecided of {lanes}");
    }
}

//! The surfel of a given mesh nearest a point: one implicit k-d tree per mesh.
//!
//! A ray that leaves a receiver and hits a mesh takes the cache's light from the surfel of
//! that mesh nearest the hit (the paths gather, the bake's buffer gaps, the render's traced
//! pixels). The senders' bounding sphere tree answered this by branch and bound over every
//! mesh's surfels, one surfel per leaf: 39 % of a 512² paths render of cbox-mirror. Here each
//! mesh's surfels are a k-d tree of their own, stored implicitly (the median of a range at its
//! middle, split along the range's widest axis; ranges of `LEAF` or fewer are scanned), so a
//! query visits only the hit mesh's surfels and reads them in order from one array.
//!
//! Each entry of that array holds what a query reads of a surfel: its position, its normal
//! (the query's filter), its index and its split axis, 32 bytes, two to a cache line. The
//! filter read the normal from the cache's surfels at first, a miss per candidate: 14 % of
//! the search's time sat on that one load.
//!
//! The answer does not depend on the tree: of the accepted surfels at the least squared
//! distance, the lowest index wins.

use glam::Vec3;

/// Ranges of at most this many surfels are scanned rather than split.
const LEAF: usize = 8;

/// One surfel as the search reads it.
#[derive(Clone, Copy, Debug)]
struct Entry {
    /// Its position.
    p: Vec3,
    /// Its normal, which the query's filter reads.
    n: Vec3,
    /// Its index among the cache's surfels.
    surfel: u32,
    /// The split axis of the range whose median it is (ranges of more than [`LEAF`] surfels
    /// only).
    axis: u32,
}

/// Per mesh, an implicit k-d tree over its surfels' positions (see the module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct NearestSurfel {
    /// The surfels, grouped by mesh, each group in k-d tree order.
    entries: Vec<Entry>,
    /// Per mesh, its group's range in `entries`.
    meshes: Vec<(u32, u32)>,
}

impl NearestSurfel {
    /// The trees of surfels at `positions` with normals `normals` on meshes `mesh_of` (one
    /// entry per surfel each).
    pub fn new(positions: &[Vec3], normals: &[Vec3], mesh_of: &[u32]) -> Self {
        let mesh_count = mesh_of.iter().map(|&m| m as usize + 1).max().unwrap_or(0);
        let mut counts = vec![0u32; mesh_count + 1];
        for &m in mesh_of {
            counts[m as usize + 1] += 1;
        }
        for m in 0..mesh_count {
            counts[m + 1] += counts[m];
        }
        let meshes: Vec<(u32, u32)> = (0..mesh_count)
            .map(|m| (counts[m], counts[m + 1]))
            .collect();
        // Group by mesh, each group in index order (a counting sort).
        let mut order = vec![0u32; mesh_of.len()];
        let mut next = counts;
        for (i, &m) in mesh_of.iter().enumerate() {
            order[next[m as usize] as usize] = i as u32;
            next[m as usize] += 1;
        }
        let mut axis = vec![0u32; order.len()];
        for &(lo, hi) in &meshes {
            build(positions, &mut order, &mut axis, lo as usize, hi as usize);
        }
        let entries = order
            .iter()
            .zip(axis)
            .map(|(&i, axis)| Entry {
                p: positions[i as usize],
                n: normals[i as usize],
                surfel: i,
                axis,
            })
            .collect();
        NearestSurfel { entries, meshes }
    }

    /// The surfel of mesh `mesh` nearest `q` among those whose normal `accept` takes, the
    /// lowest index among equally near ones; `None` where the mesh has none. `seed`, a
    /// surfel of mesh `mesh`, its position and its normal (the answer for a nearby query,
    /// say), bounds the search from the start; the answer is the same without it.
    pub fn nearest(
        &self,
        q: Vec3,
        mesh: u32,
        accept: impl Fn(Vec3) -> bool,
        seed: Option<(u32, Vec3, Vec3)>,
    ) -> Option<u32> {
        let &(lo, hi) = self.meshes.get(mesh as usize)?;
        let mut best = Best {
            d2: f32::INFINITY,
            surfel: u32::MAX,
        };
        if let Some((surfel, p, n)) = seed {
            best.offer(p.distance_squared(q), surfel, || accept(n));
        }
        self.search(q, lo as usize, hi as usize, &accept, &mut best);
        (best.surfel != u32::MAX).then_some(best.surfel)
    }

    fn search(
        &self,
        q: Vec3,
        lo: usize,
        hi: usize,
        accept: &impl Fn(Vec3) -> bool,
        best: &mut Best,
    ) {
        if hi - lo <= LEAF {
            for e in &self.entries[lo..hi] {
                best.offer(e.p.distance_squared(q), e.surfel, || accept(e.n));
            }
            return;
        }
        let mid = lo + (hi - lo) / 2;
        let median = &self.entries[mid];
        let axis = median.axis as usize;
        let d = q[axis] - median.p[axis];
        let (near, far) = if d < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(q, near.0, near.1, accept, best);
        best.offer(median.p.distance_squared(q), median.surfel, || {
            accept(median.n)
        });
        // Ties included: an equally near surfel of lower index may lie across the plane.
        if d * d <= best.d2 {
            self.search(q, far.0, far.1, accept, best);
        }
    }
}

/// Order `order[lo..hi]` as a k-d tree: its median along the widest axis at the middle, the
/// lower half before it and the upper after, each ordered the same way; the median's axis
/// into `axis`.
fn build(positions: &[Vec3], order: &mut [u32], axis_of: &mut [u32], lo: usize, hi: usize) {
    if hi - lo <= LEAF {
        return;
    }
    let range = &mut order[lo..hi];
    let (min, max) = range.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(a, b), &i| (a.min(positions[i as usize]), b.max(positions[i as usize])),
    );
    let extent = max - min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = (hi - lo) / 2;
    range.select_nth_unstable_by(mid, |&a, &b| {
        positions[a as usize][axis]
            .total_cmp(&positions[b as usize][axis])
            .then(a.cmp(&b))
    });
    axis_of[lo + mid] = axis as u32;
    build(positions, order, axis_of, lo, lo + mid);
    build(positions, order, axis_of, lo + mid + 1, hi);
}

/// The best candidate so far.
struct Best {
    d2: f32,
    surfel: u32,
}

impl Best {
    /// Take `surfel` at squared distance `d2` if it is nearer (or as near with a lower index)
    /// and `accepted` says so; the filter runs only for a candidate that would win.
    #[inline(always)]
    fn offer(&mut self, d2: f32, surfel: u32, accepted: impl FnOnce() -> bool) {
        if (d2, surfel) < (self.d2, self.surfel) && accepted() {
            self.d2 = d2;
            self.surfel = surfel;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::Sampler;

    /// Against a linear scan, on random clouds with duplicated points (ties) and a filter on
    /// the normals that rejects about a third of them.
    #[test]
    fn matches_a_linear_scan() {
        let mut rng = Sampler::new(7, 0, 0);
        let facing = Vec3::new(0.3, -0.2, 0.9).normalize();
        let accept = |n: Vec3| n.dot(facing) > -0.3;
        for n in [0usize, 1, 5, 9, 100, 3000] {
            let mut positions: Vec<Vec3> = (0..n)
                .map(|_| Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d() * 0.01))
                .collect();
            let normals: Vec<Vec3> = (0..n)
                .map(|_| {
                    (Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d()) * 2.0 - 1.0)
                        .normalize_or(Vec3::Z)
                })
                .collect();
            // Exact duplicates, to exercise the tie rule.
            for i in (0..n).step_by(7) {
                positions[i] = positions[i / 2];
            }
            let mesh_of: Vec<u32> = (0..n).map(|i| (i % 3) as u32).collect();
            let index = NearestSurfel::new(&positions, &normals, &mesh_of);
            let rejected = (0..n).filter(|&i| !accept(normals[i])).count();
            assert!(
                n < 100 || (rejected > n / 5 && rejected < n / 2),
                "{rejected} of {n}"
            );
            for k in 0..200 {
                let q = if k % 2 == 0 && n > 0 {
                    positions[k % n]
                } else {
                    Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d()) * 1.2 - 0.1
                };
                for mesh in 0..4u32 {
                    let scan = (0..n as u32)
                        .filter(|&i| mesh_of[i as usize] == mesh && accept(normals[i as usize]))
                        .min_by(|&a, &b| {
                            let (da, db) = (
                                positions[a as usize].distance_squared(q),
                                positions[b as usize].distance_squared(q),
                            );
                            da.total_cmp(&db).then(a.cmp(&b))
                        });
                    assert_eq!(
                        index.nearest(q, mesh, accept, None),
                        scan,
                        "n {n} query {k} mesh {mesh}"
                    );
                    // Seeded with any surfel of the mesh, accepted or not: the same answer.
                    if let Some(seed) = (0..n as u32).find(|&i| mesh_of[i as usize] == mesh) {
                        let s = seed as usize;
                        let seeded =
                            index.nearest(q, mesh, accept, Some((seed, positions[s], normals[s])));
                        assert_eq!(seeded, scan, "seeded: n {n} query {k} mesh {mesh}");
                    }
                }
            }
        }
    }
}

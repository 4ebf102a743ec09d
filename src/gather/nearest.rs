//! The surfel of a given mesh nearest a point: one implicit k-d tree per mesh.
//!
//! A ray that leaves a receiver and hits a mesh takes the cache's light from the surfel of
//! that mesh nearest the hit (the paths gather, the bake's buffer gaps). The senders' bounding
//! sphere tree answered this by branch and bound over every mesh's surfels, one surfel per
//! leaf: 39 % of a 512² paths render of cbox-mirror. Here each mesh's surfels are a k-d tree
//! of their own, stored implicitly (the median of a range at its middle, split along the
//! range's widest axis; ranges of `LEAF` or fewer are scanned), so a query visits only the
//! hit mesh's surfels and reads them in order from one array.
//!
//! The answer does not depend on the tree: of the accepted surfels at the least squared
//! distance, the lowest index wins.

use glam::Vec3;

/// Ranges of at most this many surfels are scanned rather than split.
const LEAF: usize = 8;

/// Per mesh, an implicit k-d tree over its surfels' positions (see the module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct NearestSurfel {
    /// Surfel indices, grouped by mesh, each group in k-d tree order.
    order: Vec<u32>,
    /// The positions of `order`'s surfels, in the same order.
    points: Vec<Vec3>,
    /// The split axis of the range whose median sits at each position (ranges of more than
    /// [`LEAF`] surfels only).
    axis: Vec<u8>,
    /// Per mesh, its group's range in `order`.
    meshes: Vec<(u32, u32)>,
}

impl NearestSurfel {
    /// The trees of surfels at `positions` on meshes `mesh_of` (one entry per surfel each).
    pub fn new(positions: &[Vec3], mesh_of: &[u32]) -> Self {
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
        let mut index = NearestSurfel {
            points: Vec::new(),
            axis: vec![0; order.len()],
            order,
            meshes,
        };
        for &(lo, hi) in &index.meshes.clone() {
            index.build(positions, lo as usize, hi as usize);
        }
        index.points = index.order.iter().map(|&i| positions[i as usize]).collect();
        index
    }

    /// Order `order[lo..hi]` as a k-d tree: its median along the widest axis at the middle,
    /// the lower half before it and the upper after, each ordered the same way.
    fn build(&mut self, positions: &[Vec3], lo: usize, hi: usize) {
        if hi - lo <= LEAF {
            return;
        }
        let range = &mut self.order[lo..hi];
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
        self.axis[lo + mid] = axis as u8;
        self.build(positions, lo, lo + mid);
        self.build(positions, lo + mid + 1, hi);
    }

    /// The surfel of mesh `mesh` nearest `q` among those `accept` takes (by surfel index),
    /// the lowest index among equally near ones; `None` where the mesh has none. `seed`, a
    /// surfel of mesh `mesh` and its position (the answer for a nearby query, say), bounds
    /// the search from the start; the answer is the same without it.
    pub fn nearest(
        &self,
        q: Vec3,
        mesh: u32,
        accept: impl Fn(u32) -> bool,
        seed: Option<(u32, Vec3)>,
    ) -> Option<u32> {
        let &(lo, hi) = self.meshes.get(mesh as usize)?;
        let mut best = Best {
            d2: f32::INFINITY,
            surfel: u32::MAX,
        };
        if let Some((surfel, p)) = seed {
            best.offer(p.distance_squared(q), surfel, &accept);
        }
        self.search(q, lo as usize, hi as usize, &accept, &mut best);
        (best.surfel != u32::MAX).then_some(best.surfel)
    }

    fn search(
        &self,
        q: Vec3,
        lo: usize,
        hi: usize,
        accept: &impl Fn(u32) -> bool,
        best: &mut Best,
    ) {
        if hi - lo <= LEAF {
            for k in lo..hi {
                best.offer(self.points[k].distance_squared(q), self.order[k], accept);
            }
            return;
        }
        let mid = lo + (hi - lo) / 2;
        let axis = self.axis[mid] as usize;
        let d = q[axis] - self.points[mid][axis];
        let (near, far) = if d < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(q, near.0, near.1, accept, best);
        best.offer(
            self.points[mid].distance_squared(q),
            self.order[mid],
            accept,
        );
        // Ties included: an equally near surfel of lower index may lie across the plane.
        if d * d <= best.d2 {
            self.search(q, far.0, far.1, accept, best);
        }
    }
}

/// The best candidate so far.
struct Best {
    d2: f32,
    surfel: u32,
}

impl Best {
    fn offer(&mut self, d2: f32, surfel: u32, accept: &impl Fn(u32) -> bool) {
        if (d2, surfel) < (self.d2, self.surfel) && accept(surfel) {
            self.d2 = d2;
            self.surfel = surfel;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::Sampler;

    /// Against a linear scan, on random clouds with duplicated points (ties) and a filter.
    #[test]
    fn matches_a_linear_scan() {
        let mut rng = Sampler::new(7, 0, 0);
        for n in [0usize, 1, 5, 9, 100, 3000] {
            let mut positions: Vec<Vec3> = (0..n)
                .map(|_| Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d() * 0.01))
                .collect();
            // Exact duplicates, to exercise the tie rule.
            for i in (0..n).step_by(7) {
                positions[i] = positions[i / 2];
            }
            let mesh_of: Vec<u32> = (0..n).map(|i| (i % 3) as u32).collect();
            let index = NearestSurfel::new(&positions, &mesh_of);
            let accept = |i: u32| !i.is_multiple_of(5);
            for k in 0..200 {
                let q = if k % 2 == 0 && n > 0 {
                    positions[k % n]
                } else {
                    Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d()) * 1.2 - 0.1
                };
                for mesh in 0..4u32 {
                    let scan = (0..n as u32)
                        .filter(|&i| mesh_of[i as usize] == mesh && accept(i))
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
                        let seeded =
                            index.nearest(q, mesh, accept, Some((seed, positions[seed as usize])));
                        assert_eq!(seeded, scan, "seeded: n {n} query {k} mesh {mesh}");
                    }
                }
            }
        }
    }
}

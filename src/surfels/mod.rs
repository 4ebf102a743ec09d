//! Poisson-disk surfels on every surface by weighted sample elimination (Yuksel, "Sample
//! Elimination for Generating Poisson Disk Sample Sets", Eurographics 2015), docs/design.md §5.1 and
//! docs/method.md §2.1.
//!
//! 1. Draw `CANDIDATES_PER_SURFEL × N` candidates uniformly by area (each from its own counter-
//!    based random stream, so the set does not depend on the thread count).
//! 2. Give each candidate the weight Σ (1 − d/2r_max)⁸ over its neighbours closer than 2r_max,
//!    with r_max = √(A / (2√3 N)), the radius of N discs in hexagonal packing over the area A.
//!    Then repeatedly remove the heaviest candidate (ties: the higher index) and lower its
//!    neighbours' weights, until N remain. This runs sequentially, so it is deterministic.
//! 3. Every candidate stands for A / (candidate count) of surface. Each surfel's area is the
//!    total of the candidates nearest to it: the local density decides the area (Voronoi by
//!    counting), and the areas sum to the total surface area.
//!
//! With per-mesh densities ([`sample_surfels_with_density`]), candidates are drawn by area
//! times density, a mesh of density w has discs of radius r_max/√w, and a candidate on it
//! stands for A_w / (count · w) of surface, A_w the density-weighted area.
//!
//! Neighbours count only when they face the same way (n·n' > 0). The two sides of a thin wall
//! then do not thin each other out, and the area of one side is never credited to the other.

pub mod coding;
pub mod radiance;
pub mod tree;

use crate::fast_hash::FastHashMap;
use crate::geometry::offset::interpolate_with_error;
use crate::geometry::warp::square_to_uniform_triangle;
use crate::sampler::Sampler;
use crate::scene::Scene;
use glam::{IVec3, Vec2, Vec3, Vec3A};
use rayon::prelude::*;

/// Candidates drawn per surfel kept (Yuksel's recommendation is 3–5).
pub(crate) const CANDIDATES_PER_SURFEL: usize = 5;

/// A surface sample (plain data, 44 bytes: a kept transport stores surfels as they are).
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Surfel {
    /// Its centre, on the surface.
    pub p: Vec3,
    /// Unit geometric normal (the front face of the triangle).
    pub n: Vec3,
    /// Area of surface this surfel stands for.
    pub area: f32,
    /// The mesh it lies on.
    pub mesh: u32,
    /// The triangle of that mesh.
    pub triangle: u32,
    /// Barycentric weights of the triangle's vertices 1 and 2 (vertex 0 has 1 − b.x − b.y).
    pub b: Vec2,
}

impl Surfel {
    /// Radius of the disc of the surfel's area.
    pub fn radius(&self) -> f32 {
        (self.area / std::f32::consts::PI).sqrt()
    }

    /// Its position on its triangle of `scene` and the bound on that position's rounding
    /// error, from which rays leave it (see [`crate::geometry::offset::offset_origin`]).
    pub(crate) fn position_with_error(&self, scene: &Scene) -> (Vec3A, Vec3A) {
        let v = scene.meshes[self.mesh as usize].corners(self.triangle);
        interpolate_with_error(v, [1.0 - self.b.x - self.b.y, self.b.x, self.b.y])
    }
}

/// `n` Poisson-disk surfels over every triangle of `scene` (fewer if the scene has fewer
/// candidates' worth of area: never more than requested).
pub fn sample_surfels(scene: &Scene, n: usize, seed: u64) -> Vec<Surfel> {
    sample_surfels_with_density(scene, n, seed, &[])
}

/// As [`sample_surfels`], with mesh `m` sampled at `density[m]` times the surfels per unit
/// area of a mesh of density 1 (meshes past the slice's end have density 1; a density must be
/// positive and finite). The discs of a mesh of density w have 1/√w times the radius.
pub fn sample_surfels_with_density(
    scene: &Scene,
    n: usize,
    seed: u64,
    density: &[f32],
) -> Vec<Surfel> {
    let density_of = |mesh: u32| f64::from(density.get(mesh as usize).copied().unwrap_or(1.0));
    let (cdf, tris) = area_table(scene, &density_of);
    let total = cdf.last().copied().unwrap_or(0.0);
    if n == 0 || !(total > 0.0) {
        return Vec::new();
    }
    let count = n * CANDIDATES_PER_SURFEL;
    // Candidates in an alpha cut-out's holes are dropped: the others still stand for the area
    // over which they were drawn, so the areas sum to the surface that is there.
    let mut candidates: Vec<Surfel> = (0..count as u64)
        .into_par_iter()
        .map(|i| candidate(scene, &cdf, &tris, total, seed, i))
        .filter(|c| !in_hole(scene, c))
        .collect();
    // Density 1's disc radius; a mesh of density w has r_max / √w.
    let r_max = (total / (2.0 * 3f64.sqrt() * n as f64)).sqrt();
    // Per mesh, looked up for every pair the elimination weighs.
    let radii: Vec<f32> = (0..scene.meshes.len() as u32)
        .map(|m| (r_max / density_of(m).sqrt()) as f32)
        .collect();
    let largest = candidates
        .iter()
        .map(|c| radii[c.mesh as usize])
        .fold(0.0f32, f32::max);
    let grid = Grid::new(&mut candidates, 2.0 * largest);
    let alive = eliminate(&candidates, &grid, &radii, n);
    // Every candidate stands for the area over which one was drawn: W / (count · w).
    let area_each = |mesh: u32| (total / (count as f64 * density_of(mesh))) as f32;
    assign_areas(&candidates, &grid, &alive, &area_each)
}

/// About the most memory (bytes) drawing `n` surfels holds at once: the candidates and their
/// grid cells, the elimination's weights, heap and liveness, and every candidate's weighted
/// neighbours ([`Neighbours`]), on a flat surface π (2 r_max)² times the candidates' density
/// 5N/A, that is 20π / (2√3) ≈ 18 each. About 1.1 kB a surfel.
pub(crate) fn sampling_memory(n: u64) -> u64 {
    let neighbours =
        (CANDIDATES_PER_SURFEL as f64 * 4.0 * std::f64::consts::PI / (2.0 * 3f64.sqrt())).ceil();
    let per_candidate = size_of::<Surfel>()
        + size_of::<u32>() // its cell
        + size_of::<f32>() + size_of::<u64>() + size_of::<u32>() + size_of::<bool>() // heap
        + size_of::<u32>() // where its neighbours end
        + neighbours as usize * size_of::<(u32, f32)>();
    n.saturating_mul((CANDIDATES_PER_SURFEL * per_candidate) as u64)
}

/// Whether candidate `c` lies in a hole of its material's alpha cut-out.
fn in_hole(scene: &Scene, c: &Surfel) -> bool {
    let m = &scene.meshes[c.mesh as usize];
    scene
        .materials
        .get(m.material)
        .and_then(|x| x.cutout)
        .is_some_and(|cutout| {
            let uv = m.uv_at(c.triangle, [1.0 - c.b.x - c.b.y, c.b.x, c.b.y]);
            !cutout.keeps(&scene.textures, uv)
        })
}

/// Cumulative triangle areas weighted by their mesh's density (f64) and the
/// `(mesh, triangle)` of each entry.
fn area_table(scene: &Scene, density: &dyn Fn(u32) -> f64) -> (Vec<f64>, Vec<(u32, u32)>) {
    let mut cdf = Vec::with_capacity(scene.triangle_count());
    let mut tris = Vec::with_capacity(scene.triangle_count());
    let mut acc = 0.0f64;
    for (mi, m) in scene.meshes.iter().enumerate() {
        let w = density(mi as u32);
        for (ti, t) in m.triangles.iter().enumerate() {
            let p = |k: u32| m.positions[k as usize].as_dvec3();
            let area = 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length() * w;
            if area > 0.0 {
                acc += area;
                cdf.push(acc);
                tris.push((mi as u32, ti as u32));
            }
        }
    }
    (cdf, tris)
}

fn candidate(
    scene: &Scene,
    cdf: &[f64],
    tris: &[(u32, u32)],
    total: f64,
    seed: u64,
    i: u64,
) -> Surfel {
    let mut s = Sampler::new(seed, i, 0);
    // Two uniforms for the triangle choice, for 48 bits of resolution over the area.
    let u = (s.next_1d() as f64 + s.next_1d() as f64 * 2f64.powi(-24)) * total;
    let k = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
    let (mesh, triangle) = tris[k];
    let m = &scene.meshes[mesh as usize];
    let t = m.triangles[triangle as usize];
    let v = t.map(|k| m.positions[k as usize]);
    let b = square_to_uniform_triangle(s.next_2d());
    Surfel {
        p: v[0] * (1.0 - b.x - b.y) + v[1] * b.x + v[2] * b.y,
        n: (v[1] - v[0]).cross(v[2] - v[0]).normalize(),
        area: 0.0,
        mesh,
        triangle,
        b,
    }
}

/// A uniform grid over the candidates, which it reorders so each cell is one contiguous slice
/// and neighbouring cells lie close in memory (Morton order of the cells): elimination
/// touches each candidate's neighbours thousands of times, and random order made it
/// memory-bound. Each cell's occupied neighbours (of the 3 × 3 × 3 around it) are listed once:
/// looking the 27 cells up in a hash map for every candidate removed was a quarter of the
/// sampling (300 000 surfels: 4.72 → 3.56 s; a million: 21.8 → 15.9 s; the same surfels).
struct Grid {
    /// Per candidate, its cell.
    cell_of: Vec<u32>,
    /// Per cell, its candidates.
    ranges: Vec<(u32, u32)>,
    /// Per cell, the occupied cells around it (itself included) in a fixed order:
    /// `around[around_start[c]..around_start[c + 1]]`.
    around: Vec<u32>,
    around_start: Vec<u32>,
}

/// Interleave the low 21 bits of three coordinates (a Morton code).
fn morton(k: IVec3) -> u64 {
    fn spread(v: i32) -> u64 {
        let mut x = (v as u32 as u64) & 0x1f_ffff;
        x = (x | x << 32) & 0x1f_0000_0000_ffff;
        x = (x | x << 16) & 0x1f_0000_ff00_00ff;
        x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
        x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
        (x | x << 2) & 0x1249_2492_4924_9249
    }
    spread(k.x) | spread(k.y) << 1 | spread(k.z) << 2
}

impl Grid {
    /// Sort `points` by cell (deterministically: ties keep their order) and index the cells.
    fn new(points: &mut [Surfel], cell: f32) -> Grid {
        let key = |p: Vec3| (p / cell).floor().as_ivec3();
        points.par_sort_by_cached_key(|s| {
            let k = key(s.p);
            (morton(k), k.x, k.y, k.z)
        });
        let mut index: FastHashMap<IVec3, u32> = FastHashMap::default();
        let mut keys = Vec::new();
        let mut ranges = Vec::new();
        let mut cell_of = vec![0u32; points.len()];
        let mut start = 0;
        for i in 1..=points.len() {
            let k = key(points[start].p);
            if i == points.len() || key(points[i].p) != k {
                let c = ranges.len() as u32;
                index.insert(k, c);
                keys.push(k);
                ranges.push((start as u32, i as u32));
                cell_of[start..i].fill(c);
                start = i;
            }
        }
        let lists: Vec<Vec<u32>> = keys
            .par_iter()
            .map(|&k| {
                let mut list = Vec::new();
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            if let Some(&c) = index.get(&(k + IVec3::new(dx, dy, dz))) {
                                list.push(c);
                            }
                        }
                    }
                }
                list
            })
            .collect();
        let mut around_start = Vec::with_capacity(lists.len() + 1);
        around_start.push(0);
        for list in &lists {
            around_start.push(around_start[around_start.len() - 1] + list.len() as u32);
        }
        Grid {
            cell_of,
            ranges,
            around: lists.concat(),
            around_start,
        }
    }

    /// Call `f` for every candidate in the 3 × 3 × 3 cells around candidate `i`'s (a superset
    /// of those within one cell size), in a fixed order.
    #[inline]
    fn for_each_around(&self, i: usize, mut f: impl FnMut(u32)) {
        let c = self.cell_of[i] as usize;
        let cells = &self.around[self.around_start[c] as usize..self.around_start[c + 1] as usize];
        for &n in cells {
            let (a, b) = self.ranges[n as usize];
            (a..b).for_each(&mut f);
        }
    }
}

/// Yuksel's weight of a neighbour at distance `d`, for candidates facing the same way, with
/// the larger of their two disc radii (symmetric, so that removing a candidate takes from
/// its neighbours exactly what it gave them).
#[inline]
fn weight(a: &Surfel, b: &Surfel, radii: &[f32]) -> f32 {
    let r_max = radii[a.mesh as usize].max(radii[b.mesh as usize]);
    let d = a.p.distance(b.p);
    if d < 2.0 * r_max && a.n.dot(b.n) > 0.0 {
        (1.0 - d / (2.0 * r_max)).powi(8)
    } else {
        0.0
    }
}

/// A max-heap over candidates by weight, ties to the higher index, whose weights can be
/// lowered in place (they only ever decrease here). Removal then follows a total order:
/// deterministic. Each entry holds its key, `(weight's order bits) << 32 | index`, so a
/// comparison is one integer compare without a look-up; the key is also where the weight is
/// kept ([`weight_of`]).
struct WeightHeap {
    heap: Vec<u64>,
    /// Per candidate still in the heap, where its entry is.
    pos: Vec<u32>,
}

/// Children per entry of [`WeightHeap`]: four keys share a cache line, and the heap is half
/// as deep as a binary one.
const ARITY: usize = 4;

/// The high half of a heap key: ordered as the weights are (by `<` and `==`, so ±0 are one
/// key).
fn weight_bits(w: f32) -> u64 {
    let bits = if w == 0.0 { 0 } else { w.to_bits() };
    u64::from(if bits >> 31 == 1 {
        !bits
    } else {
        bits | 1 << 31
    }) << 32
}

/// The weight of a heap key ([`weight_bits`]'s inverse; −0 comes back as +0, which lowers
/// to the same values).
fn weight_of(key: u64) -> f32 {
    let bits = (key >> 32) as u32;
    f32::from_bits(if bits >> 31 == 1 {
        bits & !(1 << 31)
    } else {
        !bits
    })
}

impl WeightHeap {
    fn new(w: &[f32]) -> Self {
        let heap: Vec<u64> = (0..w.len()).map(|i| weight_bits(w[i]) | i as u64).collect();
        let pos = (0..w.len() as u32).collect();
        let mut h = WeightHeap { heap, pos };
        for i in (0..h.heap.len().div_ceil(ARITY)).rev() {
            h.sift_down(i);
        }
        h
    }

    fn sift_down(&mut self, mut i: usize) {
        let entry = self.heap[i];
        let len = self.heap.len();
        loop {
            let first = ARITY * i + 1;
            if first >= len {
                break;
            }
            let mut top = first;
            for c in first + 1..(first + ARITY).min(len) {
                if self.heap[c] > self.heap[top] {
                    top = c;
                }
            }
            if self.heap[top] <= entry {
                break;
            }
            self.heap[i] = self.heap[top];
            self.pos[self.heap[i] as u32 as usize] = i as u32;
            i = top;
        }
        self.heap[i] = entry;
        self.pos[entry as u32 as usize] = i as u32;
    }

    fn pop(&mut self) -> Option<u32> {
        let top = *self.heap.first()? as u32;
        let last = self.heap.pop()?;
        if !self.heap.is_empty() {
            self.heap[0] = last;
            self.sift_down(0);
        }
        Some(top)
    }

    /// Lower the weight of `i` (still in the heap) by `dw ≥ 0`.
    fn decrease(&mut self, i: u32, dw: f32) {
        let at = self.pos[i as usize] as usize;
        self.heap[at] = weight_bits(weight_of(self.heap[at]) - dw) | u64::from(i);
        self.sift_down(at);
    }
}

/// Every candidate's neighbours of non-zero weight with their weights, in the grid's fixed
/// order (compressed rows, chunk by chunk). Elimination visits a removed candidate's
/// neighbours once each; weighing them here, in parallel, leaves the sequential loop only the
/// heap updates (and a third of the candidates it looked at before, those of the 27 cells
/// that lie beyond 2 r_max). About 18 entries a candidate, 8 bytes each: most of
/// [`sampling_memory`].
struct Neighbours {
    chunks: Vec<NeighbourChunk>,
}

/// The neighbours of [`Neighbours::CHUNK`] candidates: where each one's entries end (u32: a
/// chunk holds far fewer), and the entries (neighbour, weight).
type NeighbourChunk = (Vec<u32>, Vec<(u32, f32)>);

impl Neighbours {
    /// Candidates weighed by one task. The chunks are kept as they are: joined into one
    /// list, they were held twice while it was filled (the sampling's peak).
    const CHUNK: usize = 4096;

    fn of(c: &[Surfel], grid: &Grid, radii: &[f32]) -> Neighbours {
        let chunks = (0..c.len().div_ceil(Self::CHUNK))
            .into_par_iter()
            .map(|k| {
                let (mut ends, mut entries) = (Vec::with_capacity(Self::CHUNK), Vec::new());
                for i in k * Self::CHUNK..((k + 1) * Self::CHUNK).min(c.len()) {
                    grid.for_each_around(i, |j| {
                        if j as usize != i {
                            let w = weight(&c[i], &c[j as usize], radii);
                            if w > 0.0 {
                                entries.push((j, w));
                            }
                        }
                    });
                    ends.push(entries.len() as u32);
                }
                entries.shrink_to_fit();
                (ends, entries)
            })
            .collect();
        Neighbours { chunks }
    }

    fn of_candidate(&self, i: usize) -> &[(u32, f32)] {
        let (ends, entries) = &self.chunks[i / Self::CHUNK];
        let k = i % Self::CHUNK;
        let start = if k == 0 { 0 } else { ends[k - 1] as usize };
        &entries[start..ends[k] as usize]
    }
}

/// Which candidates survive elimination down to `keep`.
fn eliminate(c: &[Surfel], grid: &Grid, radii: &[f32], keep: usize) -> Vec<bool> {
    let neighbours = Neighbours::of(c, grid, radii);
    // Summed in the grid's order, as the removals below subtract them.
    let w: Vec<f32> = (0..c.len())
        .into_par_iter()
        .map(|i| neighbours.of_candidate(i).iter().map(|&(_, w)| w).sum())
        .collect();
    let mut heap = WeightHeap::new(&w);
    let mut alive = vec![true; c.len()];
    let mut remaining = c.len();
    while remaining > keep {
        let Some(i) = heap.pop() else {
            break;
        };
        alive[i as usize] = false;
        remaining -= 1;
        for &(j, dw) in neighbours.of_candidate(i as usize) {
            if alive[j as usize] {
                heap.decrease(j, dw);
            }
        }
    }
    alive
}

/// The surviving candidates, each with the area of the candidates nearest to it
/// (`area_each` of a candidate on a mesh).
fn assign_areas(
    c: &[Surfel],
    grid: &Grid,
    alive: &[bool],
    area_each: &impl Fn(u32) -> f32,
) -> Vec<Surfel> {
    let nearest: Vec<u32> = (0..c.len())
        .into_par_iter()
        .map(|i| {
            if alive[i] {
                return i as u32;
            }
            let mut best = (f32::INFINITY, u32::MAX);
            grid.for_each_around(i, |j| {
                let s = &c[j as usize];
                if alive[j as usize] && s.n.dot(c[i].n) > 0.0 {
                    let d = s.p.distance_squared(c[i].p);
                    if (d, j) < best {
                        best = (d, j);
                    }
                }
            });
            if best.1 == u32::MAX {
                // No surfel nearby facing the same way (a sliver of surface that lost all its
                // candidates): the nearest surfel anywhere takes the area.
                best = (0..c.len() as u32)
                    .filter(|&j| alive[j as usize])
                    .map(|j| (c[j as usize].p.distance_squared(c[i].p), j))
                    .fold((f32::INFINITY, u32::MAX), |a, b| if b < a { b } else { a });
            }
            best.1
        })
        .collect();
    // Summed in candidate order (f64): the same areas for any thread count.
    let mut areas = vec![0.0f64; c.len()];
    for (i, &k) in nearest.iter().enumerate() {
        areas[k as usize] += f64::from(area_each(c[i].mesh));
    }
    c.iter()
        .zip(alive)
        .zip(&areas)
        .filter(|((_, a), _)| **a)
        .map(|((s, _), &area)| Surfel {
            area: area as f32,
            ..*s
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The heap pops what an exhaustive search finds, the heaviest alive candidate by float
    /// comparison with ties to the higher index (±0 equal), through lowered weights, ties and
    /// negative weights (a sum that rounds below zero once its terms are taken back).
    #[test]
    fn weight_heap_pops_the_heaviest_with_ties_to_the_higher_index() {
        let mut rng = Sampler::new(7, 0, 0);
        let n = 1000;
        // Weights from a few values, so that ties are common; -0.0 beside 0.0.
        let values = [0.0f32, -0.0, 0.25, 0.5, 1.0, -1e-7, 2.0];
        let w: Vec<f32> = (0..n)
            .map(|_| values[(rng.next_1d() * values.len() as f32) as usize % values.len()])
            .collect();
        let mut heap = WeightHeap::new(&w);
        let mut w = w;
        let mut alive = vec![true; n];
        for _ in 0..n {
            let expected = (0..n)
                .filter(|&i| alive[i])
                .reduce(|a, b| {
                    if w[b] > w[a] || (w[b] == w[a] && b > a) {
                        b
                    } else {
                        a
                    }
                })
                .expect("a candidate is alive");
            assert_eq!(heap.pop(), Some(expected as u32));
            alive[expected] = false;
            // Lower a few alive weights, some to a value another candidate has.
            for _ in 0..3 {
                let j = (rng.next_1d() * n as f32) as usize % n;
                if alive[j] {
                    let dw = [0.25f32, 0.5, 1e-7][(rng.next_1d() * 3.0) as usize % 3];
                    w[j] -= dw;
                    heap.decrease(j as u32, dw);
                }
            }
        }
        assert_eq!(heap.pop(), None);
    }
}

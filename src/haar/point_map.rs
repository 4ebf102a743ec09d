//! A sparse Haar map laid out for point evaluation: the gather's lookups.
//!
//! [`SparseHaar::eval`] walks the coefficient tree from the root, one node a level, each
//! node's address read from its parent: a chain of dependent loads. Over a render's
//! thousands of maps those loads miss the cache, and the walk, not its arithmetic, was 10–20 %
//! of a glossy scene's render (cbox-rough at 512²: 9.8 million evaluations of 3.3 levels
//! each, two thirds of the samples of `SparseHaar::eval` on the load of the next node).
//! Most evaluations read the inner nodes' projected-area maps, whose 8 × 8 texels are all
//! kept: a tree of 21 nodes (588 bytes) for 64 floats (256 bytes).
//!
//! A [`PointMap`] keeps such a map as its texels at the depth its tree reaches, wherever they
//! take no more memory than the tree: one load instead of a walk. Each texel holds the sums the
//! tree's walk makes to reach it, in the same order (`SparseHaar::point_texels_into`), and a
//! point's texel is found by the same arithmetic that picks the tree's quadrants (a
//! multiplication by a power of two, exact, then truncation), so both forms give the same value
//! bit for bit at every point (`tests/haar.rs`).

use super::sparse::SparseHaar;
use super::transform::Coefficient;

/// A map for point evaluation: its texels where they are no larger than its tree, else the
/// tree.
#[derive(Clone, Debug, PartialEq)]
pub enum PointMap<T> {
    /// The texels of the level the tree reaches (`2^depth` a side, row-major), each the
    /// tree's value there; `levels` is the map's resolution, as [`SparseHaar::levels`].
    Texels {
        /// The map's resolution (log2 of its side).
        levels: u32,
        /// The levels the tree holds details on (log2 of the texels' side).
        depth: u32,
        /// The values, row-major.
        texels: Box<[T]>,
    },
    /// The tree itself.
    Tree(SparseHaar<T>),
}

impl<T: Coefficient> From<SparseHaar<T>> for PointMap<T> {
    fn from(map: SparseHaar<T>) -> Self {
        let depth = map.stored_levels();
        let side = 1usize << depth;
        let texel_bytes = side * side * std::mem::size_of::<T>();
        if depth == 0 || texel_bytes > map.tree_bytes() {
            return PointMap::Tree(map);
        }
        let mut texels = Vec::new();
        map.point_texels_into(depth, &mut texels);
        PointMap::Texels {
            levels: map.levels(),
            depth,
            texels: texels.into_boxed_slice(),
        }
    }
}

/// The index, in row-major texels of `2^depth` a side, of the texel holding the point
/// `(x, y)` of the unit square, as [`PointMap::eval`] reads it.
#[inline]
pub fn texel_index(depth: u32, x: f32, y: f32) -> usize {
    // The tree's walk picks, at level l, the half-cell floor(x · 2^(l+1)) (capped at the
    // last): the top l + 1 bits of floor(x · 2^depth), which is this.
    let side = 1u32 << depth;
    let at = |v: f32| ((v * side as f32) as u32).min(side - 1);
    (at(y) * side + at(x)) as usize
}

impl<T: Coefficient> PointMap<T> {
    /// f at the point `(x, y)` of the unit square: [`SparseHaar::eval`] of the map it was made
    /// from, bit for bit.
    #[inline]
    pub fn eval(&self, x: f32, y: f32) -> T {
        match self {
            PointMap::Texels { depth, texels, .. } => texels[texel_index(*depth, x, y)],
            PointMap::Tree(map) => map.eval(x, y),
        }
    }

    /// The map's resolution (log2 of its side), as [`SparseHaar::levels`].
    pub fn levels(&self) -> u32 {
        match self {
            PointMap::Texels { levels, .. } => *levels,
            PointMap::Tree(map) => map.levels(),
        }
    }
}

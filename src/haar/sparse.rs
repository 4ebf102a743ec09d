//! Sparse Haar coefficient trees with O(log N) point evaluation (docs/method.md §5.2).
//!
//! A [`SparseHaar`] keeps the scaling coefficient and a quadtree of detail triples: a node holds
//! the three details of one cell and the indices of its four children (the quadrants one level
//! finer). A subtree whose details were all dropped is absent, so evaluation walks from the root
//! towards the point's finest cell and stops at the first missing node.
//!
//! Thresholds are relative: [`SparseHaar::compress`] drops every detail coefficient whose
//! magnitude is below `tau · ‖f‖₂`, where ‖f‖₂ is the function's L2 norm over the unit square
//! (equal to the norm of its coefficient vector, the basis being orthonormal). Scaling f by any
//! factor scales the kept set's coefficients by the same factor and keeps the same set. The
//! dropped energy bounds the error: ‖f − f̃‖₂ ≤ tau · ‖f‖₂ · √(dropped coefficients), per channel.

use super::transform::{detail_index, detail_value, locate, Coefficient, Details, Haar2d};

const NONE: u32 = u32::MAX;

/// Whether a coefficient survives the absolute threshold `cut`.
#[inline]
fn keeps<T: Coefficient>(c: T, cut: f32) -> bool {
    c != T::default() && c.magnitude() >= cut
}

/// Per cell of `h` (in [`detail_index`] order), whether it or a cell below it keeps a detail:
/// one pass from the finest level up, so that the tree is built without visiting the cells
/// of dropped subtrees twice (most of a thresholded map).
fn kept_subtrees<T: Coefficient>(h: &Haar2d<T>, cut: f32) -> Vec<bool> {
    let mut alive: Vec<bool> = h
        .details
        .iter()
        .map(|d| d.iter().any(|&c| keeps(c, cut)))
        .collect();
    for l in (0..h.levels.saturating_sub(1)).rev() {
        for j in 0..1u32 << l {
            for i in 0..1u32 << l {
                let below = [(0, 0), (1, 0), (0, 1), (1, 1)]
                    .iter()
                    .any(|&(a, b)| alive[detail_index(l + 1, 2 * i + a, 2 * j + b)]);
                alive[detail_index(l, i, j)] |= below;
            }
        }
    }
    alive
}

/// Set the texels of cell `(i, j)` of level `l` to `value`, in `out`: the texels of level
/// `levels` (`2^levels` a side, row-major).
fn fill_cell<T: Copy>(out: &mut [T], levels: u32, (l, i, j): (u32, usize, usize), value: T) {
    let size = 1usize << (levels - l);
    let side = 1usize << levels;
    for y in j * size..(j + 1) * size {
        out[y * side + i * size..y * side + (i + 1) * size].fill(value);
    }
}

#[derive(Clone, Debug, PartialEq)]
struct Node<T> {
    details: Details<T>,
    children: [u32; 4],
}

/// A thresholded Haar decomposition of a function on the unit square.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseHaar<T> {
    levels: u32,
    scale: T,
    /// Depth-first pre-order; `nodes[0]` is the root when there is any.
    nodes: Vec<Node<T>>,
}

impl<T: Coefficient> SparseHaar<T> {
    /// Keep the coefficients of `h` whose magnitude is at least `tau · ‖f‖₂` (see the module
    /// docs); `tau = 0` keeps every non-zero detail.
    pub fn compress(h: &Haar2d<T>, tau: f32) -> Self {
        Self::compress_below(h, tau * h.norm())
    }

    /// Keep the coefficients of `h` whose magnitude is at least `cut` (an absolute value: the
    /// caller makes it relative, e.g. to an aggregate the details belong to).
    pub fn compress_below(h: &Haar2d<T>, cut: f32) -> Self {
        let mut out = SparseHaar {
            levels: h.levels,
            scale: h.scale,
            nodes: Vec::new(),
        };
        if h.levels > 0 {
            let alive = kept_subtrees(h, cut);
            if alive[0] {
                out.nodes
                    .reserve_exact(alive.iter().filter(|&&a| a).count());
                out.build(h, cut, &alive, 0, 0, 0);
            }
        }
        out
    }

    /// Append cell (l, i, j), which keeps something in its subtree (`alive`), and the live
    /// cells below it; returns its index.
    fn build(&mut self, h: &Haar2d<T>, cut: f32, alive: &[bool], l: u32, i: u32, j: u32) -> u32 {
        let mut details = h.details[detail_index(l, i, j)];
        for c in &mut details {
            if !keeps(*c, cut) {
                *c = T::default();
            }
        }
        let at = self.nodes.len();
        self.nodes.push(Node {
            details,
            children: [NONE; 4],
        });
        if l + 1 < h.levels {
            for (q, (a, b)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
                let (ci, cj) = (2 * i + a, 2 * j + b);
                if alive[detail_index(l + 1, ci, cj)] {
                    self.nodes[at].children[q] = self.build(h, cut, alive, l + 1, ci, cj);
                }
            }
        }
        at as u32
    }

    /// Σ w·f over `terms`, thresholded at `tau` of the sum's norm as [`SparseHaar::compress`]
    /// does it (see [`SparseSum`]).
    pub fn weighted_sum(terms: &[(&SparseHaar<T>, f32)], tau: f32) -> Self {
        let sum = SparseSum::of(terms);
        sum.keep(tau * sum.norm())
    }

    /// The product of f with a function that is constant on each cell of level `k`
    /// (`factors`, row-major, `2^k` a side; `k` at most the map's levels), exactly: the
    /// details finer than level k scale by their cell's factor, and the coarser ones are the
    /// transform of the products of the cells' means. Every non-zero coefficient is kept.
    pub fn scaled_by_cells(&self, k: u32, factors: &[f32]) -> Self {
        assert!(k <= self.levels, "cells finer than the map");
        let side = 1usize << k;
        assert_eq!(factors.len(), side * side, "one factor per cell");
        let mut means = Vec::new();
        self.means_into(k, &mut means);
        let products: Vec<T> = means.iter().zip(factors).map(|(m, f)| *m * *f).collect();
        let coarse = Haar2d::forward(&products, side);
        let mut out = SparseHaar {
            levels: self.levels,
            scale: coarse.scale,
            nodes: Vec::new(),
        };
        if self.levels > 0 {
            let root = if self.nodes.is_empty() { NONE } else { 0 };
            out.push_scaled(self, &coarse, factors, root, (0, 0, 0));
        }
        out
    }

    /// [`SparseHaar::scaled_by_cells`] for the cell `(l, i, j)` (the map's node there:
    /// `node`) and below; returns the new node's index, or `NONE` where all is zero.
    fn push_scaled(
        &mut self,
        map: &SparseHaar<T>,
        coarse: &Haar2d<T>,
        factors: &[f32],
        node: u32,
        (l, i, j): (u32, u32, u32),
    ) -> u32 {
        let k = coarse.levels;
        let details = if l < k {
            coarse.details[detail_index(l, i, j)]
        } else {
            let shift = l - k;
            let f = factors[((j as usize >> shift) << k) + (i as usize >> shift)];
            if node == NONE || f == 0.0 {
                return NONE;
            }
            map.nodes[node as usize].details.map(|c| c * f)
        };
        let at = self.open_node(details, 0.0);
        if l + 1 < self.levels {
            for (q, (a, b)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
                let child = if node == NONE {
                    NONE
                } else {
                    map.nodes[node as usize].children[q]
                };
                if l + 1 < k || child != NONE {
                    let c = self.push_scaled(
                        map,
                        coarse,
                        factors,
                        child,
                        (l + 1, 2 * i + a, 2 * j + b),
                    );
                    self.nodes[at].children[q] = c;
                }
            }
        }
        self.close_node(at)
    }

    /// Append a node with the `details` that reach `cut` (the others zero) and no children
    /// yet; returns its index, for [`SparseHaar::close_node`] once its children are in.
    fn open_node(&mut self, mut details: Details<T>, cut: f32) -> usize {
        for c in &mut details {
            if !keeps(*c, cut) {
                *c = T::default();
            }
        }
        self.nodes.push(Node {
            details,
            children: [NONE; 4],
        });
        self.nodes.len() - 1
    }

    /// Node `at` (the last one, its children appended and closed before it) kept if it or a
    /// child holds something, else removed: its index, or `NONE`.
    fn close_node(&mut self, at: usize) -> u32 {
        let n = &self.nodes[at];
        if n.children.iter().any(|&c| c != NONE) || n.details.iter().any(|c| *c != T::default()) {
            at as u32
        } else {
            self.nodes.pop();
            NONE
        }
    }

    /// The map with `f` applied to every stored coefficient (the scaling one and the
    /// details; a zero detail stays zero, so `f` must map zero to zero): a scaling per
    /// channel, say.
    pub(crate) fn map_coefficients(mut self, f: impl Fn(T) -> T) -> Self {
        self.scale = f(self.scale);
        for node in &mut self.nodes {
            for c in &mut node.details {
                if *c != T::default() {
                    *c = f(*c);
                }
            }
        }
        self
    }

    /// The means of f over the cells of level `k` (row-major, `2^k` a side): the texels of
    /// the map averaged down to that resolution, as [`SparseHaar::texels_into`] gives them.
    pub fn means_into(&self, k: u32, out: &mut Vec<T>) {
        self.decode_at(k, out);
    }

    /// The map's texels at `levels` (`2^levels` a side, row-major) into `out`: each cell of
    /// that level holds the map's mean over it.
    fn decode_at(&self, levels: u32, out: &mut Vec<T>) {
        let n = 1usize << levels;
        out.clear();
        out.resize(n * n, T::default());
        let root = if self.nodes.is_empty() { NONE } else { 0 };
        self.decode_to(levels, out, root, 0, (0, 0), self.scale);
    }

    /// f at the point `(x, y)` of the unit square.
    pub fn eval(&self, x: f32, y: f32) -> T {
        let mut value = self.scale;
        let mut node = if self.nodes.is_empty() { NONE } else { 0 };
        let mut l = 0;
        while node != NONE {
            let (_, _, quadrant) = locate(x, y, l);
            let n = &self.nodes[node as usize];
            value = value + detail_value(n.details, quadrant, l);
            node = n.children[quadrant];
            l += 1;
        }
        value
    }

    /// The full decomposition back (dropped coefficients as zeros).
    pub fn to_dense(&self) -> Haar2d<T> {
        self.dense_at(self.levels)
    }

    /// The decomposition back at the coarsest resolution that holds every stored detail (the
    /// finer ones are all zero): the same function as [`SparseHaar::to_dense`], smaller where
    /// the map is smooth (a diffuse subtree's intensity in a tree of 64² maps is 8²).
    pub fn to_dense_trimmed(&self) -> Haar2d<T> {
        self.dense_at(self.stored_depth(0, 0))
    }

    /// The decomposition with the details of `levels` levels (at least the stored ones).
    fn dense_at(&self, levels: u32) -> Haar2d<T> {
        let mut h = Haar2d {
            levels,
            scale: self.scale,
            details: vec![[T::default(); 3]; ((1usize << (2 * levels)) - 1) / 3],
        };
        if !self.nodes.is_empty() {
            self.fill(&mut h, 0, 0, 0, 0);
        }
        h
    }

    /// The map's texels (row-major, `2^levels` a side) into `out`, as
    /// `to_dense().inverse()` gives them, bit for bit (the same sums, and scalings by powers
    /// of two), without the dense decomposition: a dropped subtree fills its block at once.
    pub fn texels_into(&self, out: &mut Vec<T>) {
        self.decode_at(self.levels, out);
    }

    /// The texels of [`SparseHaar::to_dense_trimmed`] (row-major) into `out`, as its
    /// `inverse()` gives them, bit for bit, without the dense decomposition; returns their
    /// levels (`2^levels` a side).
    pub fn trimmed_texels_into(&self, out: &mut Vec<T>) -> u32 {
        let levels = self.stored_depth(0, 0);
        self.decode_at(levels, out);
        levels
    }

    /// Cell `(i, j)` of level `l`, whose (scaled) mean is `m`, and below, down to level
    /// `stop` (the resolution of `out`).
    fn decode_to(&self, stop: u32, out: &mut [T], node: u32, l: u32, (i, j): (usize, usize), m: T) {
        if node == NONE || l == stop {
            // m is the mean over 4^(stop − l) texels, scaled by 2^−l: each texel is m 2^l.
            fill_cell(out, stop, (l, i, j), m * (1u32 << l) as f32);
            return;
        }
        let n = &self.nodes[node as usize];
        let [dx, dy, dxy] = n.details;
        let means = [
            (m + dx + dy + dxy) * 0.5,
            (m - dx + dy - dxy) * 0.5,
            (m + dx - dy - dxy) * 0.5,
            (m - dx - dy + dxy) * 0.5,
        ];
        for (q, (a, b)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
            self.decode_to(
                stop,
                out,
                n.children[q],
                l + 1,
                (2 * i + a, 2 * j + b),
                means[q],
            );
        }
    }

    /// The map's texels at the `depth` its tree reaches ([`SparseHaar::stored_levels`];
    /// `2^depth` a side, row-major) into `out`, each the value [`SparseHaar::eval`] gives
    /// inside it, bit for bit: the same sums in the same order, each node's once for the
    /// texels below it rather than once a lookup.
    pub(crate) fn point_texels_into(&self, depth: u32, out: &mut Vec<T>) {
        let side = 1usize << depth;
        out.clear();
        out.resize(side * side, self.scale);
        if !self.nodes.is_empty() {
            self.point_fill(0, 0, (0, 0), self.scale, depth, out);
        }
    }

    /// [`SparseHaar::point_texels_into`] below `node`, cell `(i, j)` of level `l`, whose
    /// value so far is `value`.
    fn point_fill(
        &self,
        node: u32,
        l: u32,
        (i, j): (usize, usize),
        value: T,
        depth: u32,
        out: &mut [T],
    ) {
        if node == NONE || l == depth {
            fill_cell(out, depth, (l, i, j), value);
            return;
        }
        let n = &self.nodes[node as usize];
        for (q, &child) in n.children.iter().enumerate() {
            let below = value + detail_value(n.details, q, l);
            let cell = (2 * i + (q & 1), 2 * j + (q >> 1));
            self.point_fill(child, l + 1, cell, below, depth, out);
        }
    }

    /// The levels the tree holds nodes on: how many [`SparseHaar::eval`] may walk.
    pub(crate) fn stored_levels(&self) -> u32 {
        self.stored_depth(0, 0)
    }

    /// The memory the tree's nodes take.
    pub(crate) fn tree_bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice())
    }

    /// The levels below and including `node` (at level `l`) that hold stored details.
    fn stored_depth(&self, node: u32, l: u32) -> u32 {
        match self.nodes.get(node as usize) {
            None => l,
            Some(n) => n
                .children
                .iter()
                .filter(|&&c| c != NONE)
                .map(|&c| self.stored_depth(c, l + 1))
                .fold(l + 1, u32::max),
        }
    }

    fn fill(&self, h: &mut Haar2d<T>, node: u32, l: u32, i: u32, j: u32) {
        let n = &self.nodes[node as usize];
        h.details[detail_index(l, i, j)] = n.details;
        for (q, (a, b)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
            if n.children[q] != NONE {
                self.fill(h, n.children[q], l + 1, 2 * i + a, 2 * j + b);
            }
        }
    }

    /// The mean of the function over the unit square (its scaling coefficient).
    pub fn mean(&self) -> T {
        self.scale
    }

    /// The resolution (log2 of the map side).
    pub fn levels(&self) -> u32 {
        self.levels
    }

    /// The same function on a grid of `levels` (finer or the same): its finer details are
    /// zero, so no node changes (as [`Haar2d::refined_to`]).
    pub fn refined_to(mut self, levels: u32) -> Self {
        assert!(levels >= self.levels, "refining to a coarser grid");
        self.levels = levels;
        self
    }

    /// Non-zero coefficients kept, the scaling coefficient included.
    pub fn coefficient_count(&self) -> usize {
        usize::from(self.scale != T::default())
            + self
                .nodes
                .iter()
                .flat_map(|n| n.details.iter())
                .filter(|c| **c != T::default())
                .count()
    }
}

impl<T: Coefficient> SparseHaar<T> {
    /// Append the little-endian encoding: levels and node count (u32 each), the scaling
    /// coefficient, then the nodes in pre-order, each as a byte whose low four bits say which
    /// children follow, and its three details. Child positions are implicit in the order.
    pub fn write_to(&self, out: &mut Vec<u8>) {
        let start = out.len();
        out.extend_from_slice(&self.levels.to_le_bytes());
        out.extend_from_slice(&(self.nodes.len() as u32).to_le_bytes());
        self.scale.write_le(out);
        for n in &self.nodes {
            let mask =
                n.children
                    .iter()
                    .enumerate()
                    .fold(0u8, |m, (q, &c)| if c != NONE { m | 1 << q } else { m });
            out.push(mask);
            for d in n.details {
                d.write_le(out);
            }
        }
        debug_assert_eq!(out.len() - start, self.encoded_len());
    }

    /// The bytes [`SparseHaar::write_to`] appends: 8 for levels and count, the scaling
    /// coefficient, and per node its byte of children and three details.
    pub fn encoded_len(&self) -> usize {
        let value = 4 * T::FLOATS;
        8 + value + self.nodes.len() * (1 + 3 * value)
    }

    /// Decode one tree from the front of `bytes`, returning it and the bytes it used; `None`
    /// when the data is short or inconsistent (non-finite values, a node count or a depth that
    /// does not match the structure).
    pub fn read_from(bytes: &[u8]) -> Option<(Self, usize)> {
        let u32_at = |o: usize| -> Option<u32> {
            Some(u32::from_le_bytes(bytes.get(o..o + 4)?.try_into().ok()?))
        };
        let levels = u32_at(0)?;
        let count = u32_at(4)? as usize;
        if levels > 16 || count > ((1usize << (2 * levels)) - 1) / 3 {
            return None;
        }
        let mut at = 8;
        let scale = read_value::<T>(bytes, &mut at)?;
        let mut out = SparseHaar {
            levels,
            scale,
            nodes: Vec::with_capacity(count),
        };
        if count > 0 {
            out.parse_node(bytes, &mut at, 0, count)?;
        }
        (out.nodes.len() == count).then_some((out, at))
    }

    /// Parse the node at `at` and its subtree (depth `l`); returns its index.
    fn parse_node(&mut self, bytes: &[u8], at: &mut usize, l: u32, count: usize) -> Option<u32> {
        if l >= self.levels || self.nodes.len() >= count {
            return None;
        }
        let mask = *bytes.get(*at)?;
        *at += 1;
        let details = [
            read_value::<T>(bytes, at)?,
            read_value::<T>(bytes, at)?,
            read_value::<T>(bytes, at)?,
        ];
        let me = self.nodes.len();
        self.nodes.push(Node {
            details,
            children: [NONE; 4],
        });
        for q in 0..4 {
            if mask & (1 << q) != 0 {
                let c = self.parse_node(bytes, at, l + 1, count)?;
                self.nodes[me].children[q] = c;
            }
        }
        (mask & 0xf0 == 0).then_some(me as u32)
    }
}

/// One little-endian, finite coefficient at `*at`, advancing it.
fn read_value<T: Coefficient>(bytes: &[u8], at: &mut usize) -> Option<T> {
    let mut f = [0f32; 3];
    for x in f.iter_mut().take(T::FLOATS) {
        let v = f32::from_le_bytes(bytes.get(*at..*at + 4)?.try_into().ok()?);
        if !v.is_finite() {
            return None;
        }
        *x = v;
        *at += 4;
    }
    Some(T::from_floats(&f[..T::FLOATS]))
}

/// Σ w·f over sparse maps, exactly, without a dense decomposition: every cell some term
/// stores (and only those) with its summed details. Bit for bit the dense sum built term by
/// term with [`Haar2d::combine`] (the same products and sums in the same order); its
/// [`SparseSum::norm`] adds the squares in the dense order, so that [`SparseSum::keep`] at a
/// cut relative to it keeps what [`SparseHaar::compress_below`] of the dense sum keeps.
pub struct SparseSum<T> {
    levels: u32,
    scale: T,
    /// In pre-order.
    cells: Vec<SummedCell<T>>,
}

/// A cell of a [`SparseSum`]: where it lies and its summed details.
struct SummedCell<T> {
    index: usize,
    level: u32,
    quadrant: usize,
    details: Details<T>,
}

impl<T: Coefficient> SparseSum<T> {
    /// Σ w·f over `terms`, at the finest resolution among them.
    pub fn of(terms: &[(&SparseHaar<T>, f32)]) -> Self {
        let levels = terms.iter().map(|(m, _)| m.levels).max().unwrap_or(0);
        let scale = terms
            .iter()
            .fold(T::default(), |acc, (m, w)| acc * 1.0 + m.scale * *w);
        // At most every term's nodes, and at most every cell of the finest levels.
        let cells = terms
            .iter()
            .map(|(m, _)| m.nodes.len())
            .sum::<usize>()
            .min(((1usize << (2 * levels)) - 1) / 3);
        let mut sum = SparseSum {
            levels,
            scale,
            cells: Vec::with_capacity(cells),
        };
        // Per level, the terms' nodes at the cell being visited.
        let mut nodes = vec![NONE; terms.len() * (levels as usize + 1)];
        for ((m, _), n) in terms.iter().zip(&mut nodes) {
            *n = if m.nodes.is_empty() { NONE } else { 0 };
        }
        if nodes[..terms.len()].iter().any(|&n| n != NONE) {
            sum.add_cell(terms, &mut nodes, (0, 0, 0), 0);
        }
        sum
    }

    /// The cell `(l, i, j)` (quadrant `quadrant` of its parent; the terms' nodes there in
    /// `nodes[..terms.len()]`) and the cells below it that any term stores.
    fn add_cell(
        &mut self,
        terms: &[(&SparseHaar<T>, f32)],
        nodes: &mut [u32],
        (l, i, j): (u32, u32, u32),
        quadrant: usize,
    ) {
        let (here, below) = nodes.split_at_mut(terms.len());
        let mut details = [T::default(); 3];
        for ((m, w), &n) in terms.iter().zip(here.iter()) {
            if n != NONE {
                let d = m.nodes[n as usize].details;
                for (acc, c) in details.iter_mut().zip(d) {
                    *acc = *acc * 1.0 + c * *w;
                }
            }
        }
        self.cells.push(SummedCell {
            index: detail_index(l, i, j),
            level: l,
            quadrant,
            details,
        });
        for (q, (a, b)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
            let mut any = false;
            for (((m, _), &n), child) in terms.iter().zip(here.iter()).zip(below.iter_mut()) {
                *child = if n == NONE {
                    NONE
                } else {
                    m.nodes[n as usize].children[q]
                };
                any |= *child != NONE;
            }
            if any {
                self.add_cell(terms, below, (l + 1, 2 * i + a, 2 * j + b), q);
            }
        }
    }

    /// The L2 norm of the sum ([`Haar2d::norm`] of the dense sum, bit for bit).
    pub fn norm(&self) -> f32 {
        let mut order: Vec<(usize, u32)> = self
            .cells
            .iter()
            .enumerate()
            .map(|(c, cell)| (cell.index, c as u32))
            .collect();
        order.sort_unstable();
        std::iter::once(self.scale)
            .chain(
                order
                    .iter()
                    .flat_map(|&(_, c)| self.cells[c as usize].details.iter().copied()),
            )
            .map(|c| (c.magnitude() as f64).powi(2))
            .sum::<f64>()
            .sqrt() as f32
    }

    /// The sum with the coefficients of magnitude at least `cut` (non-zero ones for 0), as
    /// [`SparseHaar::compress_below`] keeps them.
    pub fn keep(&self, cut: f32) -> SparseHaar<T> {
        let mut out = SparseHaar {
            levels: self.levels,
            scale: self.scale,
            nodes: Vec::new(),
        };
        if !self.cells.is_empty() {
            out.nodes.reserve_exact(self.cells.len());
            self.keep_cell(&mut out, &mut 0, cut);
            out.nodes.shrink_to_fit();
        }
        out
    }

    /// Append `cells[*next]` and its subtree (the deeper cells that follow it in pre-order)
    /// to `out` with the details that reach `cut`, unless nothing in it does; returns its
    /// index, or `NONE`.
    fn keep_cell(&self, out: &mut SparseHaar<T>, next: &mut usize, cut: f32) -> u32 {
        let cell = &self.cells[*next];
        *next += 1;
        let at = out.open_node(cell.details, cut);
        while *next < self.cells.len() && self.cells[*next].level > cell.level {
            let quadrant = self.cells[*next].quadrant;
            let child = self.keep_cell(out, next, cut);
            out.nodes[at].children[quadrant] = child;
        }
        out.close_node(at)
    }
}

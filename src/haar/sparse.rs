//! Sparse Haar coefficient trees with O(log N) point evaluation (spec §5.2).
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

use super::transform::{detail_index, Coefficient, Details, Haar2d};

const NONE: u32 = u32::MAX;

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
            out.build(h, cut, 0, 0, 0);
        }
        out
    }

    /// Append the subtree of cell (l, i, j) if it keeps anything; returns its index or NONE.
    fn build(&mut self, h: &Haar2d<T>, cut: f32, l: u32, i: u32, j: u32) -> u32 {
        let keep = |c: T| c != T::default() && c.magnitude() >= cut;
        let mut details = h.details[detail_index(l, i, j)];
        for c in &mut details {
            if !keep(*c) {
                *c = T::default();
            }
        }
        let at = self.nodes.len();
        self.nodes.push(Node {
            details,
            children: [NONE; 4],
        });
        let mut any_child = false;
        if l + 1 < h.levels {
            for (q, (a, b)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
                let c = self.build(h, cut, l + 1, 2 * i + a, 2 * j + b);
                self.nodes[at].children[q] = c;
                any_child |= c != NONE;
            }
        }
        if !any_child && details.iter().all(|c| *c == T::default()) {
            // Nothing below or here: drop the node (it is the last one pushed).
            self.nodes.truncate(at);
            return NONE;
        }
        at as u32
    }

    /// f at the point `(x, y)` of the unit square.
    pub fn eval(&self, x: f32, y: f32) -> T {
        let mut value = self.scale;
        let mut node = if self.nodes.is_empty() { NONE } else { 0 };
        let mut l = 0;
        while node != NONE {
            let cells = 1u32 << l;
            let hx = ((x * 2.0 * cells as f32) as u32).min(2 * cells - 1);
            let hy = ((y * 2.0 * cells as f32) as u32).min(2 * cells - 1);
            let sx = if hx & 1 == 0 { 1.0 } else { -1.0 };
            let sy = if hy & 1 == 0 { 1.0 } else { -1.0 };
            let n = &self.nodes[node as usize];
            let [dx, dy, dxy] = n.details;
            value = value + (dx * sx + dy * sy + dxy * (sx * sy)) * cells as f32;
            // The quadrant one level finer: the half-cell parities at this level.
            node = n.children[((hx & 1) + 2 * (hy & 1)) as usize];
            l += 1;
        }
        value
    }

    /// The full decomposition back (dropped coefficients as zeros).
    pub fn to_dense(&self) -> Haar2d<T> {
        let count = ((1usize << (2 * self.levels)) - 1) / 3;
        let mut h = Haar2d {
            levels: self.levels,
            scale: self.scale,
            details: vec![[T::default(); 3]; count],
        };
        if !self.nodes.is_empty() {
            self.fill(&mut h, 0, 0, 0, 0);
        }
        h
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

    /// The resolution (log2 of the map side).
    pub fn levels(&self) -> u32 {
        self.levels
    }

    /// Stored detail triples (nodes), for memory accounting.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
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
    /// Append the little-endian encoding: levels, node count, the scaling coefficient, then
    /// per node its three details and four child indices.
    pub fn write_to(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.levels.to_le_bytes());
        out.extend_from_slice(&(self.nodes.len() as u32).to_le_bytes());
        self.scale.write_le(out);
        for n in &self.nodes {
            for d in n.details {
                d.write_le(out);
            }
            for c in n.children {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }

    /// Decode one tree from the front of `bytes`, returning it and the bytes it used; `None`
    /// when the data is short or inconsistent (non-finite values, child indices that do not
    /// point forward within the tree).
    pub fn read_from(bytes: &[u8]) -> Option<(Self, usize)> {
        let word = |i: usize| -> Option<[u8; 4]> { bytes.get(4 * i..4 * i + 4)?.try_into().ok() };
        let levels = u32::from_le_bytes(word(0)?);
        let count = u32::from_le_bytes(word(1)?) as usize;
        if levels > 16 || count > ((1usize << (2 * levels)) - 1) / 3 {
            return None;
        }
        let value = |i: usize| -> Option<T> {
            let f: Option<Vec<f32>> = (i..i + T::FLOATS)
                .map(|k| word(k).map(f32::from_le_bytes).filter(|x| x.is_finite()))
                .collect();
            Some(T::from_floats(&f?))
        };
        let scale = value(2)?;
        let per_node = 3 * T::FLOATS + 4;
        let first = 2 + T::FLOATS;
        let mut nodes = Vec::with_capacity(count);
        for k in 0..count {
            let at = first + per_node * k;
            let details = [
                value(at)?,
                value(at + T::FLOATS)?,
                value(at + 2 * T::FLOATS)?,
            ];
            let mut children = [NONE; 4];
            for (q, c) in children.iter_mut().enumerate() {
                *c = u32::from_le_bytes(word(at + 3 * T::FLOATS + q)?);
                if *c != NONE && (*c as usize >= count || *c as usize <= k) {
                    return None;
                }
            }
            nodes.push(Node { details, children });
        }
        Some((
            SparseHaar {
                levels,
                scale,
                nodes,
            },
            4 * (first + per_node * count),
        ))
    }
}

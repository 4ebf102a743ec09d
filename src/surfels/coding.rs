//! Hierarchical wavelet coding of the surfel tree (docs/method.md §6, docs/design.md §5.5–§5.6).
//!
//! Every node has a directional function on the octahedral map: for a leaf, its surfel's
//! radiant intensity I(ω) = A max(0, n·ω) L(ω); for an inner node the sum of its children's,
//! G(j) = G(left) + G(right), so that a node seen from afar emits exactly what its surfels do
//! (docs/design.md §5.5 replaces the thesis's plain average by this sum). Alongside, the detail
//! H(j) = (G(left) − G(right)) / 2 recovers the children: G(left) = G(j)/2 + H(j) and
//! G(right) = G(j)/2 − H(j).
//!
//! With the split level ε: nodes above ε store G only, nodes at ε store G and (if inner) H,
//! inner nodes below ε store H only, and leaves below ε nothing (their parent's H gives them).
//! A node below ε is rebuilt from its ancestor at ε down the path:
//! G(j) = 2^−(l−ε) G(a) + Σₖ sₖ 2^−(l−lₖ−1) H(k), with sₖ = +1 towards a left child, −1 right.
//!
//! Compression is relative, never absolute: G(j) keeps its coefficients at least τ‖G(j)‖₂, and
//! H(j) those at least τ‖G(j)‖₂ too (the details measured against the node they refine).
//! Construction runs post-order with both subtrees in parallel (`rayon::join`); every stored
//! function is compressed from the exact uncompressed G's of the children, so compression
//! error never accumulates up the tree, and only the uncompressed G's of the pending path
//! exist at once: O(depth) maps, never the whole set.

use super::tree::{SurfelTree, NONE};
use crate::haar::{Coefficient, Haar2d, SparseHaar, SparseSum};

/// What one node stores.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeCoding<T> {
    /// The node's own map G, stored at and above the split level.
    pub g: Option<SparseHaar<T>>,
    /// The detail H between its two children (their maps are G/2 ± H), stored at and below
    /// the split level.
    pub h: Option<SparseHaar<T>>,
}

impl<T> Default for NodeCoding<T> {
    fn default() -> Self {
        NodeCoding { g: None, h: None }
    }
}

/// The coded tree: one [`NodeCoding`] per node of the [`SurfelTree`].
#[derive(Clone, Debug, PartialEq)]
pub struct CodedTree<T> {
    /// The split level ε (see the module docs).
    pub split_level: u32,
    /// Per node, in the tree's order.
    pub nodes: Vec<NodeCoding<T>>,
}

/// Code `tree` with leaf functions `leaf(surfel index)` (the radiant-intensity map of one
/// surfel at its own resolution, every non-zero coefficient kept), split level `split_level`
/// and relative threshold `tau`; every stored map has `levels`.
///
/// A node's maps are summed sparsely ([`SparseSum`]): only the cells some child stores are
/// visited, at the finest resolution below the node, not at `levels` (a subtree of diffuse
/// surfels, 8 × 8 cosine lobes, in a scene with a 64 × 64 glass costs at most 64 texels a
/// node instead of 4096; a mirror's sparse maps, the cells they keep). The coefficients are
/// those of the dense sums ([`Haar2d::combine`]) bit for bit.
pub fn encode<T: Coefficient + Send + Sync>(
    tree: &SurfelTree,
    leaf: &(dyn Fn(u32) -> SparseHaar<T> + Sync),
    levels: u32,
    split_level: u32,
    tau: f32,
) -> CodedTree<T> {
    let mut nodes = vec![NodeCoding::default(); tree.nodes.len()];
    if !tree.nodes.is_empty() {
        let mut out = Vec::new();
        let coder = Coder {
            tree,
            leaf,
            eps: split_level,
            tau,
        };
        coder.node(0, &mut out);
        for (i, c) in out {
            nodes[i as usize] = NodeCoding {
                g: c.g.map(|g| g.refined_to(levels)),
                h: c.h.map(|h| h.refined_to(levels)),
            };
        }
    }
    CodedTree { split_level, nodes }
}

/// Subtrees of at most this many surfels are coded on one thread, appending to their
/// parent's list: below it a task costs more than it shares, and every level of tasks
/// copied its subtree's list into its parent's once more.
const SERIAL_BELOW: u32 = 512;

/// `visit` of inner node `node`'s children, left then right, each appending what its subtree
/// stores to `out` in that order: as two tasks whose lists are joined, or on this thread
/// for a subtree of at most [`SERIAL_BELOW`] surfels.
fn children<R: Send, T: Send>(
    node: &crate::surfels::tree::Node,
    out: &mut Vec<T>,
    visit: impl Fn(u32, &mut Vec<T>) -> R + Sync,
) -> (R, R) {
    let [l, r] = node.children;
    if node.count <= SERIAL_BELOW {
        return (visit(l, out), visit(r, out));
    }
    let (mut out_l, mut out_r) = (Vec::new(), Vec::new());
    let g = rayon::join(|| visit(l, &mut out_l), || visit(r, &mut out_r));
    out.append(&mut out_l);
    out.append(&mut out_r);
    g
}

/// What [`encode`] codes with.
struct Coder<'a, T> {
    tree: &'a SurfelTree,
    leaf: &'a (dyn Fn(u32) -> SparseHaar<T> + Sync),
    eps: u32,
    tau: f32,
}

impl<T: Coefficient + Send + Sync> Coder<'_, T> {
    /// Returns the uncompressed G of node `j`, appending what the subtree stores to `out`.
    fn node(&self, j: u32, out: &mut Vec<(u32, NodeCoding<T>)>) -> SparseHaar<T> {
        let (tree, eps, tau) = (self.tree, self.eps, self.tau);
        let node = &tree.nodes[j as usize];
        if node.is_leaf() {
            let g = (self.leaf)(tree.order[node.first as usize]);
            if node.level <= eps {
                let stored = SparseHaar::weighted_sum(&[(&g, 1.0)], tau);
                out.push((
                    j,
                    NodeCoding {
                        g: Some(stored),
                        h: None,
                    },
                ));
            }
            return g;
        }
        let (gl, gr) = children(node, out, |c, out| self.node(c, out));
        let g = SparseSum::of(&[(&gl, 1.0), (&gr, 1.0)]);
        let cut = tau * g.norm();
        let stored = NodeCoding {
            g: (node.level <= eps).then(|| g.keep(cut)),
            h: (node.level >= eps).then(|| SparseSum::of(&[(&gl, 0.5), (&gr, -0.5)]).keep(cut)),
        };
        out.push((j, stored));
        g.keep(0.0)
    }
}

/// The exact radiant intensity G(j) of every node `j` for which `wanted(j)` holds, `None`
/// for the others: the sum of its leaves' maps `leaf(surfel index)`, nothing dropped, at the
/// finest resolution below it. What a reader of a few nodes' own light needs (a bounce reads
/// a fifth of the inner nodes), without the split-level coding a cache stores for its size.
/// Only the subtrees below a wanted node are summed.
pub fn node_sums<T: Coefficient + Send + Sync>(
    tree: &SurfelTree,
    leaf: &(dyn Fn(u32) -> SparseHaar<T> + Sync),
    wanted: &(dyn Fn(u32) -> bool + Sync),
) -> Vec<Option<SparseHaar<T>>> {
    let mut sums = vec![None; tree.nodes.len()];
    if !tree.nodes.is_empty() {
        let mut out = Vec::new();
        sum_below(tree, leaf, wanted, 0, false, &mut out);
        for (j, g) in out {
            sums[j as usize] = Some(g);
        }
    }
    sums
}

/// The G of node `j` if it or an ancestor is wanted (`wanted_above`), appending the wanted
/// nodes' G below it to `out`.
fn sum_below<T: Coefficient + Send + Sync>(
    tree: &SurfelTree,
    leaf: &(dyn Fn(u32) -> SparseHaar<T> + Sync),
    wanted: &(dyn Fn(u32) -> bool + Sync),
    j: u32,
    wanted_above: bool,
    out: &mut Vec<(u32, SparseHaar<T>)>,
) -> Option<SparseHaar<T>> {
    let node = &tree.nodes[j as usize];
    let this = wanted(j);
    let needed = wanted_above || this;
    let g = if node.is_leaf() {
        needed.then(|| leaf(tree.order[node.first as usize]))
    } else {
        let (gl, gr) = children(node, out, |c, out| {
            sum_below(tree, leaf, wanted, c, needed, out)
        });
        gl.zip(gr)
            .map(|(gl, gr)| SparseSum::of(&[(&gl, 1.0), (&gr, 1.0)]).keep(0.0))
    };
    if this {
        out.extend(g.clone().map(|g| (j, g)));
    }
    g
}

impl<T> CodedTree<T> {
    /// A coding of `tree` at split level `split_level` that stores no map yet: what a bake
    /// whose bounces code the tree for their light holds until they do.
    pub fn uncoded(tree: &SurfelTree, split_level: u32) -> Self {
        CodedTree {
            split_level,
            nodes: (0..tree.nodes.len())
                .map(|_| NodeCoding::default())
                .collect(),
        }
    }
}

impl<T: Coefficient> CodedTree<T> {
    /// Node `j`'s function rebuilt from what is stored (see the module docs).
    pub fn reconstruct(&self, tree: &SurfelTree, j: u32) -> Option<Haar2d<T>> {
        let (anchor, path) = self.path_to_anchor(tree, j)?;
        let mut g = self.nodes[anchor as usize].g.as_ref()?.to_dense();
        // Walk down: each step halves the parent and adds ± its detail.
        for (k, sign) in path.into_iter().rev() {
            let h = self.nodes[k as usize].h.as_ref()?.to_dense();
            g = Haar2d::combine(&g, 0.5, &h, sign);
        }
        Some(g)
    }

    /// Node `j`'s function at the point `(x, y)` of the map, without rebuilding it.
    pub fn eval(&self, tree: &SurfelTree, j: u32, x: f32, y: f32) -> Option<T> {
        let (anchor, path) = self.path_to_anchor(tree, j)?;
        let mut v = self.nodes[anchor as usize].g.as_ref()?.eval(x, y);
        for (k, sign) in path.into_iter().rev() {
            v = v * 0.5 + self.nodes[k as usize].h.as_ref()?.eval(x, y) * sign;
        }
        Some(v)
    }

    /// The nearest ancestor-or-self storing G, and the inner nodes on the way down to `j` with
    /// the sign of the child taken at each (listed from `j` upwards).
    fn path_to_anchor(&self, tree: &SurfelTree, j: u32) -> Option<(u32, Vec<(u32, f32)>)> {
        let mut path = Vec::new();
        let mut at = j;
        while self.nodes.get(at as usize)?.g.is_none() {
            let parent = tree.nodes[at as usize].parent;
            if parent == NONE {
                return None;
            }
            let sign = if tree.nodes[parent as usize].children[0] == at {
                1.0
            } else {
                -1.0
            };
            path.push((parent, sign));
            at = parent;
        }
        Some((at, path))
    }

    /// Nodes, maps and coefficients stored (for the bake summary).
    pub fn stored_counts(&self) -> (usize, usize) {
        let maps = self
            .nodes
            .iter()
            .map(|n| usize::from(n.g.is_some()) + usize::from(n.h.is_some()))
            .sum();
        let coefficients = self
            .nodes
            .iter()
            .flat_map(|n| [&n.g, &n.h])
            .flatten()
            .map(|s| s.coefficient_count())
            .sum();
        (maps, coefficients)
    }
}

//! The surfel tree: a binary bounding-sphere hierarchy (docs/design.md §5.5, docs/method.md §6.1).
//!
//! Built top-down by median split along the longest axis of the surfel centres' bounds (a
//! balanced tree, depth ⌈log₂ N⌉, one surfel per leaf), then bottom-up for the bounding spheres
//! (each encloses its children's, a surfel being the sphere of its disc), the normal cones and
//! the areas. Nodes are stored breadth-first, so the array runs coarse to fine: a reader of the
//! cache can load the top levels alone.

use super::Surfel;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// No child / no parent.
pub const NONE: u32 = u32::MAX;

/// One node of the tree: the one node record from the tree's build through the cache (where
/// [`crate::cache::store::NodeRecord`] adds where its maps are) to the gather (where
/// `gather::senders::SenderNode` keeps what a traversal tests of it beside what it sums from
/// the surfels below, in one cache line). Plain 4-byte
/// fields, so that the cache stores it as it is.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Node {
    /// Centre of the bounding sphere.
    pub center: Vec3,
    /// Radius of a sphere enclosing every surfel disc below.
    pub radius: f32,
    /// Normal cone: every surfel normal below makes an angle of at most `cone_angle` (radians,
    /// π when the normals span the sphere) with `axis`. Kept as an angle: cones merge in
    /// angles, and acos of a stored cosine would lose half the digits of a narrow cone.
    pub axis: Vec3,
    /// See `axis`.
    pub cone_angle: f32,
    /// Total surfel area below.
    pub area: f32,
    /// Depth (the root is level 0).
    pub level: u32,
    /// The parent node, or [`NONE`] for the root.
    pub parent: u32,
    /// `[left, right]`, or `[NONE, NONE]` for a leaf.
    pub children: [u32; 2],
    /// The surfels below are `order[first .. first + count]` of the tree.
    pub first: u32,
    /// See `first`.
    pub count: u32,
}

impl Node {
    /// Whether the node is a leaf (one surfel, no children).
    pub fn is_leaf(&self) -> bool {
        self.children[0] == NONE
    }
}

/// The hierarchy over a set of surfels.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfelTree {
    /// Breadth-first: `nodes[0]` is the root, and every level follows the one above.
    pub nodes: Vec<Node>,
    /// Surfel indices in leaf order: each node's surfels are one contiguous range.
    pub order: Vec<u32>,
}

impl SurfelTree {
    /// Build over `surfels` (an empty set gives an empty tree).
    pub fn build(surfels: &[Surfel]) -> SurfelTree {
        let mut order: Vec<u32> = (0..surfels.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * surfels.len());
        if surfels.is_empty() {
            return SurfelTree { nodes, order };
        }
        nodes.push(placeholder(0, NONE, 0, surfels.len() as u32));
        // Breadth-first splitting: the node array grows level by level.
        let mut next = 0;
        while next < nodes.len() {
            let Node {
                first,
                count,
                level,
                ..
            } = nodes[next];
            if count > 1 {
                let range = &mut order[first as usize..(first + count) as usize];
                split_at_median(range, surfels);
                let half = count / 2;
                let left = nodes.len() as u32;
                nodes.push(placeholder(level + 1, next as u32, first, half));
                nodes.push(placeholder(
                    level + 1,
                    next as u32,
                    first + half,
                    count - half,
                ));
                nodes[next].children = [left, left + 1];
            }
            next += 1;
        }
        // Bottom-up: children come after their parent, so a reverse sweep sees them first.
        for i in (0..nodes.len()).rev() {
            let n = nodes[i];
            let (center, radius, axis, cone_angle, area) = if n.is_leaf() {
                let s = &surfels[order[n.first as usize] as usize];
                (s.p, s.radius(), s.n, 0.0, s.area)
            } else {
                let [a, b] = n.children.map(|c| nodes[c as usize]);
                let (center, radius) = merge_spheres(a.center, a.radius, b.center, b.radius);
                let (axis, cone_angle) = merge_cones(a.axis, a.cone_angle, b.axis, b.cone_angle);
                (center, radius, axis, cone_angle, a.area + b.area)
            };
            let node = &mut nodes[i];
            node.center = center;
            node.radius = radius;
            node.axis = axis;
            node.cone_angle = cone_angle;
            node.area = area;
        }
        SurfelTree { nodes, order }
    }

    /// Number of levels (the deepest leaf's level + 1).
    pub fn depth(&self) -> u32 {
        self.nodes.last().map_or(0, |n| n.level + 1)
    }
}

fn placeholder(level: u32, parent: u32, first: u32, count: u32) -> Node {
    Node {
        center: Vec3::ZERO,
        radius: 0.0,
        axis: Vec3::Z,
        cone_angle: 0.0,
        area: 0.0,
        level,
        parent,
        children: [NONE; 2],
        first,
        count,
    }
}

/// Reorder `range` so its lower half holds the surfels below the median along the longest axis
/// of their centres' bounds (ties broken by index, so the split is deterministic).
fn split_at_median(range: &mut [u32], surfels: &[Surfel]) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for &i in range.iter() {
        lo = lo.min(surfels[i as usize].p);
        hi = hi.max(surfels[i as usize].p);
    }
    let axis = (hi - lo).max_position();
    let half = range.len() / 2;
    range.select_nth_unstable_by(half, |&a, &b| {
        let (pa, pb) = (surfels[a as usize].p[axis], surfels[b as usize].p[axis]);
        pa.total_cmp(&pb).then(a.cmp(&b))
    });
}

/// The smallest sphere enclosing two spheres.
fn merge_spheres(ca: Vec3, ra: f32, cb: Vec3, rb: f32) -> (Vec3, f32) {
    let d = cb.distance(ca);
    if d + rb <= ra {
        return (ca, ra);
    }
    if d + ra <= rb {
        return (cb, rb);
    }
    let r = 0.5 * (d + ra + rb);
    let center = ca + (cb - ca) * ((r - ra) / d);
    // Rounding can leave a child's far point a few ulps outside: pad by a relative epsilon.
    (center, r * (1.0 + 4.0 * f32::EPSILON))
}

/// The smallest cone (axis, half-angle) containing two cones.
fn merge_cones(a: Vec3, theta_a: f32, b: Vec3, theta_b: f32) -> (Vec3, f32) {
    use std::f32::consts::PI;
    // atan2 rather than acos: acos loses half the digits for nearly parallel normals.
    let between = a.cross(b).length().atan2(a.dot(b));
    if between + theta_b <= theta_a {
        return (a, theta_a);
    }
    if between + theta_a <= theta_b {
        return (b, theta_b);
    }
    let theta = 0.5 * (theta_a + between + theta_b);
    let Some(ortho) = (b - a * a.dot(b)).try_normalize().filter(|_| theta < PI) else {
        // Opposite axes or a cone past the whole sphere.
        return (a, PI);
    };
    // Rotate a towards b by (theta − theta_a).
    let r = theta - theta_a;
    let axis = (a * r.cos() + ortho * r.sin()).normalize();
    // Pad for the rounding of the rotation, so every normal below stays inside.
    (axis, (theta + 8.0 * f32::EPSILON).min(PI))
}

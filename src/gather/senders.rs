//! The cache as a gather sees it: the surfel tree with, for every node, the radiance it sends
//! towards a receiver and the solid angle it covers there (docs/method.md §2.3, §6.5; docs/design.md §5.5).
//!
//! A node seen from afar along ω (from the node towards the receiver) has radiant intensity
//! I(ω) and projected area P(ω), so it covers P(ω)/d² and has radiance I(ω)/P(ω). Nodes below
//! the split level store only details; their G is rebuilt once here, top-down
//! (G(child) = G(parent)/2 ± H(parent), docs/method.md §6.5), so that a lookup is one sparse evaluation.
//! A leaf is its surfel: its radiance and its exact projected area A|n·ω|.
//!
//! The final render lights emitters directly, so the gather must see only reflected light:
//! every node's emitted intensity E(ω) is rebuilt exactly as the bake built it into I, and
//! subtracted (emitting surfels still occlude). That is why this module reads the surfels'
//! `intensity_map` (the one the bake's coding sums up the tree), so that E is I's emission bit
//! for bit.

use super::lookup::Lookup;
use super::microbuffer::Sender;
use super::nearest::NearestSurfel;
use crate::cache::store::{
    BakedCache, NodeRecord, SurfelRecord, BACK_SIDED, CLOSED, NO_MAP, SOLID,
};
use crate::cache::CacheError;
use crate::haar::point_map::texel_index;
use crate::haar::sphere_map::MAX_TABLE_LEVELS;
use crate::haar::{
    direction_to_square, square_to_direction, texel_at, texel_directions, Coefficient, Haar2d,
    PointMap, SparseHaar,
};
use crate::spectrum::Rgb;
use crate::surfels::radiance::{intensity_map, SurfelRadiance};
use crate::surfels::tree::{Node, NONE};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// Nodes whose normals lie within this angle (radians) of their axis are flat enough to
/// have a plane, which tells the surface they lie on from occluders (30°).
pub(crate) const FLAT_CONE: f32 = std::f32::consts::FRAC_PI_6;

/// One node of the tree as a traversal tests it, in one cache line: its bounds, normal cone
/// and children, what it sums from the surfels below that every visit reads, and where its
/// projected-area map lies. A cut visits about a thousand nodes of a tree of 10⁵, nearly every
/// one a cache miss: with the whole record (136 bytes, three lines) and its projected-area map
/// behind two more pointers, the first load of a node and of its map were a third of the
/// traversal's own time (perf, cbox-diffuse at 512²). What a splat reads once is in
/// [`NodeDetail`].
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct SenderNode {
    /// Centre of the bounding sphere.
    pub center: Vec3,
    /// Radius of a sphere enclosing every surfel disc below.
    pub radius: f32,
    /// The normal cone's axis (the tree's `Node::axis`).
    pub axis: Vec3,
    /// sin(cone_angle), or above 1 for cones wider than a hemisphere.
    pub sin_cone: f32,
    /// Σ A n over the surfels below: for directions where every normal below faces the same
    /// way, the projected area is exactly |N·ω|.
    pub area_normal: Vec3,
    /// The closed mesh ([`CLOSED`]) every surfel below lies on, or [`NONE`].
    pub closed_mesh: u32,
    /// `[left, right]`, or `[NONE, NONE]` for a leaf.
    pub children: [u32; 2],
    /// A leaf's surfel; an inner node's projected-area map in [`Senders`] (the first of its
    /// texels, or with [`node_flags::PROJECTED_APART`] its index among those kept apart).
    item: u32,
    /// [`node_flags`].
    flags: u8,
    /// log2 of the side of the projected-area map's texels (see [`PointMap::Texels`]).
    projected_depth: u8,
    /// The projected-area map's resolution (log2 of its side, [`SparseHaar::levels`]).
    projected_levels: u8,
}

/// The bits of a [`SenderNode`]'s flags ([`SenderNode::has`]), each computed once from what
/// the node's record and surfels say (so every test that reads one decides as the value
/// would).
pub mod node_flags {
    /// Surfels of a solid ([`super::SOLID`]) lie below: their inward light is not in the
    /// node's maps, so a receiver on a solid must reach them as leaves.
    pub const SOLID: u8 = 1;
    /// Surfels below send light from their back into the maps ([`super::BACK_SIDED`]).
    pub const BACK_SIDED: u8 = 1 << 1;
    /// The normal cone is within [`super::PLANAR_CONE`]: the node may be a plane.
    pub const PLANAR: u8 = 1 << 2;
    /// The normal cone is narrower than a hemisphere.
    pub const NARROW: u8 = 1 << 3;
    /// The normal cone is within the gather's flat cone (`FLAT_CONE`): the node has a plane.
    pub const FLAT: u8 = 1 << 4;
    /// No surfel below has directional radiance (all are diffuse).
    pub const DIFFUSE: u8 = 1 << 5;
    /// More than half the area below has directional (glossy) radiance.
    pub const MOSTLY_DIRECTIONAL: u8 = 1 << 6;
    /// The projected-area map is kept apart (as a tree, where its texels would take more
    /// memory), not among the texels.
    pub const PROJECTED_APART: u8 = 1 << 7;
}

impl SenderNode {
    /// Whether the node is a leaf (its surfel alone).
    pub fn is_leaf(&self) -> bool {
        self.children[0] == NONE
    }

    /// The surfel of a leaf ([`NONE`] for inner nodes).
    pub fn surfel(&self) -> u32 {
        if self.is_leaf() {
            self.item
        } else {
            NONE
        }
    }

    /// Whether flag `f` ([`node_flags`]) is set.
    pub fn has(&self, f: u8) -> bool {
        self.flags & f != 0
    }
}

/// What a node sums from the surfels below that only a splat or a plane test reads (see
/// [`SenderNode`]).
#[derive(Clone, Copy, Debug)]
pub struct NodeDetail {
    /// Per colour channel, Σ A L n over the (diffuse) surfels below, L their reflected
    /// radiance: where every surfel below faces ω, the node's radiance along ω is exactly
    /// (S·ω)/(N·ω), without the intensity map's texels (see [`Senders::seen`]).
    pub radiance_normal: [Vec3; 3],
    /// For a node whose normals agree to [`PLANAR_CONE`]: the range of `axis · x` over its
    /// surfels' centres (a slab that may be a little wider than they are); otherwise
    /// unbounded. A thin slab is a plane (see [`Senders::holds_plane_of`]).
    pub slab: [f32; 2],
}

/// A node as the tree's records and the surfels below give it, while [`Senders`] is built.
#[derive(Clone, Copy, Debug)]
struct NodeSummary {
    /// The node as the tree built it (bounds, normal cone, children).
    node: Node,
    /// The surfel of a leaf ([`NONE`] for inner nodes).
    surfel: u32,
    /// sin(cone_angle), or above 1 for cones wider than a hemisphere.
    sin_cone: f32,
    /// What it sums from the surfels below; its slab is unbounded unless its normals agree
    /// to [`PLANAR_CONE`] (see [`NodeDetail::slab`]).
    below: Below,
}

impl NodeSummary {
    fn is_leaf(&self) -> bool {
        self.node.is_leaf()
    }
}

/// The widest normal cone (radians) of a node that may be planar: flat to rounding.
pub const PLANAR_CONE: f32 = 1e-3;

/// The thickest slab, in node radii, that counts as a plane (rounding; an emitter hung 1 cm
/// under a ceiling is 1e-2 of a node of both 1 m wide, and must stay apart).
pub const PLANAR_SLAB: f32 = 1e-3;

/// The tree of senders.
pub struct Senders {
    /// The tree's nodes, breadth-first from the root.
    pub nodes: Vec<SenderNode>,
    /// Per node, what a splat reads of it.
    details: Vec<NodeDetail>,
    /// Per mesh: whether it bounds a solid.
    solid_meshes: Vec<bool>,
    /// Per closed mesh: the bounds of its surfels' discs.
    closed_boxes: Vec<Option<[Vec3; 2]>>,
    /// The surfels, as the cache records them.
    pub surfels: Vec<SurfelRecord>,
    /// Per inner node: G of the radiant intensity (leaves: empty).
    intensity: Vec<PointMap<Rgb>>,
    /// The inner nodes' G of the projected area kept as texels ([`PointMap::Texels`]), one
    /// node's after another, found from the node ([`SenderNode`]): one load, not three.
    projected_texels: Vec<f32>,
    /// The rest of the inner nodes' projected-area maps ([`node_flags::PROJECTED_APART`]).
    projected_apart: Vec<PointMap<f32>>,
    /// Per node with emitting surfels below: their emitted intensity.
    emitted: Vec<Option<PointMap<Rgb>>>,
    /// Per surfel with a directional map: the map (outgoing radiance over the sphere).
    maps: Vec<Option<PointMap<Rgb>>>,
    /// Whether [`Senders::seen`] evaluates the radiance it looks up (see
    /// [`Senders::geometry_of`]).
    evaluates: bool,
    /// The surfels by mesh, for [`Senders::lookup_at`]; built on its first call.
    nearest: OnceLock<NearestSurfel>,
}

/// What a receiver sees of one node.
#[derive(Clone, Copy, Debug)]
pub struct Seen {
    /// Radiance towards the receiver (reflected light only; zero from
    /// [`Senders::geometry_of`] senders).
    pub radiance: Rgb,
    /// Projected area towards the receiver (the node covers `projected / d²` steradians).
    pub projected: f32,
    /// Where the radiance is read.
    pub lookup: Lookup,
}

/// What a node keeps of the surfels below it, summed bottom-up (see [`SenderNode`]).
#[derive(Clone, Copy, Debug)]
struct Below {
    area_normal: Vec3,
    directional_area: f32,
    radiance_normal: [Vec3; 3],
    solid: bool,
    back_sided: bool,
    closed_mesh: u32,
    slab: [f32; 2],
}

impl Default for Below {
    fn default() -> Self {
        Below {
            area_normal: Vec3::ZERO,
            directional_area: 0.0,
            radiance_normal: [Vec3::ZERO; 3],
            solid: false,
            back_sided: false,
            closed_mesh: NONE,
            slab: [f32::INFINITY, f32::NEG_INFINITY],
        }
    }
}

impl Below {
    /// A leaf's surfel `s` (`leaf` its node).
    fn of_surfel(s: &SurfelRecord, leaf: NodeSummary) -> Below {
        let area_normal = Vec3::from(s.n) * s.area;
        let reflected = (Vec3::from(s.rgb) - Vec3::from(s.emitted)).max(Vec3::ZERO);
        let h = leaf.node.axis.dot(Vec3::from(s.p));
        Below {
            area_normal,
            directional_area: if s.map != NO_MAP { s.area } else { 0.0 },
            radiance_normal: [reflected.x, reflected.y, reflected.z].map(|l| area_normal * l),
            solid: s.flags & SOLID != 0,
            back_sided: s.flags & BACK_SIDED != 0,
            closed_mesh: if s.flags & CLOSED != 0 { s.mesh } else { NONE },
            slab: [h, h],
        }
    }

    /// Child `ch` as its `parent` sums it: its slab along the parent's axis is its own,
    /// widened by how far its axis turns from the parent's over its radius.
    fn of_child(ch: &NodeSummary, parent: NodeSummary) -> Below {
        let shift = parent.node.axis.dot(ch.node.center) - ch.node.axis.dot(ch.node.center);
        let widen = (parent.node.axis - ch.node.axis).length() * ch.node.radius;
        let slab = ch.below.slab;
        Below {
            slab: [slab[0] + shift - widen, slab[1] + shift + widen],
            ..ch.below
        }
    }

    fn join(a: Below, b: Below) -> Below {
        let [ar, ag, ab] = a.radiance_normal;
        let [br, bg, bb] = b.radiance_normal;
        Below {
            area_normal: a.area_normal + b.area_normal,
            directional_area: a.directional_area + b.directional_area,
            radiance_normal: [ar + br, ag + bg, ab + bb],
            solid: a.solid || b.solid,
            back_sided: a.back_sided || b.back_sided,
            closed_mesh: if a.closed_mesh == b.closed_mesh {
                a.closed_mesh
            } else {
                NONE
            },
            slab: [a.slab[0].min(b.slab[0]), a.slab[1].max(b.slab[1])],
        }
    }
}

impl Senders {
    /// Load the tree of `cache`, rebuilding every inner node's G.
    pub fn from_cache(cache: &BakedCache) -> Result<Senders, CacheError> {
        let path = &cache.cache.path;
        let records = &cache.nodes;
        let levels = cache.map_resolution().map_or(3, |r| r.max(1).ilog2());
        let at = |j: u32| &records[j as usize];
        let intensity = rebuild(
            path,
            records,
            |j| decoded(cache, at(j).g),
            |j| decoded(cache, at(j).h),
        )?;
        let projected = rebuild(
            path,
            records,
            |j| decoded(cache, at(j).area_g),
            |j| decoded(cache, at(j).area_h),
        )?;
        let maps: Vec<Option<SparseHaar<Rgb>>> = cache
            .surfels
            .par_iter()
            .map(|s| decoded(cache, s.map))
            .collect::<Result<_, _>>()?;
        let nodes = sender_nodes(path, records, &cache.surfels, &cache.order)?;
        let emitted = emitted_intensities(records, &nodes, &cache.surfels, &maps, levels);
        Ok(Senders::assemble(
            nodes,
            cache.surfels.clone(),
            (intensity, projected),
            emitted,
            maps,
        ))
    }

    /// The geometry of a bake still in memory, for a gather that only records where radiance
    /// is read (the bake's transport, which evaluates the lookups against each bounce's light
    /// itself: [`Senders::seen`] and the splats it feeds carry zero radiance): its records
    /// ([`crate::bake::store::records_of`]), the stored projected-area maps of each node (G,
    /// H) and its surfels' maps (their resolution says where a lookup reads). `path` names
    /// the bake in errors.
    pub fn geometry_of(
        path: &Path,
        records: &[NodeRecord],
        surfels: Vec<SurfelRecord>,
        order: &[u32],
        projected: [&(dyn Fn(u32) -> Option<SparseHaar<f32>> + Sync); 2],
        maps: Vec<Option<SparseHaar<Rgb>>>,
    ) -> Result<Senders, CacheError> {
        let [g, h] = projected;
        let projected = rebuild(path, records, |j| Ok(g(j)), |j| Ok(h(j)))?;
        let nodes = sender_nodes(path, records, &surfels, order)?;
        let none = SparseHaar::compress(&Haar2d::forward(&[Rgb::ZERO], 1), 0.0);
        let mut senders = Senders::assemble(
            nodes,
            surfels,
            (vec![none; records.len()], projected),
            vec![None; records.len()],
            maps,
        );
        senders.evaluates = false;
        Ok(senders)
    }

    /// The senders of `nodes` (see [`sender_nodes`]) with their maps.
    fn assemble(
        mut nodes: Vec<NodeSummary>,
        surfels: Vec<SurfelRecord>,
        (intensity, projected): (Vec<SparseHaar<Rgb>>, Vec<SparseHaar<f32>>),
        emitted: Vec<Option<SparseHaar<Rgb>>>,
        maps: Vec<Option<SparseHaar<Rgb>>>,
    ) -> Senders {
        // Children come after their parents: what a node keeps of the surfels below is summed
        // bottom-up.
        for j in (0..nodes.len()).rev() {
            let sender = nodes[j];
            let below = if sender.is_leaf() {
                Below::of_surfel(&surfels[sender.surfel as usize], sender)
            } else {
                sender
                    .node
                    .children
                    .iter()
                    .filter(|&&c| (c as usize) < nodes.len() && c as usize > j)
                    .map(|&c| Below::of_child(&nodes[c as usize], sender))
                    .reduce(Below::join)
                    .unwrap_or_default()
            };
            let slab = if sender.node.cone_angle <= PLANAR_CONE {
                below.slab
            } else {
                sender.below.slab
            };
            nodes[j].below = Below { slab, ..below };
        }
        let mut solid_meshes = Vec::new();
        let mut closed_boxes: Vec<Option<[Vec3; 2]>> = Vec::new();
        for s in &surfels {
            let m = s.mesh as usize;
            if m >= solid_meshes.len() {
                solid_meshes.resize(m + 1, false);
                closed_boxes.resize(m + 1, None);
            }
            solid_meshes[m] |= s.flags & SOLID != 0;
            if s.flags & CLOSED != 0 {
                // The surfels' discs: their centres lie on the mesh, their rims around it.
                let r = Vec3::splat((s.area / std::f32::consts::PI).sqrt());
                let p = Vec3::from(s.p);
                let [lo, hi] = closed_boxes[m].unwrap_or([p, p]);
                closed_boxes[m] = Some([lo.min(p - r), hi.max(p + r)]);
            }
        }
        let (hot, details, projected_texels, projected_apart) =
            split_nodes(&nodes, point_maps(projected));
        Senders {
            solid_meshes,
            closed_boxes,
            nodes: hot,
            details,
            surfels,
            intensity: point_maps(intensity),
            projected_texels,
            projected_apart,
            emitted: optional_point_maps(emitted),
            maps: optional_point_maps(maps),
            evaluates: true,
            nearest: OnceLock::new(),
        }
    }

    /// What a receiver on mesh `receiver_mesh` sees of node `j` along the unit direction `w`
    /// from the node towards it; with `back_hidden` (see [`Senders::back_hidden`]), only the
    /// node's front faces.
    pub fn seen(&self, j: u32, w: Vec3, receiver_mesh: u32, back_hidden: bool) -> Seen {
        let (lookup, projected) = self.seen_lookup(j, w, receiver_mesh, back_hidden);
        Seen {
            radiance: self.evaluated(lookup),
            projected,
            lookup,
        }
    }

    /// Where [`Senders::seen`] reads node `j`'s radiance along `w`, and its projected area:
    /// geometry alone (see [`Lookup`]).
    pub(crate) fn seen_lookup(
        &self,
        j: u32,
        w: Vec3,
        receiver_mesh: u32,
        back_hidden: bool,
    ) -> (Lookup, f32) {
        let sender = &self.nodes[j as usize];
        if sender.is_leaf() {
            let s = &self.surfels[sender.item as usize];
            let cos = Vec3::from(s.n).dot(w);
            if back_hidden && cos < 0.0 {
                return (Lookup::Nothing, 0.0);
            }
            return (
                self.surfel_lookup(sender.item, w, cos, receiver_mesh),
                s.area * cos.abs(),
            );
        }
        // Every surfel below diffuse and facing ω: Σ A L (n·ω) / Σ A (n·ω), exactly. The
        // maps' texels (25° wide at 8²) straddle a wall's edge-on band there and took up to
        // 8 % of a closed room's light (tests/furnace.rs).
        let facing = sender.area_normal.dot(w);
        if sender.has(node_flags::DIFFUSE) && facing > 0.0 && sender.axis.dot(w) > sender.sin_cone {
            return (
                Lookup::NodeNormal {
                    node: j,
                    u: w / facing,
                },
                facing,
            );
        }
        let levels = u32::from(sender.projected_levels);
        let p = direction_to_square(w);
        let projected = self
            .exact_projected(sender, w)
            .unwrap_or_else(|| self.projected_at(sender, p).max(0.0));
        let n_dot = sender.area_normal.dot(w);
        let (front, back) = (0.5 * (projected + n_dot), 0.5 * (projected - n_dot));
        // I's cosine and P are sampled at the centres of P's texels (see `intensity_map`);
        // where the normals allow, P at the centre is exact.
        let intensity = |point: Vec2, denominator: f32| Lookup::NodeMap {
            node: j,
            point,
            scale: 1.0 / denominator,
        };
        let area_at = |p: Vec2, centre: Vec3| {
            self.exact_projected(sender, centre)
                .unwrap_or_else(|| self.projected_at(sender, p).max(0.0))
        };
        if back_hidden && !(front > 0.0) {
            return (Lookup::Nothing, 0.0);
        }
        let centre = texel_centre(p, levels);
        if !sender.has(node_flags::BACK_SIDED) && (front >= back || back_hidden) {
            // Surfels that send light from their front only (all but thin sheets): the
            // radiance is I over the front projected area P⁺ = (P + N·ω)/2 (cos⁺ = (|cos| +
            // cos)/2) at the texel's centre, where I was sampled (I/P lost up to 8 % where
            // the texel straddles an edge-on band, tests/furnace.rs). Where the centre sees
            // much less of the front than ω does (a flat node seen within a texel of edge-on,
            // whose centre lies behind it), the texel tilted towards the front is read.
            let front_at = |p: Vec2, c: Vec3| 0.5 * (area_at(p, c) + sender.area_normal.dot(c));
            let mut texel = (p, front_at(p, centre));
            if !(texel.1 >= 0.5 * front) && sender.axis.dot(w) > 0.0 && sender.sin_cone < 1.0 {
                let (q, c) = texel_on_side(w, sender.axis, sender.sin_cone, levels);
                texel = (q, front_at(q, c));
            }
            let (q, front_texel) = texel;
            let conditioned = front_texel > 0.0 && front_texel >= 0.5 * front;
            // With the back hidden only the front shows, so where the texel's P⁺ is
            // ill-conditioned the front area along ω itself divides I.
            if conditioned || back_hidden {
                let (q, denominator) = if conditioned {
                    (q, front_texel)
                } else {
                    (p, front)
                };
                return (intensity(q, denominator), front.max(0.0));
            }
        }
        // The node covers what faces the receiver, or its back where that is larger (a sheet
        // seen from behind, whose back still occludes; for a solid the back lies behind the
        // front). Radiance from the two maps at the same texel (their quantisation cancels),
        // unless the texel straddles the node's edge-on band and its P is far below the
        // exact one; the solid angle from the exact projected area where it is known.
        let at_centre = area_at(p, centre);
        let denominator = if at_centre >= 0.5 * projected {
            at_centre
        } else {
            projected
        };
        let lookup = if denominator > 0.0 {
            intensity(p, denominator)
        } else {
            Lookup::Nothing
        };
        (lookup, projected)
    }

    /// The radiance at `lookup` in the light this tree was loaded with (reflected light only:
    /// emission is subtracted).
    pub fn radiance_of(&self, lookup: Lookup) -> Rgb {
        match lookup {
            Lookup::Nothing => Rgb::ZERO,
            Lookup::SurfelRgb { surfel } => {
                let s = &self.surfels[surfel as usize];
                (Vec3::from(s.rgb) - Vec3::from(s.emitted)).max(Rgb::ZERO)
            }
            Lookup::SurfelMap {
                surfel,
                point,
                front,
            } => {
                let s = &self.surfels[surfel as usize];
                let emitted = if front {
                    Vec3::from(s.emitted)
                } else {
                    Rgb::ZERO
                };
                self.maps[surfel as usize].as_ref().map_or(Rgb::ZERO, |m| {
                    (m.eval(point.x, point.y) - emitted).max(Rgb::ZERO)
                })
            }
            Lookup::NodeNormal { node, u } => {
                let [r, g, b] = self.details[node as usize].radiance_normal;
                Vec3::new(r.dot(u), g.dot(u), b.dot(u)).max(Rgb::ZERO)
            }
            Lookup::NodeMap { node, point, scale } => {
                let mut i = self.intensity[node as usize].eval(point.x, point.y);
                if let Some(e) = &self.emitted[node as usize] {
                    i -= e.eval(point.x, point.y);
                }
                (i * scale).max(Rgb::ZERO)
            }
        }
    }

    /// Whether node `j`'s back faces are hidden from every receiver within `margin` of `p`
    /// (not on `mesh`): all its surfels lie on one closed mesh, and the receivers lie outside
    /// that mesh's bounds. A closed surface seen from outside shows only its front faces; its
    /// back faces, drawn as black occluders, filled the gaps between the front faces' splats
    /// and took 5–12 % of the light a Cornell box's walls gathered.
    pub fn back_hidden(&self, j: u32, p: Vec3, margin: f32, mesh: u32) -> bool {
        let sender = &self.nodes[j as usize];
        let m = sender.closed_mesh;
        if m == NONE || m == mesh || sender.has(node_flags::BACK_SIDED) {
            return false;
        }
        self.closed_boxes
            .get(m as usize)
            .copied()
            .flatten()
            .is_some_and(|[lo, hi]| {
                (p + Vec3::splat(margin)).cmplt(lo).any()
                    || (p - Vec3::splat(margin)).cmpgt(hi).any()
            })
    }

    /// Whether every surfel of node `j` faces away from every point within `margin` of `p`:
    /// for n within the cone of half-angle θ around the axis a, and x in the bounding sphere,
    /// n·(x − p) ≥ (a·v) cos θ − |a × v| sin θ − r with v = centre − p.
    pub fn faces_away(&self, j: u32, p: Vec3, margin: f32) -> bool {
        let sender = &self.nodes[j as usize];
        let v = sender.center - p;
        // cos θ from sin θ: the cone is narrower than a hemisphere there.
        sender.has(node_flags::NARROW)
            && sender.axis.dot(v) * (1.0 - sender.sin_cone * sender.sin_cone).max(0.0).sqrt()
                - sender.axis.cross(v).length() * sender.sin_cone
                > sender.radius + margin
    }

    /// Whether a receiver on `mesh` must reach the surfels of a solid below node `j` one by
    /// one: it lies on a solid itself, whose inward light only leaves carry (the light inside
    /// a glass sphere, on its way to a caustic). A node wholly on another closed mesh needs
    /// no leaves: a solid's inward light reaches only its own surface, so the node's maps,
    /// its outward light, are all the receiver sees of it (two glass objects would otherwise
    /// reach each other's every surfel).
    pub fn needs_leaves(&self, j: u32, mesh: u32) -> bool {
        let sender = &self.nodes[j as usize];
        sender.has(node_flags::SOLID)
            && self.solid_meshes.get(mesh as usize) == Some(&true)
            && (sender.closed_mesh == NONE || sender.closed_mesh == mesh)
    }

    /// Where the cache's radiance along `w` leaves the point `q` of mesh `mesh`, whose
    /// geometric normal is `ng`, towards a receiver on mesh `receiver_mesh`: the surfel of
    /// that mesh nearest `q` among those facing `ng`'s way (within 60°), read as a gather reads
    /// a leaf ([`Senders::surfel_lookup`]). `None` where the mesh has no such surfel. (What a
    /// ray from a receiver hits: the gaps its buffer's splats leave, a path-traced gather's
    /// secondary hits.)
    pub fn lookup_at(
        &self,
        q: Vec3,
        mesh: u32,
        ng: Vec3,
        w: Vec3,
        receiver_mesh: u32,
    ) -> Option<Lookup> {
        let i = self.surfel_at(q, mesh, ng, None)?;
        Some(self.surfel_read(i, w, receiver_mesh))
    }

    /// The surfel that [`Senders::lookup_at`] reads at `q` (mesh `mesh`, normal `ng`): the
    /// nearest of that mesh facing `ng`'s way (within 60°). `near`, a surfel found for a
    /// point near `q` (a ray beside this one), starts the search: the answer is the same,
    /// found sooner.
    pub fn surfel_at(&self, q: Vec3, mesh: u32, ng: Vec3, near: Option<u32>) -> Option<u32> {
        let nearest = self.nearest.get_or_init(|| {
            let positions: Vec<Vec3> = self.surfels.iter().map(|s| Vec3::from(s.p)).collect();
            let normals: Vec<Vec3> = self.surfels.iter().map(|s| Vec3::from(s.n)).collect();
            let meshes: Vec<u32> = self.surfels.iter().map(|s| s.mesh).collect();
            NearestSurfel::new(&positions, &normals, &meshes)
        });
        let seed = near
            .and_then(|i| self.surfels.get(i as usize).map(|s| (i, s)))
            .filter(|(_, s)| s.mesh == mesh)
            .map(|(i, s)| (i, Vec3::from(s.p), Vec3::from(s.n)));
        nearest.nearest(q, mesh, |n| n.dot(ng) > 0.5, seed)
    }

    /// Surfel `i`'s light along `w` towards a receiver on mesh `receiver_mesh`, as a gather
    /// reads a leaf ([`Senders::surfel_lookup`]).
    pub fn surfel_read(&self, i: u32, w: Vec3, receiver_mesh: u32) -> Lookup {
        let cos = Vec3::from(self.surfels[i as usize].n).dot(w);
        self.surfel_lookup(i, w, cos, receiver_mesh)
    }

    /// Node `j` as a microbuffer records it, at `offset` from the receiver, seen as `seen`.
    pub fn sender(&self, j: u32, offset: Vec3, seen: Seen) -> Sender {
        let sender = &self.nodes[j as usize];
        let (radius, normal) = if sender.is_leaf() {
            let s = &self.surfels[sender.item as usize];
            ((s.area / std::f32::consts::PI).sqrt(), Vec3::from(s.n))
        } else if sender.has(node_flags::FLAT) {
            (sender.radius, sender.axis)
        } else {
            (sender.radius, Vec3::ZERO)
        };
        Sender {
            offset,
            radius,
            normal,
            radiance: seen.radiance,
            lookup: seen.lookup,
        }
    }

    /// The projected area of inner node `j` along `w` (cheaper than [`Senders::seen`]: the
    /// traversal tests it before it needs the radiance).
    pub(crate) fn projected_area(&self, j: u32, w: Vec3) -> f32 {
        let sender = &self.nodes[j as usize];
        self.exact_projected(sender, w)
            .unwrap_or_else(|| self.projected_at(sender, direction_to_square(w)).max(0.0))
    }

    /// G of inner node `sender`'s projected area at the point `p` of the unit square (zero
    /// for a leaf, whose map is empty).
    #[inline]
    fn projected_at(&self, sender: &SenderNode, p: Vec2) -> f32 {
        if sender.is_leaf() {
            0.0
        } else if sender.has(node_flags::PROJECTED_APART) {
            self.projected_apart[sender.item as usize].eval(p.x, p.y)
        } else {
            let at = texel_index(u32::from(sender.projected_depth), p.x, p.y);
            self.projected_texels[sender.item as usize + at]
        }
    }

    /// Whether every surfel below node `j` lies in the plane through `p` with normal `n`,
    /// facing its way, to within [`PLANAR_SLAB`] of the node's radius: a receiver at `p` on
    /// that plane sees the node edge-on (it sends nothing there and hides nothing).
    pub fn holds_plane_of(&self, j: u32, p: Vec3, n: Vec3) -> bool {
        let sender = &self.nodes[j as usize];
        if !sender.has(node_flags::PLANAR) || !(sender.axis.dot(n) > 0.0) {
            return false;
        }
        let slab = self.details[j as usize].slab;
        let tolerance = PLANAR_SLAB * sender.radius;
        let h = sender.axis.dot(p);
        slab[1] - slab[0] <= tolerance && h >= slab[0] - tolerance && h <= slab[1] + tolerance
    }

    /// Σ A |n·ω| = |N·ω| when every normal below lies on one side of the plane ⊥ ω, i.e.
    /// when ω is more than the cone's angle away from the plane ⊥ the axis. The 8 × 8 map's
    /// texels (25° wide) would otherwise bias the coverage by a few percent.
    fn exact_projected(&self, sender: &SenderNode, w: Vec3) -> Option<f32> {
        (sender.axis.dot(w).abs() > sender.sin_cone).then(|| sender.area_normal.dot(w).abs())
    }

    /// Emitted radiance leaving node `j` along `w` (front faces only): a leaf's surfel's
    /// emission, an inner node's emitted intensity over its projected area.
    pub(crate) fn emitted_radiance(&self, j: u32, w: Vec3) -> Rgb {
        let sender = &self.nodes[j as usize];
        if sender.is_leaf() {
            let s = &self.surfels[sender.item as usize];
            return if Vec3::from(s.n).dot(w) > 0.0 {
                Vec3::from(s.emitted)
            } else {
                Rgb::ZERO
            };
        }
        let Some(e) = &self.emitted[j as usize] else {
            return Rgb::ZERO;
        };
        let area = self.projected_area(j, w);
        if area > 0.0 {
            let p = direction_to_square(w);
            (e.eval(p.x, p.y) / area).max(Rgb::ZERO)
        } else {
            Rgb::ZERO
        }
    }

    /// [`Senders::radiance_of`], or zero from [`Senders::geometry_of`] senders: what a
    /// splat carries.
    pub fn evaluated(&self, lookup: Lookup) -> Rgb {
        if self.evaluates {
            self.radiance_of(lookup)
        } else {
            Rgb::ZERO
        }
    }

    /// Where surfel `i`'s reflected radiance along `w` (`cos` = n·w) towards a receiver on mesh
    /// `receiver_mesh` is read (a solid's inward light reaches only its own surface).
    pub fn surfel_lookup(&self, i: u32, w: Vec3, cos: f32, receiver_mesh: u32) -> Lookup {
        let s = &self.surfels[i as usize];
        if cos < 0.0 && s.flags & SOLID != 0 && s.mesh != receiver_mesh {
            return Lookup::Nothing;
        }
        match &self.maps[i as usize] {
            Some(m) => {
                let side = Vec3::from(s.n) * cos.signum();
                let (point, _) = texel_on_side(w, side, 0.0, m.levels());
                Lookup::SurfelMap {
                    surfel: i,
                    point,
                    front: cos > 0.0,
                }
            }
            None if cos > 0.0 => Lookup::SurfelRgb { surfel: i },
            None => Lookup::Nothing,
        }
    }
}

/// The centre of the texel of the `2^levels`-texel sphere map that holds point `p` of its
/// unit square (from the shared table where the resolution has one: the same directions).
fn texel_centre(p: Vec2, levels: u32) -> Vec3 {
    let n = 1u32 << levels;
    let (x, y) = texel_at(p, n);
    if levels <= MAX_TABLE_LEVELS {
        return texel_directions(levels)[(y * n + x) as usize];
    }
    square_to_direction((Vec2::new(x as f32, y as f32) + 0.5) / n as f32)
}

/// Where to read a sphere map of `levels` for direction `w` seen on the side `side` (a unit
/// vector) of a surface, with the texel's centre: `w`'s own texel, unless its centre lies less
/// than `min_cos` towards `side`. A texel straddling the horizon holds the value at its
/// centre, which may be the other side's (nothing, for a one-sided surfel: 3 % of a closed
/// glossy room's leaves were read as black there); then the texel reached by tilting `w`
/// towards `side` by whole texel widths, as far as four.
fn texel_on_side(w: Vec3, side: Vec3, min_cos: f32, levels: u32) -> (Vec2, Vec3) {
    let p = direction_to_square(w);
    let centre = texel_centre(p, levels);
    if side.dot(centre) > min_cos {
        return (p, centre);
    }
    // A texel's width in radians: √(4π) / 2^levels.
    let step = 3.545 / (1u32 << levels) as f32;
    let tangent = (w - side * side.dot(w)).normalize_or_zero();
    let elevation = side.dot(w).clamp(-1.0, 1.0).asin();
    for k in 1..=4 {
        let e = (elevation + k as f32 * step).min(std::f32::consts::FRAC_PI_2);
        let tilted = tangent * e.cos() + side * e.sin();
        let q = direction_to_square(tilted);
        let c = texel_centre(q, levels);
        if side.dot(c) > min_cos {
            return (q, c);
        }
    }
    (p, centre)
}

/// The tree's nodes from their records, without what is summed from the surfels below
/// (see [`Senders::assemble`]); refused if a leaf names no surfel.
fn sender_nodes(
    path: &Path,
    records: &[NodeRecord],
    surfels: &[SurfelRecord],
    order: &[u32],
) -> Result<Vec<NodeSummary>, CacheError> {
    let nodes: Vec<NodeSummary> = records
        .iter()
        .map(|r| NodeSummary {
            node: r.node,
            surfel: if r.node.is_leaf() {
                order.get(r.node.first as usize).copied().unwrap_or(NONE)
            } else {
                NONE
            },
            sin_cone: if r.node.cone_angle < std::f32::consts::FRAC_PI_2 {
                r.node.cone_angle.sin()
            } else {
                2.0
            },
            below: Below {
                slab: [f32::NEG_INFINITY, f32::INFINITY],
                ..Below::default()
            },
        })
        .collect();
    if nodes
        .iter()
        .any(|n| n.is_leaf() && n.surfel as usize >= surfels.len())
    {
        return Err(CacheError::Malformed {
            path: path.to_path_buf(),
            what: "a leaf has no surfel".into(),
        });
    }
    Ok(nodes)
}

/// The nodes as traversal reads them ([`SenderNode`]) and what a splat reads ([`NodeDetail`]),
/// with the inner nodes' projected-area maps (`projected`, per node) laid out for them: those
/// kept as texels one after another, the rest apart.
fn split_nodes(
    nodes: &[NodeSummary],
    projected: Vec<PointMap<f32>>,
) -> (
    Vec<SenderNode>,
    Vec<NodeDetail>,
    Vec<f32>,
    Vec<PointMap<f32>>,
) {
    use node_flags as f;
    let mut texels = Vec::new();
    let mut apart = Vec::new();
    let hot = nodes
        .iter()
        .zip(projected)
        .map(|(n, map)| {
            let (cone, below) = (n.node.cone_angle, &n.below);
            // The fraction of the area below whose radiance is directional (non-diffuse).
            let directional = if n.node.area > 0.0 {
                (below.directional_area / n.node.area).min(1.0)
            } else {
                0.0
            };
            let mut flags = [
                (below.solid, f::SOLID),
                (below.back_sided, f::BACK_SIDED),
                (cone <= PLANAR_CONE, f::PLANAR),
                (cone < std::f32::consts::FRAC_PI_2, f::NARROW),
                (cone < FLAT_CONE, f::FLAT),
                (directional == 0.0, f::DIFFUSE),
                (directional > 0.5, f::MOSTLY_DIRECTIONAL),
            ]
            .into_iter()
            .filter(|&(on, _)| on)
            .fold(0, |flags, (_, bit)| flags | bit);
            let levels = map.levels() as u8;
            let (item, depth) = match map {
                _ if n.is_leaf() => (n.surfel, 0),
                PointMap::Texels {
                    depth, texels: t, ..
                } if u32::try_from(texels.len() + t.len()).is_ok() => {
                    let first = texels.len() as u32;
                    texels.extend_from_slice(&t);
                    (first, depth as u8)
                }
                map => {
                    flags |= f::PROJECTED_APART;
                    apart.push(map);
                    (apart.len() as u32 - 1, 0)
                }
            };
            SenderNode {
                center: n.node.center,
                radius: n.node.radius,
                axis: n.node.axis,
                sin_cone: n.sin_cone,
                area_normal: below.area_normal,
                closed_mesh: below.closed_mesh,
                children: n.node.children,
                item,
                flags,
                projected_depth: depth,
                projected_levels: levels,
            }
        })
        .collect();
    let details = nodes
        .iter()
        .map(|n| NodeDetail {
            radiance_normal: n.below.radiance_normal,
            slab: n.below.slab,
        })
        .collect();
    (hot, details, texels, apart)
}

/// `maps` laid out for the gather's point lookups ([`PointMap`]).
fn point_maps<T: Coefficient + Send>(maps: Vec<SparseHaar<T>>) -> Vec<PointMap<T>> {
    maps.into_par_iter().map(PointMap::from).collect()
}

/// [`point_maps`] where some are absent.
fn optional_point_maps<T: Coefficient + Send>(
    maps: Vec<Option<SparseHaar<T>>>,
) -> Vec<Option<PointMap<T>>> {
    maps.into_par_iter()
        .map(|m| m.map(PointMap::from))
        .collect()
}

/// A node's stored map (G or H), decoded; `None` where the node stores none.
type StoredMap<T> = Result<Option<SparseHaar<T>>, CacheError>;

/// Map `index` of `cache`'s pool, or `None` for [`NO_MAP`].
fn decoded<T: Coefficient>(cache: &BakedCache, index: u32) -> StoredMap<T> {
    (index != NO_MAP).then(|| cache.map(index)).transpose()
}

/// Every inner node's G, from the stored G (`g(j)`, at and above the split level) or from the
/// parent's G and H (`h(parent)`, below it). Nodes are breadth-first, so a level depends on the
/// one above. `path` names the bake in errors.
fn rebuild<T: Coefficient + Send + Sync>(
    path: &Path,
    records: &[NodeRecord],
    g: impl Fn(u32) -> StoredMap<T> + Sync,
    h: impl Fn(u32) -> StoredMap<T> + Sync,
) -> Result<Vec<SparseHaar<T>>, CacheError> {
    let bad = |what: &str| CacheError::Malformed {
        path: path.to_path_buf(),
        what: what.into(),
    };
    let empty = || SparseHaar::compress(&Haar2d::forward(&[T::default()], 1), 0.0);
    let mut out: Vec<SparseHaar<T>> = Vec::with_capacity(records.len());
    let mut start = 0;
    while start < records.len() {
        let level = records[start].node.level;
        let end = start
            + records[start..]
                .iter()
                .take_while(|r| r.node.level == level)
                .count();
        let level_maps: Vec<SparseHaar<T>> = records[start..end]
            .par_iter()
            .enumerate()
            .map(|(i, r)| {
                let j = (start + i) as u32;
                if r.node.children[0] == NONE {
                    return Ok(empty());
                }
                if let Some(g) = g(j)? {
                    return Ok(g);
                }
                let parent = r.node.parent as usize;
                if parent >= start {
                    return Err(bad("a node's parent does not come before it"));
                }
                let Some(h) = h(parent as u32)? else {
                    return Err(bad(
                        "a node below the split level has no detail to rebuild it",
                    ));
                };
                let sign = if records[parent].node.children[0] == j {
                    1.0
                } else {
                    -1.0
                };
                let g = Haar2d::combine(&out[parent].to_dense(), 0.5, &h.to_dense(), sign);
                Ok(SparseHaar::compress_below(&g, 0.0))
            })
            .collect::<Result<_, CacheError>>()?;
        out.extend(level_maps);
        start = end;
    }
    Ok(out)
}

/// The emitted intensity of every node with emitting surfels below, built as the bake built
/// the emission into I: each emitting surfel's intensity map of its emission alone, at its own
/// resolution, summed up the tree (at the finest below each node), at the tree's resolution.
fn emitted_intensities(
    records: &[NodeRecord],
    nodes: &[NodeSummary],
    surfels: &[SurfelRecord],
    maps: &[Option<SparseHaar<Rgb>>],
    levels: u32,
) -> Vec<Option<SparseHaar<Rgb>>> {
    let mut dense: Vec<Option<Haar2d<Rgb>>> = vec![None; nodes.len()];
    // Children come after their parents: sum in reverse order.
    for j in (0..nodes.len()).rev() {
        let sender = &nodes[j];
        if sender.is_leaf() {
            let s = &surfels[sender.surfel as usize];
            let le = Vec3::from(s.emitted);
            if le == Rgb::ZERO {
                continue;
            }
            let n = Vec3::from(s.n);
            let emission = match &maps[sender.surfel as usize] {
                None => SurfelRadiance::Rgb(le),
                Some(m) => {
                    let own = m.levels();
                    let texels: Vec<Rgb> = crate::haar::texel_directions(own)
                        .iter()
                        .map(|w| if w.dot(n) > 0.0 { le } else { Rgb::ZERO })
                        .collect();
                    SurfelRadiance::Map(SparseHaar::compress(
                        &Haar2d::forward(&texels, 1 << own),
                        0.0,
                    ))
                }
            };
            dense[j] = Some(intensity_map(n, s.area, &emission, true).to_dense());
        } else {
            let [l, r] = records[j].node.children.map(|c| dense[c as usize].as_ref());
            dense[j] = match (l, r) {
                (Some(a), Some(b)) => Some(Haar2d::combine(a, 1.0, b, 1.0)),
                (Some(a), None) | (None, Some(a)) => Some(a.clone()),
                (None, None) => None,
            };
        }
    }
    // Only inner nodes need it (leaves subtract their surfel's emission exactly).
    dense
        .into_iter()
        .zip(nodes)
        .map(|(d, n)| {
            d.filter(|_| !n.is_leaf())
                .map(|d| SparseHaar::compress_below(&d, 0.0).refined_to(levels))
        })
        .collect()
}

// The traversal's record fills one cache line (see [`SenderNode`]).
const _: () = assert!(std::mem::size_of::<SenderNode>() == 64);

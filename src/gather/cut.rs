//! A receiver's cut of the sender tree, splatted into its microbuffer (docs/method.md §2.3, §7.3).
//!
//! From the given start nodes (the root for plain PBGI, the near nodes of a cluster cut for
//! FPBGI), a node joins the cut when the solid angle it covers, P(ω)/d², is no larger than the
//! pixel it falls in, and it is far enough for that estimate to hold (its bounding sphere at
//! least two radii away and not much wider than the pixel); otherwise its children are
//! visited. Nodes whose bounding sphere lies below a hemispherical receiver's horizon are
//! culled.
//!
//! Near leaves (docs/method.md §2.3 step 3): a leaf wider than its pixel, or within [`NEAR_RADII`] disc
//! radii (where P/d² no longer holds), is split into equal-area pieces of its disc, each no
//! wider than a pixel from where it lies (a quadtree, fine near the receiver and coarse on the
//! disc's far side), splatted with its own direction, distance and cosine; pieces below a
//! hemispherical receiver's horizon are dropped, which clips the disc there. The
//! spec resolves near leaves by ray casting the pixel centres instead; measured on a lit
//! square (tests/gather.rs), that lost 17 % of a ring of pixels where ray-cast and splatted
//! leaves of one surface share pixels (a centre ray that misses the near discs drops their
//! share of the pixel), and 6 % overhead from the gaps between discs.
//!
//! The final render sets its near leaves aside instead ([`NearLeaves::Aside`]) and traces
//! rays through its buffer's pixels for them (`render::near_field`): discs tile a surface
//! only roughly, and within a few radii of a receiver their gaps and overhangs are what it
//! sees (light leaking into the centimetre gap between the Cornell box's ceiling and its
//! hanging light, contacts too bright). The bake splits them, as above.

use super::microbuffer::{Microbuffer, Sender};
use super::senders::Senders;
use crate::cache::store::NO_NODE;
use crate::geometry::frame::Frame;
use crate::geometry::warp::square_to_uniform_disk_concentric;
use glam::{Vec2, Vec3};

/// Leaves nearer than this many disc radii are split into pieces.
pub const NEAR_RADII: f32 = 4.0;

/// The most pieces per side of a split leaf (a power of two: the pieces are a quadtree's
/// cells). It matters only within a fraction of a radius of the disc: a cap of 16 left 30 %
/// holes under a sphere resting on a floor, through which the light behind leaked.
pub(crate) const MAX_PIECES: u32 = 64;

/// Pieces per pixel width of a split leaf.
pub(crate) const PIECES_PER_PIXEL: f32 = 1.0;

/// The nearest, in node radii, that a node straddling a render receiver's plane joins its cut
/// whole (from a uniform buffer; see [`splat_cut_beyond`]). Each receiver refined every such
/// node down to its leaves, however far: the walls' and boxes' rows along the floor under a
/// floor receiver, 45 % of the nodes a cbox-diffuse or cbox-glossy render visited. At 512²,
/// from 4 radii, every reference scene's relMSE came out 0.3–0.8 % lower and its render
/// 1–13 % faster (docs/render.md); from a BSDF-refined buffer the glossy scenes' error rose,
/// so a refined buffer takes them whole only in its faint directions
/// (`Microbuffer::is_faint_at`).
/// The bake keeps opening them all ([`splat_cut`]): its furnaces are where the rule came from
/// (docs/bounces.md), and they were not measured again.
pub const STRADDLE_RADII: f32 = 4.0;

/// How far from a receiver's plane, in disc radii, a parallel disc of another mesh still
/// counts as the receiver's own surface (coplanar meshes, to rounding).
pub(crate) const COPLANAR: f32 = 0.01;

/// What one traversal did (for the render statistics).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CutStats {
    /// Nodes visited.
    pub visited: u64,
    /// Nodes splatted into the buffer.
    pub splats: u64,
    /// Near leaves split into pieces, or set aside to be traced ([`NearLeaves`]).
    pub near_leaves: u64,
}

/// What a receiver's cut does with its near leaves (see the module docs).
pub enum NearLeaves<'a> {
    /// Split each into pieces and splat them.
    Split,
    /// Add each to the list, splatting nothing, for the caller to trace the near field.
    Aside(&'a mut Vec<u32>),
}

impl std::ops::AddAssign for CutStats {
    fn add_assign(&mut self, o: CutStats) {
        self.visited += o.visited;
        self.splats += o.splats;
        self.near_leaves += o.near_leaves;
    }
}

/// Traverse from `start` for the receiver at `p` on mesh `mesh` (the buffer's frame is its
/// shading frame) and splat the cut into `mb`, opening every node that straddles the
/// receiver's plane (the bake's rule; the render's is [`splat_cut_beyond`]).
pub fn splat_cut(
    senders: &Senders,
    p: Vec3,
    mesh: u32,
    mb: &mut Microbuffer,
    start: &[u32],
    stack: &mut Vec<u32>,
) -> CutStats {
    let always_open = f32::INFINITY;
    let near = &mut NearLeaves::Split;
    splat_cut_beyond(senders, (p, mesh), mb, start, stack, always_open, near)
}

/// [`splat_cut`], where a node straddling the plane of a receiver with a uniform buffer joins
/// the cut whole, as any other node, when it lies at least `straddle_radii` of its radii away
/// ([`STRADDLE_RADII`] in the render), and the near leaves go as `near` says.
pub fn splat_cut_beyond(
    senders: &Senders,
    (p, mesh): (Vec3, u32),
    mb: &mut Microbuffer,
    start: &[u32],
    stack: &mut Vec<u32>,
    straddle_radii: f32,
    near: &mut NearLeaves,
) -> CutStats {
    let mut stats = CutStats::default();
    let n = mb.frame.n;
    stack.clear();
    stack.extend_from_slice(start);
    while let Some(j) = stack.pop() {
        stats.visited += 1;
        let sender = &senders.nodes[j as usize];
        let v = sender.center - p;
        if !mb.spherical && n.dot(v) < -sender.radius {
            continue;
        }
        let d2 = v.length_squared();
        let d = d2.sqrt();
        // A closed mesh seen from outside shows only its front faces.
        let back_hidden = senders.back_hidden(j, p, 0.0, mesh);
        if back_hidden && senders.faces_away(j, p, 0.0) {
            continue;
        }
        if sender.is_leaf() {
            // A surfel centred below a hemispherical receiver's horizon belongs to a surface
            // that passes under it (at a contact or an intersection): the part of its disc
            // that peeks above is an artefact of the disc, not something the receiver sees.
            if !(d > 0.0) || (!mb.spherical && n.dot(v) <= 0.0) {
                continue;
            }
            let dir = v / d;
            // A leaf's projected area is exact and cheap; its radiance is looked up only if it
            // is splatted whole (split leaves look up each piece's).
            let s = &senders.surfels[sender.surfel() as usize];
            let omega = s.area * Vec3::from(s.n).dot(dir).abs() / d2;
            let disc = (s.area / std::f32::consts::PI).sqrt();
            let at = mb.locate(dir);
            let pixel = at
                .as_ref()
                .map_or(mb.pixel_solid_angle(), |at| mb.solid_angle_at(at));
            if omega <= pixel && d > NEAR_RADII * disc {
                if let Some(at) = at.filter(|_| omega > 0.0) {
                    let seen = senders.seen(j, -dir, mesh, back_hidden);
                    let sender = senders.sender(j, v, seen);
                    stats.splats += u64::from(mb.splat_at(&sender, d, at, omega));
                }
            } else {
                stats.near_leaves += 1;
                match near {
                    NearLeaves::Split => {
                        stats.splats += split_leaf(senders, sender.surfel(), (p, mesh), pixel, mb);
                    }
                    NearLeaves::Aside(leaves) => leaves.push(sender.surfel()),
                }
            }
            continue;
        }
        // A node whose bounding sphere straddles a hemispherical receiver's plane is seen
        // edge-on from one direction only where it is small: the receiver's own surface in it
        // would be taken as a back face seen from below and darken the horizon. Its children
        // are visited instead (near a receiver, or from a BSDF-refined buffer), and a flat
        // node lying in the receiver's plane, facing its way, is that surface itself: it
        // sends nothing towards the receiver and does not occlude. Farther than
        // `straddle_radii` from a uniform buffer it joins the cut as any node does.
        let dir = v / d;
        // Where `dir` falls in the buffer, looked up at most once.
        let mut located = None;
        if !mb.spherical && n.dot(v).abs() < sender.radius {
            if senders.holds_plane_of(j, p, n) {
                continue;
            }
            // A BSDF-refined buffer opens far ones too, except in the directions its lobe
            // hardly weighs (faint pixels), which take them as a uniform buffer does.
            let far = d2 > (straddle_radii * sender.radius).powi(2);
            let open = !far
                || (mb.is_refined()
                    && !(*located.get_or_insert_with(|| mb.locate(dir)))
                        .is_some_and(|at| mb.is_faint_at(&at)));
            if open {
                stack.extend(sender.children.into_iter().filter(|&c| c != NO_NODE));
                continue;
            }
        }
        // Against the largest pixel first: it rejects most nodes near the root without a
        // pixel lookup.
        let base = mb.pixel_solid_angle();
        let mut projected = None;
        let accepted = if !senders.needs_leaves(j, mesh)
            && fits_pixel(senders, j, d2, dir, base, &mut projected)
        {
            located.unwrap_or_else(|| mb.locate(dir)).filter(|at| {
                let pixel = mb.solid_angle_at(at);
                pixel == base || fits_pixel(senders, j, d2, dir, pixel, &mut projected)
            })
        } else {
            None
        };
        if let Some(at) = accepted {
            let seen = senders.seen(j, -dir, mesh, back_hidden);
            let sender = senders.sender(j, v, seen);
            stats.splats += u64::from(mb.splat_at(&sender, d, at, seen.projected / d2));
        } else {
            for c in sender.children {
                if c != NO_NODE {
                    stack.push(c);
                }
            }
        }
    }
    stats
}

/// Whether inner node `j`, at squared distance `d2` along unit direction `dir` from the
/// receiver, may be splatted into a pixel of solid angle `pixel`: it is at least two radii
/// away, its bounding sphere is not wider than four pixels, and the solid angle it covers,
/// P/d², is no larger than the pixel. `projected` keeps P along `dir` once it is known, for
/// the test against another pixel.
pub(crate) fn fits_pixel(
    senders: &Senders,
    j: u32,
    d2: f32,
    dir: Vec3,
    pixel: f32,
    projected: &mut Option<f32>,
) -> bool {
    let r = senders.nodes[j as usize].radius;
    d2 > 4.0 * r * r
        && std::f32::consts::PI * r * r / d2 <= 4.0 * pixel
        && *projected.get_or_insert_with(|| senders.projected_area(j, -dir)) / d2 <= pixel
}

/// The most a piece of the unit square reaches on a unit disc under the concentric map,
/// per unit of its side (see [`split_leaf`]): 3 × √2 / 2.
const REACH: f32 = 2.13;

/// Quadrant `q` (x-major) of the square at `corner` whose quadrants are `half` wide.
fn quadrant(corner: Vec2, half: f32, q: u32) -> Vec2 {
    corner + Vec2::new((q % 2) as f32, (q / 2) as f32) * half
}

/// Splat surfel `i`, seen from the receiver (position, mesh), as equal-area pieces
/// of its disc, each no wider than `pixel` as seen face-on from its own nearest point.
/// Returns the pieces splatted.
fn split_leaf(
    senders: &Senders,
    i: u32,
    (p, mesh): (Vec3, u32),
    pixel: f32,
    mb: &mut Microbuffer,
) -> u64 {
    let s = &senders.surfels[i as usize];
    let (c, ns) = (Vec3::from(s.p), Vec3::from(s.n));
    let radius = (s.area / std::f32::consts::PI).sqrt();
    // A disc facing the receiver's way whose plane passes within half its radius of the
    // receiver is the receiver's own surface (its own surfel, a coplanar neighbour, or on a
    // curved surface a neighbour whose tangent plane passes just above it): seen edge-on, it
    // sends nothing there and must not occlude. A disc of another mesh is the same surface
    // only when coplanar to rounding; one parallel a little off (an emitter hung 1 cm under
    // the ceiling) hides what lies behind it. (A surface facing the receiver at a contact, a
    // sphere resting on a floor, is not skipped either.)
    let own = if s.mesh == mesh { 0.5 } else { COPLANAR };
    if ns.dot(mb.frame.n) > 0.5 && (c - p).dot(ns).abs() < own * radius {
        return 0;
    }
    // Seen from behind within a radius of its plane, a disc of the receiver's own mesh stands
    // for that surface curving round the receiver (inside a crease, or a glass sphere's
    // inside), not for its back side: its back radiance there (a glass surfel's transmitted
    // light) would leak through. Another mesh seen from behind is an occluder however near
    // (the ceiling 1 cm above an emitter's back must stay dark: skipping the emitter's discs
    // there lit it, and the light's edges then held most of the diffuse box's relMSE).
    let front = (p - c).dot(ns);
    if front < 0.0 && -front < radius && s.mesh == mesh {
        return 0;
    }
    // The pieces are the cells of a quadtree over the disc's equal-area (concentric) square,
    // split until each is no wider than a pixel as seen from its own nearest point (floored
    // at a quarter of the disc's radius, where the disc's own bound stops growing). Pieces
    // near the receiver come out as fine as a uniform split would make every piece; the far
    // side of the disc stays coarse (with a uniform m × m split, pieces were two thirds of a
    // render's splats). A piece that straddles a hemispherical receiver's horizon is split to
    // half a pixel, so the horizon clips the disc that finely.
    let floor = 0.25 * radius;
    let limit = pixel / (PIECES_PER_PIXEL * PIECES_PER_PIXEL);
    let max_level = MAX_PIECES.trailing_zeros();
    let frame = Frame::from_normal(ns);
    let to_disc = |u: Vec2| {
        let q = square_to_uniform_disk_concentric(u) * radius;
        frame.to_world(Vec3::new(q.x, q.y, 0.0))
    };
    let mut splats = 0;
    // Depth first, quadrants in x-major order: a deterministic order of pieces.
    let mut stack: Vec<(Vec2, u32)> = Vec::with_capacity(4 * max_level as usize + 4);
    stack.extend((0..4u32).rev().map(|q| (quadrant(Vec2::ZERO, 0.5, q), 1)));
    while let Some((corner, level)) = stack.pop() {
        let side = 1.0 / (1u32 << level) as f32;
        let centre = to_disc(corner + Vec2::splat(0.5 * side));
        // The piece's reach from its centre: the concentric map stretches no length by more
        // than 3 disc radii per unit of the square (its Jacobian's Frobenius norm is at most
        // √(1 + π²/8) ≈ 1.49 on [−1, 1]², which is twice the unit square), over half the
        // cell's diagonal.
        let reach = REACH * side * radius;
        let offset = c + centre - p;
        let d2 = offset.length_squared();
        let d = d2.sqrt();
        let piece_area = s.area * side * side;
        if level < max_level {
            let nearest = (d - reach).max(floor);
            let straddles = !mb.spherical && offset.dot(mb.frame.n).abs() < reach;
            let bound = piece_area / (nearest * nearest);
            if bound > limit || (straddles && bound > 0.25 * limit) {
                stack.extend(
                    (0..4u32)
                        .rev()
                        .map(|q| (quadrant(corner, 0.5 * side, q), level + 1)),
                );
                continue;
            }
        }
        if !(d2 > 0.0) || (!mb.spherical && offset.dot(mb.frame.n) <= 0.0) {
            continue;
        }
        let w = offset / d;
        // Every piece is seen from the side the disc's centre is seen from.
        let cos = ns.dot(-w);
        if (cos > 0.0) != (front > 0.0) {
            continue;
        }
        let omega = piece_area * cos.abs() / d2;
        if omega > 0.0 {
            let lookup = senders.surfel_lookup(i, -w, cos, mesh);
            let sender = Sender {
                offset,
                radius: radius * side,
                normal: ns,
                radiance: senders.evaluated(lookup),
                lookup,
            };
            splats += u64::from(mb.splat(&sender, omega));
        }
    }
    splats
}

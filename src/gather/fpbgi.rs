//! Factorized PBGI (docs/method.md §3): receivers of one image tile are clustered, each cluster shares
//! one cut of the far nodes and one microbuffer of them, and each receiver refines only the
//! near nodes into its own buffer.
//!
//! - Clustering (docs/method.md §3.2): k-means over positions and normals with the metric
//!   D(x, c) = ‖p_c − p_x‖² + α‖n_c − n_x‖², α = the diagonal of the bounding box of the tile's
//!   receivers. The thesis leaves the start and the iteration count open: the k starting centres
//!   are receivers evenly spaced in image order (deterministic, spread over the tile) and the
//!   iterations stop when no receiver changes cluster, or after [`KMEANS_ITERATIONS`].
//! - The active receiver is the one nearest its cluster's final centre; the cluster radius r
//!   is its largest distance to a member (docs/method.md §13 item 4).
//! - Cluster cut (docs/method.md §3.3, with the far/near rule read as §13 item 1 recommends): a node with
//!   r/d > ε is near and stops the cluster's traversal (0.3 ε for nodes made mostly of glossy
//!   surfels, whose radiance changes fast with the direction: with ε for all, FPBGI differed
//!   from PBGI by relMSE 1.6e-4 on cbox-glossy, in the glow the gold box reflects; with 0.3 ε,
//!   2.5e-5, for 1.37× instead of 1.81× the speed); a far node that passes the solid-angle
//!   test from the active receiver joins the cluster buffer. The cluster buffer is spherical
//!   and not culled by any horizon, so it serves members whose normals differ from the active receiver's.
//! - Each member traverses from the near nodes into its own buffer; the two are composited by
//!   depth per pixel, the cluster buffer looked up along each member pixel's direction
//!   (docs/method.md §3.4 step 3).

use super::cut::{fits_pixel, splat_cut_beyond, CutStats, NearLeaves};
use super::microbuffer::Microbuffer;
use super::senders::{node_flags, Senders};
use crate::cache::store::NO_NODE;
use crate::geometry::frame::Frame;
use glam::Vec3;

/// The most k-means iterations.
pub const KMEANS_ITERATIONS: u32 = 16;

/// The far threshold's factor for nodes made mostly of directional (glossy) surfels (see the
/// module docs for the measured trade-off).
pub(crate) const DIRECTIONAL_FAR: f32 = 0.3;

/// One cluster of receivers: the render's k-means clusters of primary hits ([`cluster`]) and
/// the bake's receiver groups of surfels (`bounce::view_tree`) alike.
#[derive(Clone, Debug, PartialEq)]
pub struct Cluster {
    /// Indices into the clustered receivers.
    pub members: Vec<u32>,
    /// The member nearest the centre.
    pub active: u32,
    /// The largest distance from the active receiver to a member.
    pub radius: f32,
    /// For members on one surface: the widest angle (radians) between a member's normal and
    /// the surface's axis (see [`ClusterReceivers::plane_slope`]); `None` where members may
    /// face any way.
    pub cone: Option<f32>,
}

/// Cluster `points` (position, unit normal) into at most `k` clusters.
pub fn cluster(points: &[(Vec3, Vec3)], k: usize) -> Vec<Cluster> {
    if points.is_empty() {
        return Vec::new();
    }
    let k = k.clamp(1, points.len());
    let (lo, hi) = points.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), (p, _)| (lo.min(*p), hi.max(*p)),
    );
    let alpha = (hi - lo).length();
    let metric = |a: &(Vec3, Vec3), b: &(Vec3, Vec3)| {
        (a.0 - b.0).length_squared() + alpha * (a.1 - b.1).length_squared()
    };
    let mut centres: Vec<(Vec3, Vec3)> = (0..k).map(|i| points[i * points.len() / k]).collect();
    let mut assign = vec![u32::MAX; points.len()];
    for _ in 0..KMEANS_ITERATIONS {
        let mut changed = false;
        for (i, x) in points.iter().enumerate() {
            let best = (0..k)
                .min_by(|&a, &b| metric(x, &centres[a]).total_cmp(&metric(x, &centres[b])))
                .unwrap_or(0) as u32;
            if assign[i] != best {
                assign[i] = best;
                changed = true;
            }
        }
        if !changed {
            break;
        }
        let mut sums = vec![(Vec3::ZERO, Vec3::ZERO, 0u32); k];
        for (x, &a) in points.iter().zip(&assign) {
            let s = &mut sums[a as usize];
            s.0 += x.0;
            s.1 += x.1;
            s.2 += 1;
        }
        for (c, s) in centres.iter_mut().zip(&sums) {
            if s.2 > 0 {
                c.0 = s.0 / s.2 as f32;
                c.1 = s.1.try_normalize().unwrap_or(c.1);
            }
        }
    }
    let mut clusters: Vec<Cluster> = (0..k)
        .map(|_| Cluster {
            members: Vec::new(),
            active: 0,
            radius: 0.0,
            cone: None,
        })
        .collect();
    for (i, &a) in assign.iter().enumerate() {
        clusters[a as usize].members.push(i as u32);
    }
    clusters.retain(|c| !c.members.is_empty());
    for c in clusters.iter_mut() {
        let mean = c
            .members
            .iter()
            .fold(Vec3::ZERO, |s, &m| s + points[m as usize].0)
            / c.members.len() as f32;
        c.active = *c
            .members
            .iter()
            .min_by(|&&a, &&b| {
                (points[a as usize].0 - mean)
                    .length_squared()
                    .total_cmp(&(points[b as usize].0 - mean).length_squared())
            })
            .unwrap_or(&c.members[0]);
        let pa = points[c.active as usize].0;
        c.radius = c
            .members
            .iter()
            .map(|&m| (points[m as usize].0 - pa).length())
            .fold(0.0, f32::max);
    }
    clusters
}

/// A cluster's shared part: its far nodes splatted into a spherical buffer around the active
/// receiver, and the near nodes its members refine.
pub struct ClusterCut {
    /// The far nodes' spherical buffer.
    pub buffer: Microbuffer,
    /// The near nodes, where the members' own traversals start.
    pub near: Vec<u32>,
    /// What the cluster's traversal did.
    pub stats: CutStats,
    /// For the last few member buffer layouts (frame, spherical), the shared pixel along each
    /// member pixel's direction (or [`NO_PIXEL`]): members on one flat surface share a frame,
    /// and the lookups were a tenth of the gather.
    lookups: Vec<(Frame, bool, Vec<u32>)>,
}

/// A member pixel whose direction the shared buffer has no pixel for.
const NO_PIXEL: u32 = u32::MAX;

/// Layouts [`ClusterCut`] remembers.
const LOOKUPS: usize = 4;

impl ClusterCut {
    /// The index in `lookups` of the shared pixels along each pixel of the buffer `mb`.
    fn lookup(&mut self, mb: &Microbuffer) -> usize {
        let found = self.lookups.iter().position(|(f, sph, t)| {
            *f == mb.frame && *sph == mb.spherical && t.len() == mb.pixels.len()
        });
        let index = match found {
            Some(i) => i,
            None => {
                let table = mb
                    .pixels
                    .iter()
                    .map(|px| {
                        self.buffer
                            .pixel_of(mb.frame.to_world(px.dir))
                            .map_or(NO_PIXEL, |c| c as u32)
                    })
                    .collect();
                if self.lookups.len() == LOOKUPS {
                    self.lookups.remove(0);
                }
                self.lookups.push((mb.frame, mb.spherical, table));
                self.lookups.len() - 1
            }
        };
        index
    }
}

/// The receivers a cluster cut serves.
#[derive(Clone, Copy, Debug)]
pub struct ClusterReceivers {
    /// The active receiver's position, mesh and frame.
    pub p: Vec3,
    /// See `p`.
    pub mesh: u32,
    /// See `p`.
    pub frame: Frame,
    /// The largest distance from the active receiver to a member.
    pub radius: f32,
    /// For members on one surface with hemispherical buffers: how far their planes may turn
    /// from the active's (the sine of the angle; 0 for members in the active's plane). Far
    /// nodes whose bounding sphere comes that near the active's plane are opened (see
    /// [`splat_cut`](super::cut::splat_cut)'s nodes straddling a receiver's plane). `None`:
    /// no plane.
    pub plane_slope: Option<f32>,
    /// Whether the shared buffer records links (see [`Microbuffer::record_links`]), for
    /// members that do.
    pub record_links: bool,
}

impl ClusterReceivers {
    /// The receivers of `cluster`, whose active member is at `p` on `mesh` with frame `frame`:
    /// members on one surface (`cluster.cone`) keep a plane unless their buffers are
    /// `spherical`.
    pub fn of(
        cluster: &Cluster,
        (p, mesh, frame): (Vec3, u32, Frame),
        spherical: bool,
        record_links: bool,
    ) -> ClusterReceivers {
        ClusterReceivers {
            p,
            mesh,
            frame,
            radius: cluster.radius,
            plane_slope: cluster.cone.filter(|_| !spherical).map(f32::sin),
            record_links,
        }
    }
}

/// How the members of one cluster fill their microbuffers: the one receiver-gather loop of the
/// final render and of the bake's bounces. Alone ([`ClusterGather::alone`]), a receiver
/// traverses the whole tree; together ([`ClusterGather::shared`]), members share the
/// cluster's far cut and each refines only its near nodes ([`ClusterGather::fill`]) before
/// the shared buffer is composited into its own ([`composite_shared`]).
pub struct ClusterGather<'a> {
    senders: &'a Senders,
    shared: Option<ClusterCut>,
    /// See [`ClusterGather::whole_straddling_beyond`].
    straddle_radii: f32,
    /// The near leaves a receiver's cut set aside ([`ClusterGather::fill_tracing_near`]).
    near_leaves: Vec<u32>,
}

/// A receiver's near field, traced by whoever gathers instead of splatted: it is handed the
/// buffer, its senders recorded but not yet resolved, and the near leaves its cut set aside
/// ([`NearLeaves::Aside`]), and records what it finds there.
pub type NearField<'f> = &'f mut dyn FnMut(&mut Microbuffer, &[u32]);

impl<'a> ClusterGather<'a> {
    /// Receivers that each traverse the whole tree.
    pub fn alone(senders: &'a Senders) -> Self {
        ClusterGather {
            senders,
            shared: None,
            straddle_radii: f32::INFINITY,
            near_leaves: Vec::new(),
        }
    }

    /// Receivers' cuts take nodes that straddle their plane whole from `radii` of their radii
    /// ([`splat_cut_beyond`]); without this they open every such node
    /// ([`splat_cut`](super::cut::splat_cut)).
    pub fn whole_straddling_beyond(self, radii: f32) -> Self {
        ClusterGather {
            straddle_radii: radii,
            ..self
        }
    }

    /// Members of one cluster that share its cut ([`cluster_cut`], far threshold `far_eps`,
    /// an `n × n` shared buffer).
    pub fn shared(
        senders: &'a Senders,
        receivers: &ClusterReceivers,
        far_eps: f32,
        n: u32,
    ) -> Self {
        ClusterGather {
            senders,
            shared: Some(cluster_cut(senders, receivers, far_eps, n)),
            straddle_radii: f32::INFINITY,
            near_leaves: Vec::new(),
        }
    }

    /// What the shared cut cost (nothing for receivers alone).
    pub(crate) fn shared_stats(&self) -> CutStats {
        self.shared
            .as_ref()
            .map_or_else(CutStats::default, |c| c.stats)
    }

    /// Fill `mb`, reset for the receiver at `p` on `mesh`, with the light it sees, resolved
    /// (and composited with the shared buffer). `stack` is scratch.
    pub fn fill(
        &mut self,
        p: Vec3,
        mesh: u32,
        mb: &mut Microbuffer,
        stack: &mut Vec<u32>,
    ) -> CutStats {
        self.fill_with((p, mesh), mb, stack, None)
    }

    /// [`ClusterGather::fill`], where the cut sets its near leaves aside and `near_field`
    /// records what the receiver sees there before the buffer is resolved.
    pub fn fill_tracing_near(
        &mut self,
        p: Vec3,
        mesh: u32,
        mb: &mut Microbuffer,
        stack: &mut Vec<u32>,
        near_field: NearField,
    ) -> CutStats {
        self.fill_with((p, mesh), mb, stack, Some(near_field))
    }

    fn fill_with(
        &mut self,
        (p, mesh): (Vec3, u32),
        mb: &mut Microbuffer,
        stack: &mut Vec<u32>,
        near_field: Option<NearField>,
    ) -> CutStats {
        let start: &[u32] = match &self.shared {
            Some(cut) => &cut.near,
            None if self.senders.nodes.is_empty() => &[],
            None => &[0],
        };
        self.near_leaves.clear();
        let mut near = match near_field {
            Some(_) => NearLeaves::Aside(&mut self.near_leaves),
            None => NearLeaves::Split,
        };
        let (senders, straddle) = (self.senders, self.straddle_radii);
        let stats = splat_cut_beyond(senders, (p, mesh), mb, start, stack, straddle, &mut near);
        if let Some(near_field) = near_field {
            if !self.near_leaves.is_empty() {
                near_field(mb, &self.near_leaves);
            }
        }
        mb.resolve();
        if let Some(cut) = &mut self.shared {
            composite_shared(cut, mb);
        }
        stats
    }
}

/// The cluster cut for `receivers`, with far threshold `far_eps`, into an `n × n` spherical
/// buffer (docs/method.md §3.3).
pub fn cluster_cut(
    senders: &Senders,
    receivers: &ClusterReceivers,
    far_eps: f32,
    n: u32,
) -> ClusterCut {
    let ClusterReceivers {
        p,
        mesh,
        frame,
        radius,
        plane_slope,
        record_links,
    } = *receivers;
    let mut buffer = Microbuffer::new(n, true, frame);
    if record_links {
        buffer.record_links();
    }
    let mut near = Vec::new();
    let mut stats = CutStats::default();
    let mut stack = vec![0u32];
    if senders.nodes.is_empty() {
        stack.clear();
    }
    while let Some(j) = stack.pop() {
        stats.visited += 1;
        let sender = &senders.nodes[j as usize];
        let v = sender.center - p;
        let d2 = v.length_squared();
        let d = d2.sqrt();
        // Near: the cluster is not small as seen from the node. A node made mostly of
        // directional (glossy) surfels, whose radiance changes fast with the direction it is
        // seen from, must be farther to be shared.
        let eps = if sender.has(node_flags::MOSTLY_DIRECTIONAL) {
            far_eps * DIRECTIONAL_FAR
        } else {
            far_eps
        };
        if !(d > 0.0) || radius > eps * d || senders.needs_leaves(j, mesh) {
            near.push(j);
            continue;
        }
        // A far node that comes near the members' planes is opened as a member's traversal
        // would open it, and a planar one in the active's plane is their own surface.
        // Members' planes turn at most `slope` from the active's, about points within
        // `radius` of it: a member sees the node's centre that much higher or lower.
        let straddles = plane_slope
            .is_some_and(|slope| frame.n.dot(v).abs() < sender.radius + slope * (d + radius));
        if straddles {
            if sender.is_leaf() {
                near.push(j);
            } else if !senders.holds_plane_of(j, p, frame.n) {
                stack.extend(sender.children.into_iter().filter(|&c| c != NO_NODE));
            }
            continue;
        }
        // A closed mesh seen from outside shows only its front faces (see splat_cut).
        let back_hidden = senders.back_hidden(j, p, radius, mesh);
        if back_hidden && senders.faces_away(j, p, radius) {
            continue;
        }
        let dir = v / d;
        let pixel = buffer.pixels[buffer.pixel_of(dir).unwrap_or(0)].solid_angle;
        let small = sender.is_leaf() || fits_pixel(senders, j, d2, dir, pixel, &mut None);
        if small {
            let seen = senders.seen(j, -dir, mesh, back_hidden);
            let omega = seen.projected / d2;
            if sender.is_leaf() && omega > pixel {
                near.push(j);
                continue;
            }
            stats.splats += u64::from(buffer.splat(&senders.sender(j, v, seen), omega));
        } else {
            for c in sender.children {
                if c != NO_NODE {
                    stack.push(c);
                }
            }
        }
    }
    buffer.resolve();
    ClusterCut {
        buffer,
        near,
        stats,
        lookups: Vec::new(),
    }
}

/// Composite the shared buffer of `cut` into a member's buffer `mb`, resolved: each of its
/// pixels takes the shared light along its direction, by depth (docs/method.md §3.4 step 3).
pub fn composite_shared(cut: &mut ClusterCut, mb: &mut Microbuffer) {
    let index = cut.lookup(mb);
    let (lookup, shared) = (&cut.lookups[index].2, &cut.buffer);
    // For a buffer that records links: the scale of each pixel's own links (radiance,
    // cosine-weighted) and the shared pixels composited into it, with their weights.
    let recording = mb.links().is_some();
    let mut own = if recording {
        vec![(1.0f32, 1.0f32); mb.pixels.len()]
    } else {
        Vec::new()
    };
    let mut from_shared = Vec::new();
    for (k, &c) in lookup.iter().enumerate() {
        if c == NO_PIXEL {
            continue;
        }
        let c = c as usize;
        let (lc, ac, dc) = (shared.radiance[c], shared.alpha[c], shared.depth[c]);
        if ac <= 0.0 {
            continue;
        }
        let (lr, ar, dr) = (mb.radiance[k], mb.alpha[k], mb.depth[k]);
        // The shared buffer's light in this pixel, weighted by the member's mean cosine.
        let px = &mb.pixels[k];
        let cos = px.dir.z.abs() * px.cos_weight;
        // As in one buffer's resolve: coverages add, and the farther part fills at most what
        // the nearer leaves open (multiplying by the open fraction instead darkened FPBGI
        // against PBGI by 0.3 %).
        let fill = |open: f32, cover: f32| {
            if cover > open {
                open.max(0.0) / cover
            } else {
                1.0
            }
        };
        let (cover_r, cover_c) = (mb.coverage[k], shared.coverage[c]);
        // Weights of the member's own light and of the shared light (radiance, cosine).
        let (own_w, shared_w) = if dr <= dc {
            let f = fill(1.0 - ar, ac);
            ((1.0, 1.0), (f, cos * f))
        } else {
            let f = fill(1.0 - ac, ar);
            ((f, f), (1.0, cos))
        };
        mb.radiance[k] = lr * own_w.0 + lc * shared_w.0;
        mb.cos_radiance[k] = mb.cos_radiance[k] * own_w.1 + lc * shared_w.1;
        mb.alpha[k] = ar * own_w.0 + ac * shared_w.0;
        mb.coverage[k] = cover_r * own_w.0 + cover_c * shared_w.0;
        mb.depth[k] = dr.min(dc);
        if shared.is_mixed(c) || ar > 0.0 {
            mb.mark_mixed(k);
        }
        if recording {
            own[k] = own_w;
            from_shared.push((k as u32, c as u32, shared_w.0, shared_w.1));
        }
    }
    if recording {
        mb.composite_links(&own, shared, &from_shared);
    }
}

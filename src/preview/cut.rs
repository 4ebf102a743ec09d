//! The view-dependent cut (docs/design.md §8): instead of the thesis's one tree level (docs/method.md §9),
//! every frame takes the coarsest nodes whose bounding spheres cover at most a given number of
//! pixels on screen, so that zooming in does not alias and far nodes cost little; the nodes
//! wholly outside the view are left out. Each cut node becomes one [`Splat`].
//!
//! A node's radiance towards the eye is evaluated here, on the CPU, from its wavelets along
//! the direction from its centre to the eye (docs/method.md §9's cheaper option), with the same
//! [`Senders::seen`] the final render's gather uses. The cut is built on the CPU anyway, and
//! this keeps the coefficient trees off the GPU: a splat carries three floats of radiance.

use super::view::View;
use crate::cache::store::NO_NODE;
use crate::gather::senders::{node_flags, Senders};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use rayon::prelude::*;

/// The mesh the eye stands on, for [`Senders::seen`]'s rule that a solid's inward light
/// reaches only its own surface: none (no mesh has this index).
const EYE_MESH: u32 = u32::MAX;

/// How far a splat's footprint reaches beyond its node's bounding sphere, in radii of the
/// node's surfels' discs. A surfel's disc has its share of the surface's area, so discs leave
/// gaps between them (a tenth of the plane in a hexagonal packing, more for Poisson disks): a
/// point of the surface may lie up to about two disc radii from the nearest surfel's centre,
/// which lies in its cut node's sphere. Measured in `tests/preview.rs`: footprints of 1.5 disc
/// radii leave 155 of 19 200 pixels without a splat, of 2 radii 7. A leaf's footprint is then
/// twice its disc; an inner node's barely more than its sphere, so that coarse cuts do not pay
/// for overlapping splats.
pub const SPLAT_RIM: f32 = 1.0;

/// One cut node as the splat and disc shaders read it (`splat.vert`, `disk.vert`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Splat {
    /// Centre and footprint radius.
    pub sphere: [f32; 4],
    /// Normal; w: 0 none (a curved node), 1 one-sided, 2 two-sided (surfels that send light
    /// from their backs too).
    pub normal: [f32; 4],
    /// Radiance towards the eye (w unused).
    pub radiance: [f32; 4],
}

/// What a splat's radiance shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Colouring {
    /// The light the node reflects (what a gather sees: the cache less its emission).
    Reflected,
    /// Reflected and emitted.
    Outgoing,
    /// Emitted only.
    Emitted,
    /// A colour per node, to show the cut.
    NodeId,
}

/// How a node is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Footprint {
    /// Splatted onto the G-buffer with radiance cache splatting's weight, over
    /// its sphere and [`SPLAT_RIM`] disc radii.
    Splat,
    /// A depth-tested disc of the node's radius in its plane (a curved node's disc faces the
    /// eye): the point-cloud view.
    Disc,
}

/// The nodes of the cut for `view`: the coarsest whose bounding spheres span at most
/// `max_pixels` on screen (leaves whatever their size), depth-first, left to right.
pub(crate) fn view_cut(senders: &Senders, view: &View, max_pixels: f32) -> Vec<u32> {
    let mut cut = Vec::new();
    let mut stack = if senders.nodes.is_empty() {
        vec![]
    } else {
        vec![0u32]
    };
    while let Some(j) = stack.pop() {
        let sender = &senders.nodes[j as usize];
        // A footprint lies within twice its node's radius (see `SPLAT_RIM`: a leaf's radius
        // is its disc's, an inner node's at least its surfels').
        if view.culls(sender.center, 2.0 * sender.radius) {
            continue;
        }
        if sender.is_leaf() || view.pixels_across(sender.center, sender.radius) <= max_pixels {
            cut.push(j);
            continue;
        }
        let [a, b] = sender.children;
        stack.extend([b, a].into_iter().filter(|&c| c != NO_NODE));
    }
    cut
}

/// The splats of `cut` as `view` sees them; `disc_radius` holds per node the mean disc
/// radius of its surfels.
pub fn splats(
    senders: &Senders,
    view: &View,
    cut: &[u32],
    colouring: Colouring,
    footprint: Footprint,
    disc_radius: &[f32],
) -> Vec<Splat> {
    cut.par_iter()
        .map(|&j| {
            let sender = &senders.nodes[j as usize];
            let w = view.towards_eye(sender.center);
            let radiance = match colouring {
                Colouring::Reflected => senders.seen(j, w, EYE_MESH, false).radiance,
                Colouring::Outgoing => {
                    senders.seen(j, w, EYE_MESH, false).radiance + senders.emitted_radiance(j, w)
                }
                Colouring::Emitted => senders.emitted_radiance(j, w),
                Colouring::NodeId => node_colour(j),
            };
            let (mut normal, flat) = if sender.is_leaf() {
                (
                    Vec3::from(senders.surfels[sender.surfel() as usize].n),
                    true,
                )
            } else {
                (sender.axis, sender.has(node_flags::FLAT))
            };
            let sides = if !flat {
                0.0
            } else if sender.has(node_flags::BACK_SIDED) {
                2.0
            } else {
                1.0
            };
            let radius = match footprint {
                Footprint::Splat => sender.radius + SPLAT_RIM * disc_radius[j as usize],
                Footprint::Disc => sender.radius,
            };
            if footprint == Footprint::Disc && !flat {
                normal = w;
            }
            Splat {
                sphere: sender.center.extend(radius).to_array(),
                normal: normal.extend(sides).to_array(),
                radiance: radiance.max(Vec3::ZERO).extend(0.0).to_array(),
            }
        })
        .collect()
}

/// A bright colour that tells node `j` from its neighbours (a hash of its index).
fn node_colour(j: u32) -> Vec3 {
    let h = j.wrapping_mul(0x9e37_79b9) ^ (j >> 16);
    let h = h.wrapping_mul(0x85eb_ca6b);
    let c = Vec3::new(
        (h & 0xff) as f32,
        ((h >> 8) & 0xff) as f32,
        ((h >> 16) & 0xff) as f32,
    ) / 255.0;
    0.2 + 0.8 * c
}

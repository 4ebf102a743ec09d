//! The view tree (docs/method.md §8.3): the surfel tree, read as a tree of receivers, lets nearby surfels
//! share the part of their gather that looks the same from all of them.
//!
//! The thesis pairs sender and receiver nodes top-down and keeps, per receiver node, the senders
//! it may share, with their microbuffers reused by children of similar normal (§8.3–§8.4). It
//! leaves the pairing order, the overlap rule and the reuse threshold open (§13 items 17–19).
//! This version takes the form the final render's FPBGI already proves (docs/method.md §3), with the
//! surfel tree instead of k-means as the clustering:
//!
//! - The receiver groups are the largest nodes of the surfel tree with at most
//!   [`GROUP_SURFELS`] surfels, all on one mesh and flat (normals within [`GROUP_CONE`] of
//!   their axis; a leaf is a group of one). Members then share one frame, and the shared
//!   buffer's lookup along their pixels is built once per group: groups on curved surfaces
//!   (normals within 10°) made cbox-glossy's bounces 1.2× slower than the per-surfel
//!   traversal, every member on its glass sphere building its own.
//! - A group shares one cut of the far senders, those whose view solid angle of the group is
//!   small (r_V/d ≤ [`VIEW_EPS`], π r_V²/d² ≤ 0.031 sr), splatted into one spherical buffer
//!   around its active member (the one nearest the node's centre), as the thesis's "entry
//!   list" of the receiver node. The thesis's 0.005 sr (ε = 0.04) shared almost nothing in a
//!   Cornell box of 20 000 surfels (1.02×, every sender within 1.25 of a group of radius
//!   0.05 is near); ε = 0.1, the final render's FPBGI threshold, keeps the bounce light
//!   within 0.5 % of the per-surfel traversal's on average (1–3 % RMS per surfel) and
//!   depth-8 renders within 0.2 % in relMSE. The speed-up is small here (1.0–1.15× per
//!   bounce at 20 000 surfels, see docs/bounces.md): in a Cornell box the near field is most
//!   of a surfel's splats.
//! - Each member refines the near senders into its own buffer and composites the shared one
//!   along its pixels' directions ([`composite_shared`]); senders that come near the members'
//!   planes are left to the members, whose traversal opens them (see [`splat_cut`]).
//!
//! [`composite_shared`]: crate::gather::fpbgi::composite_shared
//! [`splat_cut`]: crate::gather::cut::splat_cut

use crate::gather::fpbgi::Cluster;
use crate::surfels::tree::{SurfelTree, NONE};
use crate::surfels::Surfel;

/// The most surfels in one receiver group.
pub const GROUP_SURFELS: u32 = 32;

/// The widest normal cone (radians) of a receiver group: flat to rounding.
pub const GROUP_CONE: f32 = 1e-3;

/// The far threshold r_V/d of a receiver group's shared senders (see the module docs).
pub const VIEW_EPS: f32 = 0.1;

/// The receiver groups of `tree` (see the module docs), covering every surfel once: clusters
/// of surfel indices whose active member is the one nearest the node's centre and whose cone
/// is the node's normal cone.
pub(crate) fn receiver_groups(tree: &SurfelTree, surfels: &[Surfel]) -> Vec<Cluster> {
    cells(tree, surfels, GROUP_SURFELS, GROUP_CONE)
        .into_iter()
        .map(|(j, active)| {
            let node = &tree.nodes[j as usize];
            let members = &tree.order[node.first as usize..(node.first + node.count) as usize];
            group_of(members.to_vec(), active, surfels, Some(node.cone_angle))
        })
        .collect()
}

/// The receiver group of `members` around its `active` member: its radius is the farthest
/// member's distance from the active one; `cone` is the group's normal cone.
pub(crate) fn group_of(
    members: Vec<u32>,
    active: u32,
    surfels: &[Surfel],
    cone: Option<f32>,
) -> Cluster {
    let pa = surfels[active as usize].p;
    let radius = members
        .iter()
        .map(|&i| (surfels[i as usize].p - pa).length())
        .fold(0.0, f32::max);
    Cluster {
        members,
        active,
        radius,
        cone,
    }
}

/// The largest nodes of `tree` with at most `most` surfels, all on one mesh, normals within
/// `cone` of the node's axis (a leaf otherwise), covering every surfel once in tree order: each
/// node's index and its member nearest the node's centre (the lowest index on a tie).
pub fn cells(tree: &SurfelTree, surfels: &[Surfel], most: u32, cone: f32) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    let mut stack = if tree.nodes.is_empty() {
        vec![]
    } else {
        vec![0u32]
    };
    while let Some(j) = stack.pop() {
        let node = &tree.nodes[j as usize];
        let members = &tree.order[node.first as usize..(node.first + node.count) as usize];
        let Some(&first) = members.first() else {
            continue;
        };
        let mesh = surfels[first as usize].mesh;
        let cell = node.is_leaf()
            || (node.count <= most
                && node.cone_angle <= cone
                && members.iter().all(|&i| surfels[i as usize].mesh == mesh));
        if !cell {
            stack.extend(node.children.iter().rev().filter(|&&c| c != NONE));
            continue;
        }
        let distance = |i: u32| (surfels[i as usize].p - node.center).length_squared();
        let active = members
            .iter()
            .copied()
            .min_by(|&a, &b| distance(a).total_cmp(&distance(b)).then(a.cmp(&b)))
            .unwrap_or(first);
        out.push((j, active));
    }
    out
}

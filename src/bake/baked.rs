//! What a bake produces in memory, before it is written ([`super::store`]): the surfels, their
//! radiance, the tree and its coding, and what each stage took.

use super::bounce::bsdf_operator::Operators;
use super::bounce::BounceReport;
use super::plan::Plan;
use super::settings::BakeSettings;
use crate::bsdf::Bsdf;
use crate::spectrum::Rgb;
use crate::surfels::coding::CodedTree;
use crate::surfels::radiance::SurfelRadiance;
use crate::surfels::tree::SurfelTree;
use crate::surfels::Surfel;
use glam::Vec3;

/// The result of a bake.
pub struct Baked {
    /// What the bake decided before the work (storage per material, emitters, memory).
    pub plan: Plan,
    /// The settings it ran with.
    pub settings: BakeSettings,
    /// The surfels, in the order the sampler placed them.
    pub surfels: Vec<Surfel>,
    /// Each surfel's outgoing radiance (direct light and, after the bounces, indirect).
    pub radiance: Vec<SurfelRadiance>,
    /// The emitted radiance (front face) included in each surfel's `radiance`.
    pub emitted: Vec<Rgb>,
    /// Per mesh: its surfels' flags ([`mesh_flags`](crate::surfels::radiance::mesh_flags)).
    pub mesh_flags: Vec<u32>,
    /// Per surfel: its BSDF (textures looked up).
    pub bsdfs: Vec<Bsdf>,
    /// Per surfel: the normal its BSDF's frame is around ([`surfel_shading_normal`](super::pipeline::surfel_shading_normal)).
    pub shading_normals: Vec<Vec3>,
    /// The BSDF operators built so far (the direct light's, for the bounces to reuse).
    pub operators: Operators,
    /// The bounding-sphere tree over the surfels.
    pub tree: SurfelTree,
    /// Radiant intensity I(ω) of every node (RGB).
    pub coded: CodedTree<Rgb>,
    /// Projected area P(ω) of every node, on an 8 × 8 map: a node seen from afar subtends
    /// P/d² and has radiance I/P (docs/design.md §5.5).
    pub projected: CodedTree<f32>,
    /// Seconds per stage, in order.
    pub timings: Vec<(&'static str, f64)>,
    /// What the indirect bounces did, if any ran.
    pub bounces: Option<BounceReport>,
}

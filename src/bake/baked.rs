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
    pub plan: Plan,
    pub settings: BakeSettings,
    pub surfels: Vec<Surfel>,
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

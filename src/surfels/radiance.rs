//! What a surfel sends: its direct-lit outgoing radiance ([`SurfelRadiance`]), its radiant
//! intensity as the tree's leaf functions see it ([`intensity_map`]) and its projected area,
//! and the per-mesh flags that decide which sides count. The bake writes these, the bounces
//! and the gather read them; so they live here, below all three.

use super::Surfel;
use crate::bsdf::Bsdf;
use crate::haar::{texel_directions, Haar2d, SparseHaar};
use crate::scene::Scene;
use crate::spectrum::Rgb;
use glam::Vec3;

/// A surfel's direct-lit outgoing radiance.
#[derive(Clone, Debug, PartialEq)]
pub enum SurfelRadiance {
    /// Diffuse: the same radiance towards every direction of the front hemisphere.
    Rgb(Rgb),
    /// Directional: a thresholded map over the whole sphere.
    Map(SparseHaar<Rgb>),
}

/// A surfel record's flag (`crate::cache::store::SurfelRecord::flags`): the surfel bounds a
/// solid.
pub const SOLID: u32 = 1;

/// A surfel record's flag: the surfel's intensity includes what it sends from its back (see
/// [`mesh_flags`]).
pub const BACK_SIDED: u32 = 2;

/// A surfel record's flag: the surfel lies on a closed mesh, whose back faces a receiver
/// outside it cannot see ([`crate::scene::Mesh::is_closed`]).
pub const CLOSED: u32 = 4;

/// Per mesh, the flags of its surfels' records (`crate::cache::store::SurfelRecord::flags`), from
/// its BSDF at texture coordinate (0, 0) and its geometry:
/// - [`SOLID`]: it bounds a solid (a `roughdielectric`: Mitsuba's dielectric is the interface
///   of a solid). Light a surfel of a solid sends into it can reach only the solid's own
///   surface before it crosses the surface again, so the tree, which everyone sees, holds
///   only what such surfels send outwards (their maps keep both sides for their own solid).
/// - [`BACK_SIDED`]: its surfels send light from their back as well as their front into the
///   tree's intensity (thin sheets: two-sided BSDFs that bound no solid; see
///   [`intensity_map`]). The other surfels' intensity is front-only, so a node of them has
///   radiance I/P⁺ with P⁺ its front projected area.
/// - [`CLOSED`]: the mesh is closed ([`crate::scene::Mesh::is_closed`]).
pub fn mesh_flags(scene: &Scene) -> Vec<u32> {
    scene
        .meshes
        .iter()
        .map(|m| {
            let bsdf = scene.materials[m.material].bsdf_at(&scene.textures, glam::Vec2::ZERO);
            let solid = matches!(bsdf, Bsdf::Dielectric(_));
            let back_sided = !solid && bsdf.is_two_sided();
            [
                (solid, SOLID),
                (back_sided, BACK_SIDED),
                (m.is_closed(), CLOSED),
            ]
            .iter()
            .filter(|(set, _)| *set)
            .fold(0, |flags, (_, bit)| flags | bit)
        })
        .collect()
}

/// Surfel `i`'s [`intensity_map`] in the light `radiance` (one per surfel), the lower half
/// of a map kept where its mesh is not a closed solid (`mesh_flags`): the tree's leaf
/// functions, for the cache's coding and the bounces' node sums alike.
pub(crate) fn intensity_of<'a>(
    surfels: &'a [Surfel],
    mesh_flags: &'a [u32],
    radiance: &'a [SurfelRadiance],
) -> impl Fn(u32) -> SparseHaar<Rgb> + Sync + 'a {
    move |i| {
        let s = &surfels[i as usize];
        let back = mesh_flags[s.mesh as usize] & SOLID == 0;
        intensity_map(s.n, s.area, &radiance[i as usize], back)
    }
}

/// The radiant intensity A |n·ω| L(ω) of a surfel of normal `n` and area `area` in radiance
/// `r`, as a map at its own resolution (the diffuse cosine lobe's [`PROJECTED_AREA_LEVELS`],
/// or its radiance map's); with `back` false, only towards the front hemisphere (see
/// [`mesh_flags`]).
///
/// The cosine is taken at the centre of the projected-area map's texel
/// ([`PROJECTED_AREA_LEVELS`]) that holds each texel, L at the texel's own centre. A node's
/// radiance is I/P texel by texel, and with both on one cosine grid it is a mean of its
/// surfels' radiance, exactly: a 16² glossy I over the 8² P strayed by 3 % in a closed room,
/// and sampling P as finely as I tripled a glossy cache (P and the cosine lobes of diffuse
/// nodes at 64²).
///
/// The result is exact and sparse (every non-zero coefficient, no dense transform of a map):
/// the cosine being constant on the 8² cells, L's finer details are scaled by it, and only
/// the 8² means go through a transform ([`SparseHaar::scaled_by_cells`]).
pub fn intensity_map(n: Vec3, area: f32, r: &SurfelRadiance, back: bool) -> SparseHaar<Rgb> {
    let coarse = match r {
        SurfelRadiance::Rgb(_) => PROJECTED_AREA_LEVELS,
        SurfelRadiance::Map(m) => m.levels().min(PROJECTED_AREA_LEVELS),
    };
    let factors: Vec<f32> = texel_directions(coarse)
        .iter()
        .map(|w| {
            let cos = w.dot(n);
            // Diffuse surfels radiate from the front only; maps carry their own lower half.
            let projected = match r {
                SurfelRadiance::Map(_) if back => cos.abs(),
                _ => cos.max(0.0),
            };
            area * projected
        })
        .collect();
    match r {
        // Diffuse radiance is constant, so its intensity is a cosine lobe on P's grid.
        SurfelRadiance::Rgb(c) => {
            let texels: Vec<Rgb> = factors.iter().map(|f| *c * *f).collect();
            SparseHaar::compress_below(&Haar2d::forward(&texels, 1 << coarse), 0.0)
        }
        // The cosine is constant on the cells of level `coarse`: L's finer details scale by
        // it, its coarser ones are the transform of the cells' means times it.
        SurfelRadiance::Map(m) => m.scaled_by_cells(coarse, &factors),
    }
}

/// The resolution of projected-area maps, and of the cosine in intensity maps: P(ω) is a sum
/// of clamped cosines, smooth enough for 8 × 8. Finer costs memory for little: at 16² the
/// glossy box's depth-3 relMSE is 5.9e-4 instead of 7.1e-4 (a glossy node's surfels are
/// weighted by the cosine at the 8² texel's centre, up to 13° off), but cbox-rough's cache
/// doubles (cosine lobes of every diffuse node at 16²), and at the maps' own 64² cbox-glossy's
/// tripled.
pub const PROJECTED_AREA_LEVELS: u32 = 3;

/// A surfel's projected area A |n·ω| on the 8 × 8 map. Both sides count: a disc occludes from
/// behind as from the front (its radiance there, I/P, is simply what it emits backwards).
pub(crate) fn projected_area_map(s: &Surfel) -> Haar2d<f32> {
    let texels: Vec<f32> = texel_directions(PROJECTED_AREA_LEVELS)
        .iter()
        .map(|w| s.area * w.dot(s.n).abs())
        .collect();
    Haar2d::forward(&texels, 1 << PROJECTED_AREA_LEVELS)
}
/// Directional resolution (log2 of the octahedral map side) a BSDF needs, from its roughness:
/// α ≥ 0.5 → 8², ≥ 0.1 → 16², ≥ 0.03 → 32², smaller → 64² (docs/design.md §5.4). `None` for a
/// diffuse BSDF, whose surfels store RGB only.
pub fn map_levels(bsdf: &Bsdf) -> Option<u32> {
    let alpha = bsdf.alpha()?;
    Some(if alpha >= 0.5 {
        3
    } else if alpha >= 0.1 {
        4
    } else if alpha >= 0.03 {
        5
    } else {
        6
    })
}

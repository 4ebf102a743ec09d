//! Which surfels gather in a bounce, and how the others take their light.
//!
//! A bounce's light varies slowly along a surface: it is light already scattered at least once,
//! and the final render gathers it again through its own microbuffers, which average many
//! surfels. So a bounce need not gather at every surfel. About one surfel in `stride` gathers
//! (the one nearest the centre of each largest tree node of at most `stride` surfels on one
//! mesh, within [`CELL_CONE`]), and each other surfel blends the gathered light of its
//! [`NEIGHBOURS`] nearest gathering surfels of the same mesh and kind (RGB, or maps of the same
//! resolution) whose normals are within [`CELL_CONE`] of its own, by inverse squared distance
//! (Shepard's weights, regularised by the surfel's own radius so that a neighbour at distance
//! zero does not take all the weight): irradiance caching's interpolation (Ward, Rubinstein and
//! Clear 1988) in its simplest form, as production light caches use it.
//!
//! Diffuse surfels blend the gathered sum before their own reflectance multiplies it, so a
//! textured albedo stays sharp. Directional surfels blend their outgoing sphere maps (in world
//! directions) only with neighbours of the same normal ([`DIRECTIONAL_CONE`]): on flat faces,
//! not on a curved glass. A surfel with no such
//! neighbour within [`SEARCH_SPACINGS`] receiver spacings gathers itself: corners, thin strips
//! and small objects keep their own gathers.
//!
//! Everything here is geometry, fixed before the first bounce, in a fixed order: the cache
//! does not depend on the thread count.

use super::view_tree::{cells, group_of};
use crate::gather::fpbgi::Cluster;
use crate::haar::SparseHaar;
use crate::spectrum::Rgb;
use crate::surfels::radiance::SurfelRadiance;
use crate::surfels::tree::SurfelTree;
use crate::surfels::Surfel;
use glam::Vec3;
use rayon::prelude::*;
use std::collections::HashMap;

/// The widest normal cone (radians) of a cell that shares one receiver, and the widest angle
/// between a surfel's normal and a neighbour's it blends: about 25°, enough for a sphere of a
/// few hundred surfels, too little to blend across a box's edge.
pub const CELL_CONE: f32 = 0.45;

/// The widest angle (radians) between a directional surfel's normal and a neighbour's it
/// blends: flat to rounding. Blending the maps of a curved glass surface blurs what it
/// focuses (cbox-rough's caustic: relMSE +2 % at a stride of 4, +10 % at 16, against none
/// with this cone), so there every surfel gathers.
pub const DIRECTIONAL_CONE: f32 = 1e-3;

/// Gathering neighbours a surfel blends.
pub const NEIGHBOURS: usize = 4;

/// How far (in receiver spacings, the square root of the mean surfel area times the stride) a
/// surfel looks for gathering neighbours.
pub const SEARCH_SPACINGS: f32 = 2.0;

/// The surfels that gather, and the blend of every other one.
pub struct Receivers {
    gathers: Vec<bool>,
    blends: Vec<Blend>,
}

/// A surfel that does not gather, and the gathering surfels it takes its light from with
/// their weights (summing to 1, in ascending distance).
struct Blend {
    surfel: u32,
    from: Vec<(u32, f32)>,
}

impl Receivers {
    /// The receivers of `surfels` (tree `tree`) at about one in `stride` (1: every surfel
    /// gathers). `kind[i]` tells which surfels may blend each other's light: surfels of one
    /// mesh with the same kind (the map resolution, or `None` for RGB).
    pub(crate) fn choose(
        tree: &SurfelTree,
        surfels: &[Surfel],
        kind: &[Option<u32>],
        stride: u32,
    ) -> Receivers {
        let n = surfels.len();
        if stride <= 1 || n == 0 {
            return Receivers {
                gathers: vec![true; n],
                blends: Vec::new(),
            };
        }
        let mut gathers = vec![false; n];
        for (_, active) in cells(tree, surfels, stride, CELL_CONE) {
            gathers[active as usize] = true;
        }
        let mean_area = surfels.iter().map(|s| f64::from(s.area)).sum::<f64>() / n as f64;
        let reach = SEARCH_SPACINGS * (mean_area * f64::from(stride)).sqrt() as f32;
        let grid = Grid::new(
            surfels,
            (0..n as u32).filter(|&i| gathers[i as usize]),
            reach,
        );
        let (cos_diffuse, cos_directional) = (CELL_CONE.cos(), DIRECTIONAL_CONE.cos());
        let found: Vec<Option<Blend>> = (0..n as u32)
            .into_par_iter()
            .map(|i| {
                if gathers[i as usize] {
                    return None;
                }
                let s = &surfels[i as usize];
                let cos_cone = if kind[i as usize].is_some() {
                    cos_directional
                } else {
                    cos_diffuse
                };
                let mut near: Vec<(f32, u32)> = grid
                    .around(s.p)
                    .filter(|&j| {
                        let t = &surfels[j as usize];
                        t.mesh == s.mesh
                            && kind[j as usize] == kind[i as usize]
                            && t.n.dot(s.n) >= cos_cone
                    })
                    .map(|j| ((surfels[j as usize].p - s.p).length_squared(), j))
                    .filter(|&(d2, _)| d2 <= reach * reach)
                    .collect();
                near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                near.truncate(NEIGHBOURS);
                let r2 = s.area / std::f32::consts::PI;
                let weights: Vec<(u32, f32)> = near
                    .iter()
                    .map(|&(d2, j)| (j, 1.0 / (d2 + r2).max(1e-20)))
                    .collect();
                let total: f32 = weights.iter().map(|w| w.1).sum();
                Some(Blend {
                    surfel: i,
                    from: weights.into_iter().map(|(j, w)| (j, w / total)).collect(),
                })
            })
            .collect();
        let mut blends = Vec::new();
        for b in found.into_iter().flatten() {
            if b.from.is_empty() {
                gathers[b.surfel as usize] = true;
            } else {
                blends.push(b);
            }
        }
        Receivers { gathers, blends }
    }

    /// Whether surfel `i` gathers.
    pub fn gathers(&self, i: u32) -> bool {
        self.gathers[i as usize]
    }

    /// Surfels that gather.
    pub fn count(&self) -> usize {
        self.gathers.iter().filter(|&&g| g).count()
    }

    /// `groups` with only their gathering members; a group left without one is dropped, and
    /// one whose active member does not gather takes the gathering member nearest it.
    pub fn groups(&self, groups: Vec<Cluster>, surfels: &[Surfel]) -> Vec<Cluster> {
        groups
            .into_iter()
            .filter_map(|g| {
                let members: Vec<u32> = g
                    .members
                    .iter()
                    .copied()
                    .filter(|&i| self.gathers[i as usize])
                    .collect();
                if members.len() == g.members.len() {
                    return Some(g);
                }
                let centre = surfels[g.active as usize].p;
                let distance = |i: u32| (surfels[i as usize].p - centre).length_squared();
                let active = members
                    .iter()
                    .copied()
                    .min_by(|&a, &b| distance(a).total_cmp(&distance(b)).then(a.cmp(&b)))?;
                Some(group_of(members, active, surfels, g.cone))
            })
            .collect()
    }

    /// Fill the light of every surfel that does not gather from its neighbours' in `light`
    /// (maps thresholded at `tau`).
    pub fn blend(&self, light: &mut [SurfelRadiance], tau: f32) {
        let blended: Vec<SurfelRadiance> = self
            .blends
            .par_iter()
            .map(|b| blend_of(&b.from, light, tau))
            .collect();
        for (b, l) in self.blends.iter().zip(blended) {
            light[b.surfel as usize] = l;
        }
    }
}

/// Σ w·light\[j\] over `from` (gathering surfels, all of one kind).
fn blend_of(from: &[(u32, f32)], light: &[SurfelRadiance], tau: f32) -> SurfelRadiance {
    let mut rgb = Rgb::ZERO;
    let mut maps: Vec<(&SparseHaar<Rgb>, f32)> = Vec::new();
    for &(j, w) in from {
        match &light[j as usize] {
            SurfelRadiance::Rgb(c) => rgb += *c * w,
            SurfelRadiance::Map(m) => maps.push((m, w)),
        }
    }
    if maps.is_empty() {
        SurfelRadiance::Rgb(rgb)
    } else {
        SurfelRadiance::Map(SparseHaar::weighted_sum(&maps, tau))
    }
}

/// Gathering surfels bucketed by position in cubes of the search reach: a surfel's candidates
/// are those of the 27 cubes around it.
struct Grid {
    cell: f32,
    cells: HashMap<[i32; 3], Vec<u32>>,
}

impl Grid {
    fn new(surfels: &[Surfel], members: impl Iterator<Item = u32>, cell: f32) -> Self {
        let mut grid = Grid {
            cell: cell.max(f32::MIN_POSITIVE),
            cells: HashMap::new(),
        };
        for i in members {
            let key = grid.key(surfels[i as usize].p);
            grid.cells.entry(key).or_default().push(i);
        }
        grid
    }

    fn key(&self, p: Vec3) -> [i32; 3] {
        (p / self.cell).floor().as_ivec3().to_array()
    }

    /// The members in the 27 cubes around `p` (a superset of those within one cube's side).
    fn around(&self, p: Vec3) -> impl Iterator<Item = u32> + '_ {
        let [x, y, z] = self.key(p);
        (-1..=1)
            .flat_map(move |dx| (-1..=1).flat_map(move |dy| (-1..=1).map(move |dz| (dx, dy, dz))))
            .filter_map(move |(dx, dy, dz)| self.cells.get(&[x + dx, y + dy, z + dz]))
            .flatten()
            .copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat square of `side²` surfels on one mesh, spacing 1.
    fn square(side: u32) -> Vec<Surfel> {
        (0..side * side)
            .map(|k| Surfel {
                p: Vec3::new((k % side) as f32, (k / side) as f32, 0.0),
                n: Vec3::Z,
                area: 1.0,
                mesh: 0,
                triangle: 0,
                b: glam::Vec2::ZERO,
            })
            .collect()
    }

    #[test]
    fn a_stride_of_one_gathers_everywhere() {
        let s = square(8);
        let tree = SurfelTree::build(&s);
        let r = Receivers::choose(&tree, &s, &vec![None; s.len()], 1);
        assert_eq!(r.count(), s.len());
        assert!(r.blends.is_empty());
    }

    #[test]
    fn blends_are_convex_and_keep_constants() {
        let s = square(32);
        let tree = SurfelTree::build(&s);
        let r = Receivers::choose(&tree, &s, &vec![None; s.len()], 4);
        // About a quarter gather (cells are the largest nodes of at most 4 surfels).
        let share = r.count() as f32 / s.len() as f32;
        assert!((0.2..=0.4).contains(&share), "{share}");
        for b in &r.blends {
            let total: f32 = b.from.iter().map(|f| f.1).sum();
            assert!((total - 1.0).abs() < 1e-5);
            assert!(b.from.iter().all(|&(j, _)| r.gathers[j as usize]));
        }
        // A constant stays exactly constant; a linear ramp stays within the ramp's range of
        // one receiver spacing (the weights are convex).
        let mut light: Vec<SurfelRadiance> = s
            .iter()
            .map(|p| SurfelRadiance::Rgb(Rgb::new(1.0, p.p.x, 0.0)))
            .collect();
        let before = light.clone();
        r.blend(&mut light, 0.0);
        for (i, (a, b)) in light.iter().zip(&before).enumerate() {
            let (SurfelRadiance::Rgb(a), SurfelRadiance::Rgb(b)) = (a, b) else {
                panic!("kinds changed");
            };
            assert!((a.x - 1.0).abs() < 1e-5, "surfel {i}: {a:?}");
            let reach = SEARCH_SPACINGS * 4f32.sqrt();
            assert!(
                (a.y - b.y).abs() <= reach,
                "surfel {i}: {a:?} against {b:?}"
            );
        }
    }

    #[test]
    fn surfels_across_an_edge_do_not_blend() {
        // Two perpendicular strips of one mesh: no surfel blends light from the other face.
        let mut s = square(16);
        let wall: Vec<Surfel> = square(16)
            .into_iter()
            .map(|mut t| {
                t.p = Vec3::new(t.p.x, -1.0, t.p.y + 1.0);
                t.n = Vec3::Y;
                t
            })
            .collect();
        s.extend(wall);
        let tree = SurfelTree::build(&s);
        let r = Receivers::choose(&tree, &s, &vec![None; s.len()], 4);
        assert!(r.blends.len() > s.len() / 2);
        for b in &r.blends {
            let n = s[b.surfel as usize].n;
            assert!(b.from.iter().all(|&(j, _)| s[j as usize].n == n));
        }
    }
}

//! The scene's triangle meshes: world-space positions, optional normals and texture
//! coordinates, and the queries every stage makes of them.

use glam::{Vec2, Vec3, Vec3A};

/// A triangle mesh in world space.
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Its name in the scene (a glTF mesh's, a USD prim path), for errors.
    pub name: String,
    /// Vertex positions (world space).
    pub positions: Vec<Vec3>,
    /// Unit shading normals per vertex; `None` means flat shading with the face normal.
    pub normals: Option<Vec<Vec3>>,
    /// Texture coordinates per vertex, if any.
    pub uvs: Option<Vec<Vec2>>,
    /// Triangles as three vertex indices, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    /// Index into the scene's materials.
    pub material: usize,
}

impl Mesh {
    /// Whether the mesh is closed and consistently wound: with vertices welded by position,
    /// every edge of a non-degenerate triangle is met once in each direction. Such a surface
    /// bounds a volume, and from outside it its back faces lie behind its front faces.
    pub fn is_closed(&self) -> bool {
        use std::collections::HashMap;
        let mut weld: HashMap<[u32; 3], u32> = HashMap::new();
        let ids: Vec<u32> = self
            .positions
            .iter()
            .map(|p| {
                let next = weld.len() as u32;
                *weld.entry(p.to_array().map(f32::to_bits)).or_insert(next)
            })
            .collect();
        // Per undirected edge (low, high): how often it is met low → high and high → low.
        let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
        for t in &self.triangles {
            let Some(v) = t
                .iter()
                .map(|&i| ids.get(i as usize).copied())
                .collect::<Option<Vec<_>>>()
            else {
                return false;
            };
            if v[0] == v[1] || v[1] == v[2] || v[2] == v[0] {
                continue;
            }
            for (a, b) in [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])] {
                let e = edges.entry((a.min(b), a.max(b))).or_default();
                if a < b {
                    e.0 += 1;
                } else {
                    e.1 += 1;
                }
            }
        }
        !edges.is_empty() && edges.values().all(|&c| c == (1, 1))
    }

    /// The corners of triangle `tri`, as the ray tests and the hit-point bounds take them.
    pub(crate) fn corners(&self, tri: u32) -> [Vec3A; 3] {
        self.triangles[tri as usize].map(|k| Vec3A::from(self.positions[k as usize]))
    }

    /// The unit geometric normal of the front face (counter-clockwise winding) of the
    /// triangle with corners `v`, as a hit and an emitter sample report it.
    pub(crate) fn geometric_normal(v: [Vec3A; 3]) -> Vec3 {
        Vec3::from((v[1] - v[0]).cross(v[2] - v[0])).normalize()
    }

    /// The texture coordinate at barycentric weights `b` of triangle `tri` ((0, 0) without UVs).
    pub fn uv_at(&self, tri: u32, b: [f32; 3]) -> Vec2 {
        interpolate_uv(self.uvs.as_deref(), self.triangles[tri as usize], b)
    }

    /// The unit interpolated vertex normal at barycentric weights `b` of triangle `tri`, or
    /// `None` for a flat mesh (or normals that cancel there).
    pub(crate) fn normal_at(&self, tri: u32, b: [f32; 3]) -> Option<Vec3> {
        let n = self.normals.as_ref()?;
        let t = self.triangles[tri as usize];
        (b[0] * n[t[0] as usize] + b[1] * n[t[1] as usize] + b[2] * n[t[2] as usize])
            .try_normalize()
    }
}

/// The texture coordinate at barycentric weights `b` of the triangle with vertices `t`, from
/// per-vertex `uvs` ((0, 0) without them): [`Mesh::uv_at`] for data kept apart from its mesh.
pub fn interpolate_uv(uvs: Option<&[Vec2]>, t: [u32; 3], b: [f32; 3]) -> Vec2 {
    match uvs {
        Some(uv) => b[0] * uv[t[0] as usize] + b[1] * uv[t[1] as usize] + b[2] * uv[t[2] as usize],
        None => Vec2::ZERO,
    }
}

/// Remove the zero-area (and non-finite) triangles of `triangles` over `positions`; returns
/// how many were removed.
pub(crate) fn drop_degenerate(positions: &[Vec3], triangles: &mut Vec<[u32; 3]>) -> usize {
    let before = triangles.len();
    triangles.retain(|t| {
        let (a, b, c) = (
            positions[t[0] as usize],
            positions[t[1] as usize],
            positions[t[2] as usize],
        );
        let area2 = (b - a).cross(c - a).length();
        area2 > 0.0 && area2.is_finite()
    });
    before - triangles.len()
}

//! Tangent-space normal maps (glTF `normalTexture`, UsdPreviewSurface's `normal` input): the
//! shading normal a map tilts, at a hit or a surfel.
//!
//! The map's texel, read linearly with its reference's scale and bias, is the normal in the
//! frame (tangent, bitangent, shading normal), where the tangent points right in the image and
//! the bitangent up: glTF's convention ("+X is right and +Y is up") and UsdPreviewSurface's
//! (+Y along +t, which is up in the image). The frame comes from the triangle's texture
//! coordinates as they land on the image (so glTF's downward v and USD's upward t both come
//! right): T = ∂p/∂x, B = −∂p/∂y, made orthogonal to the shading normal, B's handedness kept
//! so that mirrored texture coordinates mirror the map.
//!
//! Decisions:
//! - The tangent is the triangle's own (as pbrt's ∂p/∂u), not MikkTSpace's vertex tangents,
//!   nor glTF's `TANGENT` attribute: the two agree on a flat or evenly mapped triangle, and
//!   differ where a mesh's tangents are smoothed across triangles (docs/scene.md).
//! - A tilted normal that would lie on the other side of the surface than the interpolated
//!   one (a steep map at a grazing triangle) is not used: the interpolated normal stays.

use super::mesh::Mesh;
use super::texture::{TexRef, Texture};
use glam::{Vec2, Vec3};

/// A tangent-space normal map: `texture`'s RGB after its scale and bias is the normal in the
/// tangent frame (glTF: scale 2 and bias −1, x and y times `normalTexture.scale`).
#[derive(Clone, Copy, Debug)]
pub struct NormalMap {
    /// The tangent-space normal image.
    pub texture: TexRef,
}

impl NormalMap {
    /// The shading normal at texture coordinate `uv` on `triangle` of `mesh`, whose
    /// interpolated (or geometric) normal is `ns`: tilted by the map, or `ns` where the
    /// triangle has no usable texture coordinates or the map's normal is degenerate.
    pub(crate) fn shading_normal(
        &self,
        textures: &[Texture],
        mesh: &Mesh,
        triangle: u32,
        uv: Vec2,
        ns: Vec3,
    ) -> Vec3 {
        let Some((tangent, bitangent)) = self.tangent_frame(mesh, triangle, ns) else {
            return ns;
        };
        let m = self.texture.sample(textures, uv).truncate();
        let tilted = (tangent * m.x + bitangent * m.y + ns * m.z).try_normalize();
        match tilted {
            Some(n) if n.is_finite() && n.dot(ns) > 0.0 => n,
            _ => ns,
        }
    }

    /// Unit tangent and bitangent of `triangle` around `ns` (see the module docs).
    fn tangent_frame(&self, mesh: &Mesh, triangle: u32, ns: Vec3) -> Option<(Vec3, Vec3)> {
        let uvs = mesh.uvs.as_ref()?;
        let t = mesh.triangles.get(triangle as usize)?;
        let p = t.map(|k| mesh.positions[k as usize]);
        let q = t.map(|k| self.texture.transform.transform_point2(uvs[k as usize]));
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let (d1, d2) = (q[1] - q[0], q[2] - q[0]);
        let det = d1.x * d2.y - d1.y * d2.x;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let dpdx = (e1 * d2.y - e2 * d1.y) / det;
        let dpdy = (e2 * d1.x - e1 * d2.x) / det;
        let tangent = (dpdx - ns * ns.dot(dpdx)).try_normalize()?;
        let up = -dpdy;
        let handedness = if ns.cross(tangent).dot(up) < 0.0 {
            -1.0
        } else {
            1.0
        };
        Some((tangent, ns.cross(tangent) * handedness))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::texture::Wrap;
    use glam::{Affine2, Vec4};

    /// A unit quad in the xz plane facing +y, with texture coordinates (x, z) — glTF's v runs
    /// down the image, so +z is down — and a one-texel map.
    fn quad_and_map(texel: Vec4, transform: Affine2) -> (Mesh, Vec<Texture>, NormalMap) {
        let mesh = Mesh {
            name: "quad".into(),
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(0.0, 0.0, 1.0),
            ],
            normals: None,
            uvs: Some(vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 1.0),
            ]),
            triangles: vec![[0, 2, 1], [0, 3, 2]],
            material: 0,
        };
        let texture = Texture {
            name: "n".into(),
            width: 1,
            height: 1,
            texels: vec![texel],
        };
        let map = NormalMap {
            texture: TexRef {
                texture: 0,
                wrap_s: Wrap::Repeat,
                wrap_t: Wrap::Repeat,
                transform,
                srgb: false,
                scale: Vec4::new(2.0, 2.0, 2.0, 1.0),
                bias: Vec4::new(-1.0, -1.0, -1.0, 0.0),
            },
        };
        (mesh, vec![texture], map)
    }

    /// A flat texel (0.5, 0.5, 1) leaves the normal; a texel tilted towards +X leans the
    /// normal towards +x (right in the image), towards +Y towards −z (up in glTF's image);
    /// with USD's flip of t (image y = 1 − t, t along +z) up is +z.
    #[test]
    fn the_map_tilts_the_normal_along_the_image_axes() {
        let up = Vec3::Y;
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let texel =
            |x: f32, y: f32, z: f32| Vec4::new(0.5 * x + 0.5, 0.5 * y + 0.5, 0.5 * z + 0.5, 1.0);
        let gltf = Affine2::IDENTITY;
        let usd = Affine2::from_scale_angle_translation(Vec2::new(1.0, -1.0), 0.0, Vec2::Y);
        for (t, transform, expected) in [
            (texel(0.0, 0.0, 1.0), gltf, up),
            (texel(s, 0.0, s), gltf, Vec3::new(s, s, 0.0)),
            (texel(0.0, s, s), gltf, Vec3::new(0.0, s, -s)),
            (texel(0.0, s, s), usd, Vec3::new(0.0, s, s)),
        ] {
            let (mesh, textures, map) = quad_and_map(t, transform);
            for triangle in 0..2 {
                let n = map.shading_normal(&textures, &mesh, triangle, Vec2::splat(0.3), up);
                assert!(
                    (n - expected).length() < 1e-5,
                    "texel {t}: {n}, expected {expected}"
                );
            }
        }
    }

    /// A normal the map would tip below the surface (the texel (1, 0.5, 0) is (1, 0, −1) in
    /// the tangent frame) is not used.
    #[test]
    fn a_normal_below_the_surface_is_refused() {
        let (mesh, textures, map) = quad_and_map(Vec4::new(1.0, 0.5, 0.0, 1.0), Affine2::IDENTITY);
        let tilted = map.shading_normal(&textures, &mesh, 0, Vec2::splat(0.3), Vec3::Y);
        assert_eq!(tilted, Vec3::Y);
    }
}

//! Texture images and their lookup (bilinear, glTF wrap modes, KHR_texture_transform).

use glam::{Affine2, Vec2, Vec4};

/// How texture coordinates outside [0, 1] are folded back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    Clamp,
    Mirror,
}

/// A decoded image with values in [0, 1] as stored (not yet linearised).
#[derive(Clone, Debug)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec4>,
}

/// A material's reference to a texture: which image, with which sampler and UV transform.
#[derive(Clone, Copy, Debug)]
pub struct TexRef {
    pub texture: usize,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
    /// KHR_texture_transform (identity without the extension).
    pub transform: Affine2,
    /// Colour data (base colour, emission) is sRGB-encoded; data maps are linear.
    pub srgb: bool,
}

fn wrap(x: i64, n: u32, mode: Wrap) -> u32 {
    let n = n as i64;
    let i = match mode {
        Wrap::Repeat => x.rem_euclid(n),
        Wrap::Clamp => x.clamp(0, n - 1),
        Wrap::Mirror => {
            let p = x.rem_euclid(2 * n);
            if p < n {
                p
            } else {
                2 * n - 1 - p
            }
        }
    };
    i as u32
}

/// sRGB transfer function to linear.
#[inline]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl TexRef {
    /// Bilinearly filtered, linear value at texture coordinate `uv`.
    pub fn sample(&self, textures: &[Texture], uv: Vec2) -> Vec4 {
        let Some(tex) = textures.get(self.texture) else {
            return Vec4::ONE;
        };
        let uv = self.transform.transform_point2(uv);
        if !uv.is_finite() {
            return Vec4::ONE;
        }
        let x = uv.x * tex.width as f32 - 0.5;
        let y = uv.y * tex.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let fetch = |i: i64, j: i64| {
            let i = wrap(i, tex.width, self.wrap_s);
            let j = wrap(j, tex.height, self.wrap_t);
            let t = tex.texels[(j * tex.width + i) as usize];
            if self.srgb {
                Vec4::new(
                    srgb_to_linear(t.x),
                    srgb_to_linear(t.y),
                    srgb_to_linear(t.z),
                    t.w,
                )
            } else {
                t
            }
        };
        let (i, j) = (x0 as i64, y0 as i64);
        let top = fetch(i, j).lerp(fetch(i + 1, j), fx);
        let bottom = fetch(i, j + 1).lerp(fetch(i + 1, j + 1), fx);
        top.lerp(bottom, fy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_modes() {
        assert_eq!(wrap(-1, 4, Wrap::Repeat), 3);
        assert_eq!(wrap(5, 4, Wrap::Clamp), 3);
        assert_eq!(wrap(4, 4, Wrap::Mirror), 3);
        assert_eq!(wrap(-1, 4, Wrap::Mirror), 0);
    }
}

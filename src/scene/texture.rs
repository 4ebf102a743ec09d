//! Texture images and their lookup: bilinear filtering, glTF's and UsdUVTexture's wrap modes,
//! KHR_texture_transform or UsdTransform2d, and UsdUVTexture's `scale` and `bias`.

use glam::{Affine2, Vec2, Vec4};

/// How texture coordinates outside [0, 1] are folded back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// The image tiles the plane.
    Repeat,
    /// Coordinates are clamped to the edge texels.
    Clamp,
    /// The image tiles the plane, every other copy mirrored.
    Mirror,
    /// Texels outside the image are black (UsdUVTexture's `black`).
    Black,
}

/// A decoded image with values as stored (colour data not yet linearised; HDR formats may
/// exceed 1).
#[derive(Clone, Debug)]
pub struct Texture {
    /// The file or prim it came from, for errors.
    pub name: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// RGBA texels, row by row from the top.
    pub texels: Vec<Vec4>,
}

/// A material's reference to a texture: which image, with which sampler and UV transform.
#[derive(Clone, Copy, Debug)]
pub struct TexRef {
    /// Index into the scene's textures.
    pub texture: usize,
    /// Wrap along u.
    pub wrap_s: Wrap,
    /// Wrap along v.
    pub wrap_t: Wrap,
    /// From the mesh's texture coordinate to the image's, where (0, 0) is the top-left corner
    /// of the image (KHR_texture_transform; for USD, UsdTransform2d and the flip of t).
    pub transform: Affine2,
    /// Colour data (base colour, emission) is sRGB-encoded; data maps are linear.
    pub srgb: bool,
    /// Applied to the linear value: `value × scale + bias` (UsdUVTexture; 1 and 0 for glTF).
    pub scale: Vec4,
    /// See `scale`.
    pub bias: Vec4,
}

/// One channel of a texture, for a scalar parameter (glTF's roughness in G and metalness in B
/// of one image, or a UsdUVTexture's `outputs:r`).
#[derive(Clone, Copy, Debug)]
pub struct ChannelRef {
    /// The image and its sampler.
    pub texture: TexRef,
    /// 0 to 3 for r, g, b, a.
    pub channel: usize,
}

impl ChannelRef {
    /// The channel's value at `uv`, bilinearly filtered.
    pub fn sample(&self, textures: &[Texture], uv: Vec2) -> f32 {
        self.texture.sample(textures, uv)[self.channel.min(3)]
    }
}

impl Texture {
    /// Turn sRGB-encoded colour channels into linear ones (alpha stays as it is).
    pub(crate) fn linearise_srgb(&mut self) {
        for t in &mut self.texels {
            *t = Vec4::new(
                srgb_to_linear(t.x),
                srgb_to_linear(t.y),
                srgb_to_linear(t.z),
                t.w,
            );
        }
    }

    /// Decode a PNG, JPEG, TGA, Radiance HDR or OpenEXR image from `bytes`; the format is
    /// the one `name`'s extension says, or else the one its first bytes say. Also says whether
    /// the image is what UsdUVTexture's `auto` colour space reads as sRGB: 8 bits per channel
    /// with 3 or 4 channels. Non-finite texels become 0.
    pub fn decode(name: &str, bytes: &[u8]) -> Result<(Texture, bool), String> {
        // Package members are named `pkg.usdz[dir/image.tga]`.
        let file = name.trim_end_matches(']');
        let img = match image::ImageFormat::from_path(file) {
            Ok(format) => image::load_from_memory_with_format(bytes, format),
            Err(_) => image::load_from_memory(bytes),
        }
        .map_err(|e| e.to_string())?;
        let auto_srgb = matches!(
            img.color(),
            image::ColorType::Rgb8 | image::ColorType::Rgba8
        );
        let rgba = img.into_rgba32f();
        let (width, height) = rgba.dimensions();
        if width == 0 || height == 0 {
            return Err("the image is empty".into());
        }
        let texels = rgba
            .pixels()
            .map(|p| Vec4::from_array(p.0.map(|c| if c.is_finite() { c } else { 0.0 })))
            .collect();
        let texture = Texture {
            name: name.to_string(),
            width,
            height,
            texels,
        };
        Ok((texture, auto_srgb))
    }
}

/// The texel index for `x` under `mode`; `None` outside the image under [`Wrap::Black`].
fn wrap(x: i64, n: u32, mode: Wrap) -> Option<u32> {
    let n = n as i64;
    let i = match mode {
        Wrap::Repeat => x.rem_euclid(n),
        Wrap::Clamp => x.clamp(0, n - 1),
        Wrap::Black if x < 0 || x >= n => return None,
        Wrap::Black => x,
        Wrap::Mirror => {
            let p = x.rem_euclid(2 * n);
            if p < n {
                p
            } else {
                2 * n - 1 - p
            }
        }
    };
    Some(i as u32)
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
            let (Some(i), Some(j)) = (
                wrap(i, tex.width, self.wrap_s),
                wrap(j, tex.height, self.wrap_t),
            ) else {
                return Vec4::W;
            };
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
        top.lerp(bottom, fy) * self.scale + self.bias
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_modes() {
        assert_eq!(wrap(-1, 4, Wrap::Repeat), Some(3));
        assert_eq!(wrap(5, 4, Wrap::Clamp), Some(3));
        assert_eq!(wrap(4, 4, Wrap::Mirror), Some(3));
        assert_eq!(wrap(-1, 4, Wrap::Mirror), Some(0));
        assert_eq!(wrap(4, 4, Wrap::Black), None);
        assert_eq!(wrap(3, 4, Wrap::Black), Some(3));
    }
}

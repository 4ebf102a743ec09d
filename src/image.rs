//! Float RGB images and their files: OpenEXR (float32, lossless) for data, PNG (sRGB, clamped)
//! for looking at. Files are written atomically: to a temporary name in the same folder, then
//! renamed, so a failed or interrupted write never leaves a broken file under the target name.

use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::spectrum::Rgb;
use std::path::Path;

#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// Row-major, top row first.
    pub pixels: Vec<Rgb>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Image {
            width,
            height,
            pixels: vec![Rgb::ZERO; width as usize * height as usize],
        }
    }

    #[inline]
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Mean over all pixels.
    pub fn mean(&self) -> Rgb {
        let s: glam::DVec3 = self.pixels.iter().map(|p| p.as_dvec3()).sum();
        (s / self.pixels.len().max(1) as f64).as_vec3()
    }
}

fn output_error(path: &Path, reason: impl ToString) -> Error {
    Error::Output {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

/// Write a float32 RGB OpenEXR file.
pub fn write_exr(path: &Path, img: &Image) -> Result<()> {
    write_exr_layers(path, img, &[])
}

/// Lossless compression with the blocks in increasing order: the default order is the order
/// in which parallel compression finishes, which made two writes of one image differ.
fn deterministic_encoding() -> exr::prelude::Encoding {
    exr::prelude::Encoding {
        line_order: exr::prelude::LineOrder::Increasing,
        ..exr::prelude::Encoding::FAST_LOSSLESS
    }
}

/// Write a float32 OpenEXR file holding `beauty` as its R, G, B channels and each of `aovs` as
/// `NAME.R`, `NAME.G`, `NAME.B` in the same part (the layered-channel convention compositing
/// tools read as layers).
pub fn write_exr_layers(path: &Path, beauty: &Image, aovs: &[(&str, &Image)]) -> Result<()> {
    use exr::prelude::*;
    let layers = std::iter::once(("", beauty)).chain(aovs.iter().copied());
    let mut channels = SmallVec::<[AnyChannel<FlatSamples>; 4]>::new();
    for (name, img) in layers {
        if img.width != beauty.width || img.height != beauty.height {
            return Err(output_error(path, format!("layer {name} has another size")));
        }
        if img.pixels.iter().any(|p| !p.is_finite()) {
            return Err(output_error(
                path,
                format!(
                    "the {} holds NaN or infinite values (a bug: please report it)",
                    if name.is_empty() {
                        "image".to_string()
                    } else {
                        format!("layer \"{name}\"")
                    }
                ),
            ));
        }
        for (c, letter) in ["R", "G", "B"].iter().enumerate() {
            let full = if name.is_empty() {
                letter.to_string()
            } else {
                format!("{name}.{letter}")
            };
            let samples: Vec<f32> = img.pixels.iter().map(|p| p[c]).collect();
            channels.push(AnyChannel::new(full.as_str(), FlatSamples::F32(samples)));
        }
    }
    let size = (beauty.width as usize, beauty.height as usize);
    let layer = Layer::new(
        size,
        LayerAttributes::default(),
        deterministic_encoding(),
        AnyChannels::sort(channels),
    );
    write_atomically(path, |tmp| {
        exr::prelude::Image::from_layer(layer)
            .write()
            .to_file(tmp)
            .map_err(|e| e.to_string())
    })
}

/// Mean squared error and relative MSE, the mean of (x − ref)² / (ref² + 0.01), over all
/// pixels and channels; `None` when the sizes differ.
pub fn error_against(img: &Image, reference: &Image) -> Option<(f64, f64)> {
    if img.width != reference.width || img.height != reference.height {
        return None;
    }
    let (mut mse, mut rel) = (0.0f64, 0.0f64);
    for (a, b) in img.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let (x, r) = (a[c] as f64, b[c] as f64);
            mse += (x - r).powi(2);
            rel += (x - r).powi(2) / (r * r + 0.01);
        }
    }
    let n = 3.0 * img.pixels.len().max(1) as f64;
    Some((mse / n, rel / n))
}

/// A linear value as an 8-bit sRGB code (clamped to [0, 1], no tone mapping).
pub fn srgb8(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Write an 8-bit sRGB PNG (values clamped to [0, 1], no tone mapping).
pub fn write_png(path: &Path, img: &Image) -> Result<()> {
    let to8 = srgb8;
    let mut buf = Vec::with_capacity(img.pixels.len() * 3);
    for p in &img.pixels {
        buf.extend_from_slice(&[to8(p.x), to8(p.y), to8(p.z)]);
    }
    write_png_rgb8(path, img.width, img.height, &buf)
}

/// Write 8-bit sRGB pixels (R, G, B per pixel, rows from the top) as a PNG.
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<()> {
    write_atomically(path, |tmp| {
        image::save_buffer_with_format(
            tmp,
            rgb,
            width,
            height,
            image::ExtendedColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .map_err(|e| e.to_string())
    })
}

/// Read the RGB channels of an OpenEXR file's first layer.
pub fn read_exr(path: &Path) -> Result<Image> {
    let img = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |res: exr::prelude::Vec2<usize>, _| Image::new(res.width() as u32, res.height() as u32),
        |img: &mut Image, pos: exr::prelude::Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = img.width as usize;
            img.pixels[pos.y() * w + pos.x()] = Rgb::new(r, g, b);
        },
    )
    .map_err(|e| Error::ImageRead {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    Ok(img.layer_data.channel_data.pixels)
}

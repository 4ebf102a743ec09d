//! Float RGB images and their files: OpenEXR (float32, lossless) for data, PNG (sRGB, clamped)
//! for looking at. Files are written atomically: to a temporary name in the same folder, then
//! renamed, so a failed or interrupted write never leaves a broken file under the target name.

use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::spectrum::Rgb;
use std::path::Path;

#[derive(Clone, Debug, PartialEq)]
/// A float RGB image.
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major, top row first.
    pub pixels: Vec<Rgb>,
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Image {
            width,
            height,
            pixels: vec![Rgb::ZERO; width as usize * height as usize],
        }
    }

    #[inline]
    /// The pixel at column `x`, row `y` (from the top).
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        self.pixels[(y * self.width + x) as usize]
    }

    /// The `width` × `height` pixels from (`x`, `y`) on; `None` past the image's edge.
    pub fn crop(&self, x: u32, y: u32, width: u32, height: u32) -> Option<Image> {
        if u64::from(x) + u64::from(width) > u64::from(self.width)
            || u64::from(y) + u64::from(height) > u64::from(self.height)
        {
            return None;
        }
        let pixels = (y..y + height)
            .flat_map(|row| (x..x + width).map(move |col| self.get(col, row)))
            .collect();
        Some(Image {
            width,
            height,
            pixels,
        })
    }

    /// Each `factor` × `factor` block of pixels averaged into one: what a box pixel filter
    /// gives at the lower resolution, so a render can be held to a reference of a fraction of
    /// its size (Mitsuba's references use the box filter). `None` unless `factor` (at least
    /// 1) divides both sides.
    pub fn box_downsample(&self, factor: u32) -> Option<Image> {
        if factor == 0 || !self.width.is_multiple_of(factor) || !self.height.is_multiple_of(factor)
        {
            return None;
        }
        let (w, h) = (self.width / factor, self.height / factor);
        let scale = 1.0 / f64::from(factor * factor);
        let pixels = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w * factor, i / w * factor);
                let sum: glam::DVec3 = (0..factor * factor)
                    .map(|k| self.get(x + k % factor, y + k / factor).as_dvec3())
                    .sum();
                (sum * scale).as_vec3()
            })
            .collect();
        Some(Image {
            width: w,
            height: h,
            pixels,
        })
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

/// Write a float32 OpenEXR file holding `beauty` as its R, G, B channels and each of `aovs` as
/// `NAME.R`, `NAME.G`, `NAME.B` in the same part (the layered-channel convention compositing
/// tools read as layers).
pub fn write_exr_layers(path: &Path, beauty: &Image, aovs: &[(&str, &Image)]) -> Result<()> {
    let channels = ExrChannels {
        beauty,
        layers: aovs.to_vec(),
        ..ExrChannels::of(beauty)
    };
    write_exr_channels(path, &channels, &ExrOptions::lossless_float(beauty))
}

/// How an EXR stores its samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ExrPrecision {
    /// 16-bit floats (half the size; 11 bits of mantissa, values up to 65 504).
    Half,
    /// 32-bit floats.
    #[default]
    Float,
}

/// An EXR's lossless compression (OpenEXR's names).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ExrCompression {
    /// Uncompressed.
    None,
    /// Run lengths: fast, large.
    Rle,
    /// zlib per scan line.
    Zips,
    /// zlib per 16 scan lines: the usual default of compositing tools.
    #[default]
    Zip,
    /// Wavelet and Huffman: small files of noisy images.
    Piz,
}

/// The channels of an EXR: the beauty as R, G, B (and A), depth as Z, normals as N.X, N.Y,
/// N.Z, and RGB layers as NAME.R, NAME.G, NAME.B: OpenEXR's standard names, which
/// compositing tools map to their alpha, depth and normal passes.
#[derive(Clone, Debug)]
pub struct ExrChannels<'a> {
    /// The RGB image.
    pub beauty: &'a Image,
    /// Coverage, one value per pixel.
    pub alpha: Option<&'a [f32]>,
    /// Depth, one value per pixel.
    pub z: Option<&'a [f32]>,
    /// Shading normals (N.X, N.Y, N.Z).
    pub normal: Option<&'a Image>,
    /// Further RGB layers, by name.
    pub layers: Vec<(&'a str, &'a Image)>,
}

impl<'a> ExrChannels<'a> {
    /// The beauty alone.
    pub fn of(beauty: &'a Image) -> Self {
        ExrChannels {
            beauty,
            alpha: None,
            z: None,
            normal: None,
            layers: Vec::new(),
        }
    }
}

/// How an EXR is written: its samples, its windows and its header.
#[derive(Clone, Debug, Default)]
pub struct ExrOptions {
    /// Half or full floats.
    pub precision: ExrPrecision,
    /// The lossless compression.
    pub compression: ExrCompression,
    /// The display window's size: the whole image (the pixels written may be a part of it).
    pub display: (u32, u32),
    /// Where the pixels written lie in the display window: its data window's corner.
    pub origin: (u32, u32),
    /// Header attributes.
    pub header: ExrHeader,
}

impl ExrOptions {
    /// Float samples of the whole of `image`, no metadata.
    pub(crate) fn lossless_float(image: &Image) -> Self {
        ExrOptions {
            display: (image.width, image.height),
            ..Default::default()
        }
    }
}

/// Header attributes, under OpenEXR's standard names (its "Standard Attributes" document).
#[derive(Clone, Debug, Default)]
pub struct ExrHeader {
    /// `software`.
    pub software: Option<String>,
    /// `worldToCamera` and `worldToNDC`: row-major, for row vectors (p · M), as OpenEXR
    /// stores Imath's M44f.
    pub world_to_camera: Option<[f32; 16]>,
    /// See `world_to_camera`.
    pub world_to_ndc: Option<[f32; 16]>,
    /// `capDate` ("YYYY:MM:DD hh:mm:ss") and `utcOffset` (seconds, UTC − local).
    pub capture_date: Option<(String, f32)>,
    /// Free text in `comments`.
    pub comments: Option<String>,
    /// A text attribute `wpbgi`: the renderer's own record (settings, cache hash, time).
    pub wpbgi: Option<String>,
}

/// Write `channels` as one OpenEXR part (see [`ExrChannels`]) with `options`.
pub fn write_exr_channels(path: &Path, channels: &ExrChannels, options: &ExrOptions) -> Result<()> {
    use exr::prelude::{
        AnyChannel, AnyChannels, AttributeValue, Blocks, Compression, Encoding, FlatSamples,
        IntegerBounds, Layer, LayerAttributes, LineOrder, SmallVec, Text, Vec2,
    };
    let beauty = channels.beauty;
    let (w, h) = (beauty.width, beauty.height);
    let count = w as usize * h as usize;
    let (dx, dy) = options.display;
    let (ox, oy) = options.origin;
    if u64::from(ox) + u64::from(w) > u64::from(dx) || u64::from(oy) + u64::from(h) > u64::from(dy)
    {
        return Err(output_error(
            path,
            format!(
                "a {w}x{h} image at ({ox}, {oy}) does not lie within its {dx}x{dy} display window"
            ),
        ));
    }
    let mut planes: Vec<(String, Vec<f32>)> = Vec::new();
    let mut rgb = |name: &str, img: &Image| -> Result<()> {
        if (img.width, img.height) != (w, h) {
            return Err(output_error(path, format!("layer {name} has another size")));
        }
        for (c, letter) in ["R", "G", "B"].iter().enumerate() {
            let full = if name.is_empty() {
                letter.to_string()
            } else {
                format!("{name}.{letter}")
            };
            planes.push((full, img.pixels.iter().map(|p| p[c]).collect()));
        }
        Ok(())
    };
    rgb("", beauty)?;
    for (name, img) in &channels.layers {
        rgb(name, img)?;
    }
    if let Some(n) = channels.normal {
        if (n.width, n.height) != (w, h) {
            return Err(output_error(path, "the normals have another size"));
        }
        for (c, axis) in ["X", "Y", "Z"].iter().enumerate() {
            planes.push((format!("N.{axis}"), n.pixels.iter().map(|p| p[c]).collect()));
        }
    }
    for (name, values) in [("A", channels.alpha), ("Z", channels.z)] {
        if let Some(v) = values {
            if v.len() != count {
                return Err(output_error(
                    path,
                    format!("channel {name} has another size"),
                ));
            }
            planes.push((name.to_string(), v.to_vec()));
        }
    }
    if let Some((name, _)) = planes
        .iter()
        .find(|(_, v)| v.iter().any(|x| !x.is_finite()))
    {
        return Err(output_error(
            path,
            format!("channel {name} holds NaN or infinite values (a bug: please report it)"),
        ));
    }
    let channel_list: SmallVec<[AnyChannel<FlatSamples>; 4]> = planes
        .into_iter()
        .map(|(name, v)| {
            let samples = match options.precision {
                ExrPrecision::Float => FlatSamples::F32(v),
                ExrPrecision::Half => {
                    FlatSamples::F16(v.into_iter().map(exr::prelude::f16::from_f32).collect())
                }
            };
            AnyChannel::new(name.as_str(), samples)
        })
        .collect();
    let compression = match options.compression {
        ExrCompression::None => Compression::Uncompressed,
        ExrCompression::Rle => Compression::RLE,
        ExrCompression::Zips => Compression::ZIP1,
        ExrCompression::Zip => Compression::ZIP16,
        ExrCompression::Piz => Compression::PIZ,
    };
    // Blocks in increasing order: the default order is the order in which parallel
    // compression finishes, which made two writes of one image differ.
    let encoding = Encoding {
        compression,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let header = &options.header;
    let text = |s: &str| Text::new_or_none(s);
    let mut attributes = LayerAttributes {
        layer_position: Vec2(ox as i32, oy as i32),
        software_name: header.software.as_deref().and_then(text),
        world_to_camera: header.world_to_camera,
        world_to_normalized_device: header.world_to_ndc,
        capture_date: header.capture_date.as_ref().and_then(|(d, _)| text(d)),
        utc_offset: header.capture_date.as_ref().map(|(_, o)| *o),
        comments: header.comments.as_deref().and_then(text),
        ..LayerAttributes::default()
    };
    // One attribute of our own at most: the crate writes its own attributes in its hash
    // map's (random) order, and files must come out byte for byte the same.
    if let Some(t) = header.wpbgi.as_deref().and_then(text) {
        attributes
            .other
            .insert(Text::new_or_panic("wpbgi"), AttributeValue::Text(t));
    }
    let layer = Layer::new(
        (w as usize, h as usize),
        attributes,
        encoding,
        AnyChannels::sort(channel_list),
    );
    let mut image = exr::prelude::Image::from_layer(layer);
    image.attributes.display_window =
        IntegerBounds::new(Vec2(0, 0), Vec2(dx as usize, dy as usize));
    write_flat_layer(path, image)
}

/// An image of one layer of flat channels, as wpbgi writes it: atomically, its blocks in
/// increasing order (so that two writes of one image are the same bytes). The one writer of
/// renders ([`write_exr_channels`]) and assembled tiles ([`crate::assemble`]).
pub(crate) fn write_flat_layer(
    path: &Path,
    image: exr::prelude::Image<
        exr::prelude::Layer<exr::prelude::AnyChannels<exr::prelude::FlatSamples>>,
    >,
) -> Result<()> {
    use exr::prelude::WritableImage;
    write_atomically(path, |tmp| {
        image.write().to_file(tmp).map_err(|e| e.to_string())
    })
}

/// `capDate` and `utcOffset` for a time in seconds since the Unix epoch, in UTC.
pub fn exr_capture_date(unix_seconds: u64) -> (String, f32) {
    let days = (unix_seconds / 86_400) as i64;
    let secs = unix_seconds % 86_400;
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1_460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    (
        format!(
            "{year:04}:{month:02}:{day:02} {:02}:{:02}:{:02}",
            secs / 3600,
            secs / 60 % 60,
            secs % 60
        ),
        0.0,
    )
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
    write_display(path, img, 0.0, ViewTransform::Srgb)
}

/// How linear radiance becomes an 8-bit display image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ViewTransform {
    /// sRGB's curve on the value clamped to [0, 1]: what is above 1 clips.
    #[default]
    Srgb,
    /// A filmic curve: ACES's reference and sRGB output transforms as fitted by K. Narkowicz
    /// (2015), x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14) of 0.6 times the value, then sRGB's
    /// curve. Highlights roll off towards white instead of clipping; mid-grey 0.18 shows at
    /// about 0.15 (the fit's 0.6, which matches ACES's exposure).
    Aces,
}

impl ViewTransform {
    /// The display value (0 to 1, before sRGB's curve) of the linear value `c`.
    pub fn apply(self, c: f32) -> f32 {
        match self {
            ViewTransform::Srgb => c.clamp(0.0, 1.0),
            ViewTransform::Aces => {
                let x = 0.6 * c.max(0.0);
                (x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
            }
        }
    }
}

/// Write `img` as an 8-bit sRGB PNG, or JPEG where `path` ends in .jpg or .jpeg, after
/// scaling it by 2^`exposure` (stops) and through `view`.
pub fn write_display(path: &Path, img: &Image, exposure: f32, view: ViewTransform) -> Result<()> {
    if !exposure.is_finite() {
        return Err(output_error(path, "the exposure must be a number of stops"));
    }
    let scale = exposure.exp2();
    let to8 = |c: f32| srgb8(view.apply(c * scale));
    let mut buf = Vec::with_capacity(img.pixels.len() * 3);
    for p in &img.pixels {
        buf.extend_from_slice(&[to8(p.x), to8(p.y), to8(p.z)]);
    }
    let jpeg = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("jpg") || e.eq_ignore_ascii_case("jpeg"));
    let format = if jpeg {
        image::ImageFormat::Jpeg
    } else {
        image::ImageFormat::Png
    };
    write_rgb8(path, img.width, img.height, &buf, format)
}

/// Write 8-bit sRGB pixels (R, G, B per pixel, rows from the top) as a PNG.
pub(crate) fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<()> {
    write_rgb8(path, width, height, rgb, image::ImageFormat::Png)
}

fn write_rgb8(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[u8],
    format: image::ImageFormat,
) -> Result<()> {
    write_atomically(path, |tmp| {
        image::save_buffer_with_format(
            tmp,
            rgb,
            width,
            height,
            image::ExtendedColorType::Rgb8,
            format,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Block means worked out by hand; sizes the factor does not divide are refused.
    #[test]
    fn box_downsample_averages_blocks() {
        let mut img = Image::new(4, 2);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = Rgb::new(i as f32, 1.0, -(i as f32));
        }
        // Blocks {0, 1, 4, 5} and {2, 3, 6, 7}.
        let half = img.box_downsample(2).unwrap();
        assert_eq!((half.width, half.height), (2, 1));
        assert_eq!(
            half.pixels,
            vec![Rgb::new(2.5, 1.0, -2.5), Rgb::new(4.5, 1.0, -4.5)]
        );
        assert_eq!(img.box_downsample(1).as_ref(), Some(&img));
        assert!(img.box_downsample(3).is_none() && img.box_downsample(0).is_none());
        assert_eq!(half.mean(), img.mean());
    }

    /// The filmic curve: black stays black, it rises monotonically, rolls off below white
    /// (no clip for values a sRGB view would clip), and matches Narkowicz's fit at points
    /// worked out by hand.
    #[test]
    fn aces_view_rolls_off() {
        let v = ViewTransform::Aces;
        assert_eq!(v.apply(0.0), 0.0);
        assert_eq!(v.apply(-1.0), 0.0);
        let xs: Vec<f32> = (0..200).map(|i| i as f32 * 0.05).collect();
        assert!(xs.windows(2).all(|w| v.apply(w[1]) > v.apply(w[0])));
        assert!(v.apply(2.0) < v.apply(4.0) && v.apply(4.0) < 1.0);
        // x = 0.6: 0.6 (1.506 + 0.03) / (0.6 (1.458 + 0.59) + 0.14) = 0.9216 / 1.3688.
        assert!((v.apply(1.0) - 0.9216 / 1.3688).abs() < 1e-6);
        assert_eq!(ViewTransform::Srgb.apply(2.0), 1.0);
    }

    /// An exposure of +1 stop shows what twice the radiance shows at 0; PNG and JPEG by name.
    #[test]
    fn exposure_doubles_the_radiance() {
        let dir = std::env::temp_dir().join(format!("wpbgi-display-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let mut img = Image::new(4, 1);
        img.pixels = vec![
            Rgb::splat(0.05),
            Rgb::splat(0.1),
            Rgb::splat(0.2),
            Rgb::splat(0.4),
        ];
        let mut doubled = img.clone();
        doubled.pixels.iter_mut().for_each(|p| *p *= 2.0);
        let (a, b, c) = (dir.join("a.png"), dir.join("b.png"), dir.join("c.jpg"));
        write_display(&a, &img, 1.0, ViewTransform::Aces).expect("a");
        write_display(&b, &doubled, 0.0, ViewTransform::Aces).expect("b");
        write_display(&c, &img, 0.0, ViewTransform::Srgb).expect("c");
        assert_eq!(std::fs::read(&a).expect("a"), std::fs::read(&b).expect("b"));
        let jpeg = std::fs::read(&c).expect("c");
        assert_eq!(&jpeg[..2], &[0xff, 0xd8], "not a JPEG");
        assert!(write_display(&a, &img, f32::NAN, ViewTransform::Srgb).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}

//! Tiles of a frame stitched into the frame (`wpbgi assemble`), for renders split over a farm.
//!
//! `render --crop` (or `--tile`) writes an OpenEXR whose data window is the tile and whose
//! display window is the whole frame, every pixel exactly as the whole render has it. Here
//! the data windows say where each tile goes: the tiles must share the display window, the
//! channels with their sample types, the compression and every header attribute but the
//! data window and the times (the capture date, and the render's seconds in the `wpbgi`
//! record); together they must cover the display window exactly once. A missing tile (a
//! pixel no tile covers) or two overlapping ones are refused, naming the pixel and the
//! files, before anything is written. The frame is written as the whole render writes it
//! ([`crate::image`]'s writer, atomically), with the latest capture date and the tiles'
//! seconds summed. With `SOURCE_DATE_EPOCH` set (a fixed date, no seconds) it equals a
//! single-process render byte for byte: the `wpbgi` record holds the render's settings but
//! not its crop.

use crate::error::{Error, Result};
use crate::image::write_flat_layer;
use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, FlatSamples, Image, Layer, LayerAttributes,
    ReadChannels, ReadLayers, SmallVec, Text, Vec2,
};
use std::path::{Path, PathBuf};

/// One tile as read.
type Tile = Image<Layer<AnyChannels<FlatSamples>>>;

/// What an assembly made.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Assembled {
    /// The frame's size (its display window).
    pub width: usize,
    /// See `width`.
    pub height: usize,
    /// Tiles stitched.
    pub tiles: usize,
    /// The channels written, in order.
    pub channels: Vec<String>,
}

/// Stitch the EXR `tiles` of one frame into `output` (see the module docs).
pub fn assemble(tiles: &[PathBuf], output: &Path) -> Result<Assembled> {
    let Some(first_path) = tiles.first() else {
        return Err(Error::InvalidSetting(
            "no tiles to assemble: give the tile EXRs of one frame".into(),
        ));
    };
    let read: Vec<Tile> = tiles.iter().map(|p| read_tile(p)).collect::<Result<_>>()?;
    let first = &read[0];
    let display = first.attributes.display_window;
    let (width, height) = (display.size.width(), display.size.height());
    if display.position != Vec2(0, 0) {
        return Err(refused(
            first_path,
            "its display window does not start at (0, 0)",
        ));
    }
    let names = |t: &Tile| -> Vec<String> {
        let list = &t.layer_data.channel_data.list;
        list.iter().map(|c| c.name.to_string()).collect()
    };
    let kinds = |t: &Tile| -> Vec<u8> {
        let list = &t.layer_data.channel_data.list;
        list.iter().map(|c| sample_kind(&c.sample_data)).collect()
    };
    // Every tile is one part of the same frame: all but the data window and the times
    // alike.
    let like_first = comparable(&first.layer_data.attributes);
    for (path, tile) in tiles.iter().zip(&read).skip(1) {
        let attributes = comparable(&tile.layer_data.attributes);
        let differs = if tile.attributes.display_window != display {
            Some("display window (the frame's size)")
        } else if names(tile) != names(first) || kinds(tile) != kinds(first) {
            Some("channels")
        } else if tile.layer_data.encoding != first.layer_data.encoding {
            Some("compression")
        } else if attributes != like_first || tile.attributes != first.attributes {
            Some("header (another render, camera or cache)")
        } else {
            None
        };
        if let Some(what) = differs {
            return Err(refused(
                path,
                format!("its {what} differs from {}'s", first_path.display()),
            ));
        }
    }
    // Where each tile goes, and which covers each pixel.
    let mut owner: Vec<u32> = vec![u32::MAX; width * height];
    for (t, (path, tile)) in tiles.iter().zip(&read).enumerate() {
        let (x0, y0, w, h) = window(tile);
        if x0 < 0 || y0 < 0 || x0 as usize + w > width || y0 as usize + h > height {
            return Err(refused(
                path,
                format!("its data window lies outside the {width}x{height} frame"),
            ));
        }
        let (x0, y0) = (x0 as usize, y0 as usize);
        for y in y0..y0 + h {
            for x in x0..x0 + w {
                let o = &mut owner[y * width + x];
                if *o != u32::MAX {
                    return Err(refused(
                        path,
                        format!(
                            "it overlaps {} at pixel ({x}, {y}): each pixel must come from one tile",
                            tiles[*o as usize].display()
                        ),
                    ));
                }
                *o = t as u32;
            }
        }
    }
    if let Some(k) = owner.iter().position(|&o| o == u32::MAX) {
        return Err(Error::InvalidSetting(format!(
            "the {} tiles leave pixel ({}, {}) of the {width}x{height} frame uncovered: a tile is \
             missing",
            tiles.len(),
            k % width,
            k / width
        )));
    }
    // The frame, channel by channel.
    let list = &first.layer_data.channel_data.list;
    let mut frame: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (c, channel) in list.iter().enumerate() {
        let mut samples = empty_like(&channel.sample_data, width * height);
        for tile in &read {
            let (x0, y0, w, _) = window(tile);
            let source = &tile.layer_data.channel_data.list[c].sample_data;
            copy_rows(source, &mut samples, w, (x0 as usize, y0 as usize), width);
        }
        frame.push(AnyChannel {
            sample_data: samples,
            ..channel.clone()
        });
    }
    let layer = Layer::new(
        (width, height),
        frame_attributes(&read),
        first.layer_data.encoding,
        AnyChannels { list: frame },
    );
    let mut image = Image::from_layer(layer);
    image.attributes = first.attributes.clone();
    write_flat_layer(output, image)?;
    Ok(Assembled {
        width,
        height,
        tiles: tiles.len(),
        channels: names(first),
    })
}

/// The name of wpbgi's own header attribute (see `render --output`): its JSON record of the
/// render's settings, and the render's seconds unless `SOURCE_DATE_EPOCH` is set.
const RECORD: &str = "wpbgi";
const SECONDS: &str = "render_seconds";

/// A tile's header as the tiles of one frame share it: without the data window, the capture
/// date and the render's seconds, which differ from task to task unless `SOURCE_DATE_EPOCH`
/// fixes them.
fn comparable(attributes: &LayerAttributes) -> LayerAttributes {
    let mut a = attributes.clone();
    a.layer_position = Vec2(0, 0);
    a.capture_date = None;
    a.utc_offset = None;
    if let Some(mut record) = record_of(&a) {
        if let Some(map) = record.as_object_mut() {
            map.remove(SECONDS);
        }
        set_record(&mut a, &record);
    }
    a
}

/// The frame's header: the tiles' shared one at (0, 0), the latest capture date among
/// theirs, and as the render's seconds their sum (the frame's render time over its tasks).
fn frame_attributes(tiles: &[Tile]) -> LayerAttributes {
    let all: Vec<&LayerAttributes> = tiles.iter().map(|t| &t.layer_data.attributes).collect();
    let mut a = all[0].clone();
    a.layer_position = Vec2(0, 0);
    if let Some(latest) = all
        .iter()
        .filter(|t| t.capture_date.is_some())
        .max_by_key(|t| t.capture_date.as_ref().map(|d| d.to_string()))
    {
        a.capture_date = latest.capture_date.clone();
        a.utc_offset = latest.utc_offset;
    }
    let seconds: Vec<f64> = all
        .iter()
        .filter_map(|t| record_of(t)?.get(SECONDS)?.as_f64())
        .collect();
    if let (Some(mut record), false) = (record_of(&a), seconds.is_empty()) {
        record[SECONDS] = serde_json::json!(seconds.iter().sum::<f64>());
        set_record(&mut a, &record);
    }
    a
}

fn record_of(a: &LayerAttributes) -> Option<serde_json::Value> {
    match a.other.get(&Text::new_or_panic(RECORD))? {
        AttributeValue::Text(t) => serde_json::from_str(&t.to_string()).ok(),
        _ => None,
    }
}

fn set_record(a: &mut LayerAttributes, record: &serde_json::Value) {
    if let Some(t) = Text::new_or_none(record.to_string()) {
        a.other
            .insert(Text::new_or_panic(RECORD), AttributeValue::Text(t));
    }
}

fn read_tile(path: &Path) -> Result<Tile> {
    exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| Error::ImageRead {
            path: path.to_path_buf(),
            reason: format!("not a tile wpbgi can assemble ({e})"),
        })
}

fn refused(path: &Path, reason: impl ToString) -> Error {
    Error::ImageRead {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

/// A tile's data window: position and size.
fn window(tile: &Tile) -> (i32, i32, usize, usize) {
    let layer = &tile.layer_data;
    let at = layer.attributes.layer_position;
    (at.x(), at.y(), layer.size.width(), layer.size.height())
}

fn sample_kind(samples: &FlatSamples) -> u8 {
    match samples {
        FlatSamples::F16(_) => 0,
        FlatSamples::F32(_) => 1,
        FlatSamples::U32(_) => 2,
    }
}

fn empty_like(samples: &FlatSamples, len: usize) -> FlatSamples {
    match samples {
        FlatSamples::F16(_) => FlatSamples::F16(vec![Default::default(); len]),
        FlatSamples::F32(_) => FlatSamples::F32(vec![0.0; len]),
        FlatSamples::U32(_) => FlatSamples::U32(vec![0; len]),
    }
}

/// Copy a tile's rows (`width` samples each) into the frame's (`frame_width` each) at
/// `(x0, y0)`; both have the same sample type (checked by the caller).
fn copy_rows(
    tile: &FlatSamples,
    frame: &mut FlatSamples,
    width: usize,
    (x0, y0): (usize, usize),
    frame_width: usize,
) {
    fn rows<T: Copy>(from: &[T], to: &mut [T], w: usize, (x0, y0): (usize, usize), fw: usize) {
        for (r, row) in from.chunks_exact(w).enumerate() {
            let at = (y0 + r) * fw + x0;
            to[at..at + w].copy_from_slice(row);
        }
    }
    match (tile, frame) {
        (FlatSamples::F16(a), FlatSamples::F16(b)) => rows(a, b, width, (x0, y0), frame_width),
        (FlatSamples::F32(a), FlatSamples::F32(b)) => rows(a, b, width, (x0, y0), frame_width),
        (FlatSamples::U32(a), FlatSamples::U32(b)) => rows(a, b, width, (x0, y0), frame_width),
        _ => {}
    }
}

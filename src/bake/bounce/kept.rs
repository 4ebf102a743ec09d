//! The bounces' recorded transport kept beside a cache (`wpbgi bake --keep-transport`), so that
//! `wpbgi relight` can re-solve the bounces for edited materials and lights without gathering
//! again (docs/relight.md).
//!
//! The transport ([`super::transport`]) is geometry: the receivers' links to the senders'
//! slots and the directional receivers' map texels, fixed by the surfels, the tree, the
//! microbuffers' resolutions and the BSDF operators' grids, none of which a reflectance, a
//! tint, a transmittance or an emission changes. The bounces' first pass records it (most of
//! their time: 3.8 of cbox-rough's 5.0 s at the default preset); a bake that is handed a kept
//! transport whose [`TransportKey`] is its own replays it instead, and writes the same cache
//! byte for byte as a bake that recorded it. The bake's BSDF operators are kept with it (a
//! relight takes each one whose key it would build: [`Operators::with_kept`](super::bsdf_operator::Operators::with_kept)), and so are its
//! surfels and their direct light ([`KeptDirect`]), with hashes of what they came from: a bake of the same geometry takes
//! the surfels, and where its emitters are the same, each surfel's direct light where its
//! material is.
//!
//! The file (`CACHE.transport`, [`beside`]) is little-endian:
//!
//! | bytes | what |
//! |---|---|
//! | 16 | magic `WPBGI-TRANSPORT\0` |
//! | 4 | format version ([`VERSION`]) |
//! | 16 | the key: a hash of everything the transport depends on |
//! | 8 × 8 | the [`TransportReport`]: bytes, bytes unbounded, kept and regathered groups, receivers, read slots, slots, incident bytes |
//! | 8 + 8 × w | the read slots' bitmap: w words |
//! | 8 | receiver groups kept |
//! | per group | its receivers (u32), then per receiver: surfel, pixel ends, terms and map texels counts (u32 each), the pixel ends (u32), the terms (u32 slot, f32 weight), the map texels (u16), two zero bytes where their count is odd |
//! | 8 | BSDF operators kept |
//! | per operator | its [`OperatorKey`](super::bsdf_operator::OperatorKey) (16), its grid side, hemispheres, basis (0 Haar, 1 texels) and 1 where grey, else 0 (u32 each), its two norms (f32), its entries' count e (u64), then its column starts (u32 × (s + 1), s its texels), the entries' rows (u32 × e), their values (f32 × e, or × 3e where not grey), the albedo (f32 × 6s) and the mean cosines (f32 × s) |
//! | 1 | 1 when the direct light follows, else 0 |
//! | 32 + 8 + 16 × m + 8 + 56 × n + … | the direct light: the hashes of its geometry and settings and of its emitters, m materials' hashes, n surfels (44 bytes each: position, normal, area, mesh, triangle, barycentrics), their emission (3 × f32), then per surfel 0 and an RGB (3 × f32), 2 and an RGB, the irradiance it reflects (3 × f32) and the normal it was taken about (3 × f32) for a diffuse surfel, or 1 and a wavelet map as the cache stores one |
//! | 8 | XXH3-64 of every byte before it |
//!
//! Every receiver's arrays start at a multiple of four bytes from the file's start, so that on
//! a little-endian machine a read leaves them in the mapped file ([`Run::in_place`]) instead
//! of copying them out.
//!
//! Anything that does not check out (magic, version, length, checksum, a count or an index
//! out of range, receivers that are not the bake's) is refused with a reason, and the bake
//! records the transport as if none had been handed to it.

use super::bsdf_operator::{Basis, BsdfOperator, KeyedOperator, OperatorParts};
use super::report::TransportReport;
use super::run::{Run, SharedBytes};
use super::transport::{ReceiverLinks, Slots, Term};
use crate::atomic::write_atomically_unsynced;
use crate::error::Result;
use crate::gather::fpbgi::Cluster;
use crate::haar::SparseHaar;
use crate::spectrum::Rgb;
use crate::surfels::coding::NodeCoding;
use crate::surfels::radiance::SurfelRadiance;
use crate::surfels::Surfel;
use rayon::prelude::*;
use std::io::Write;
use std::path::{Path, PathBuf};
use xxhash_rust::xxh3::Xxh3;

/// The file's first bytes.
const MAGIC: &[u8; 16] = b"WPBGI-TRANSPORT\0";

/// The format this build writes and reads. 5: the same layout as 4, whose links lack the
/// rays through mixed pixels (`iterate::trace_mixed_pixels`), so a file of 4 no longer
/// replays this build's bake. 6: the same layout as 5, whose directional receivers' links
/// weigh a pixel's senders by radiance rather than by cosine-weighted radiance, and lack the
/// rays through their mixed pixels at the horizon.
pub const VERSION: u32 = 6;

/// The hash of everything a bake's transport depends on (see [`super::iterate`]'s
/// `transport_key`): equal keys, equal transports.
pub type TransportKey = [u8; 16];

/// The transport file kept beside `cache`: its name with `.transport` appended.
pub fn beside(cache: &Path) -> PathBuf {
    let mut name = cache.as_os_str().to_owned();
    name.push(".transport");
    PathBuf::from(name)
}

/// A bake's recorded transport, out of memory or into it.
pub struct KeptTransport {
    /// What it is the transport of.
    pub key: TransportKey,
    /// Its size, as the bake that recorded it reported it.
    pub report: TransportReport,
    /// The read slots' bitmap ([`SlotIndex`](super::transport::SlotIndex)'s words).
    pub(super) words: Vec<u64>,
    /// The links of the receiver groups kept, in group order, their slots compact.
    pub(super) kept: Vec<Vec<ReceiverLinks>>,
    /// The bake's BSDF operators, with their keys.
    pub(crate) operators: Vec<KeyedOperator>,
    /// The bake's direct light, where it was handed out with the transport.
    pub direct: Option<KeptDirect>,
}

/// A bake's surfels and their direct light (emission included, as the direct pass leaves it),
/// with what they were computed from: a later bake of the same geometry and settings takes
/// the surfels, and where the emitters are also the same, the direct light of every surfel
/// whose material is too. That is what its own passes would compute again, bit for bit (each
/// surfel's light samples are seeded by its number).
#[derive(Clone, Debug, PartialEq)]
pub struct KeptDirect {
    /// [`geometry_hash`](crate::cache::store::geometry_hash) of the bake's scene and settings.
    pub geometry: [u8; 16],
    /// [`emitters_hash`](crate::cache::store::emitters_hash) of its scene.
    pub emitters: [u8; 16],
    /// [`material_hash`](crate::cache::store::material_hash) of each of its materials.
    pub materials: Vec<[u8; 16]>,
    /// The surfels (what the edited scene's sampling would draw again: they depend on
    /// geometry alone).
    pub surfels: Vec<Surfel>,
    /// Each surfel's outgoing radiance after the direct pass.
    pub radiance: Vec<SurfelRadiance>,
    /// Each surfel's emission, included in `radiance`.
    pub emitted: Vec<Rgb>,
    /// Per surfel, for a diffuse one the irradiance it reflected and the normal it was taken
    /// about: what a diffuse surfel whose reflectance alone is edited reflects again (its
    /// light samples see geometry and emitters alone).
    pub irradiance: Vec<Option<KeptIrradiance>>,
}

/// The irradiance on a diffuse surfel's front face ([`DirectLight::irradiance`](crate::bake::direct::DirectLight::irradiance)) and the
/// shading normal its cosines were taken to: a bake of the same geometry and emitters whose
/// surfel shades with the same normal reflects this irradiance, whatever its reflectance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeptIrradiance {
    /// The irradiance, RGB.
    pub irradiance: Rgb,
    /// The shading normal.
    pub shading: glam::Vec3,
}

/// A cache's coding of its tree's projected area, handed to a bake of the same geometry and
/// settings (a relight's, from the cache it starts from): the area depends on the surfels and
/// the tree alone, so that bake takes it instead of coding the area again, bit for bit the
/// coding it would make.
#[derive(Clone, Debug, PartialEq)]
pub struct KeptProjected {
    /// [`geometry_hash`](crate::cache::store::geometry_hash) of the scene and settings the
    /// coding was made for.
    pub geometry: [u8; 16],
    /// Per node of the tree, its maps G and H of the projected area.
    pub nodes: Vec<NodeCoding<f32>>,
}

/// What a bake's bounces do with a kept transport: replay one handed in, hand theirs out;
/// and what else a relight hands the bake from the cache it starts from.
#[derive(Default)]
pub struct TransportHandoff {
    /// A transport kept from an earlier bake, replayed if its key is this bake's.
    pub reuse: Option<KeptTransport>,
    /// The projected area's coding of a cache of this bake's geometry, taken where the
    /// geometry hashes match and the tree has as many nodes.
    pub projected: Option<KeptProjected>,
    /// Whether to hand this bake's transport out (in `kept`), with its direct light.
    pub keep: bool,
    /// Surfels whose direct light was taken from `reuse`.
    pub direct_reused: usize,
    /// Diffuse surfels whose material was edited and whose irradiance was taken from `reuse`
    /// and reflected again.
    pub irradiance_reused: usize,
    /// The transport handed out, when `keep` was asked.
    pub kept: Option<KeptTransport>,
    /// Whether `reuse` was replayed.
    pub replayed: bool,
    /// Why `reuse` was not replayed, when it was handed in and was not.
    pub refused: Option<String>,
}

impl KeptTransport {
    /// The links of the groups kept, checked against the bake's: the same key, the slots'
    /// bitmap of their size, every group's receivers its members in order, and every index
    /// in range (see `check_links`). The reason, when they are not.
    pub(super) fn check(
        &self,
        key: &TransportKey,
        slots: &Slots,
        groups: &[Cluster],
        check_links: impl Fn(&ReceiverLinks, usize) -> std::result::Result<(), String>,
    ) -> std::result::Result<(), String> {
        if self.key != *key {
            return Err("it was recorded for other geometry, receivers or BSDF grids".into());
        }
        if self.words.len() as u64 != slots.total().div_ceil(64) {
            return Err("its bitmap of read slots is not of this bake's size".into());
        }
        if self.kept.len() > groups.len() {
            return Err("it holds more receiver groups than the bake has".into());
        }
        let read: usize = self.words.iter().map(|w| w.count_ones() as usize).sum();
        for (links, group) in self.kept.iter().zip(groups) {
            if links.len() != group.members.len()
                || links
                    .iter()
                    .zip(&group.members)
                    .any(|(l, &m)| l.surfel != m)
            {
                return Err("its receivers are not the bake's".into());
            }
            for l in links {
                check_links(l, read)?;
            }
        }
        Ok(())
    }

    /// Write to `path` atomically (not synced: the file can be made again, and is checked
    /// when read).
    pub fn write(&self, path: &Path) -> Result<()> {
        write_atomically_unsynced(path, |tmp| {
            let stream = || -> std::io::Result<()> {
                let file = std::fs::File::create(tmp)?;
                let mut out = Hashed {
                    inner: std::io::BufWriter::with_capacity(1 << 20, file),
                    hash: Xxh3::new(),
                };
                self.stream(&mut out)?;
                let digest = out.hash.digest();
                out.inner.write_all(&digest.to_le_bytes())?;
                out.inner.flush()
            };
            stream().map_err(|e| e.to_string())
        })
    }

    fn stream(&self, out: &mut impl Write) -> std::io::Result<()> {
        out.write_all(MAGIC)?;
        out.write_all(&VERSION.to_le_bytes())?;
        out.write_all(&self.key)?;
        for x in report_fields(&self.report) {
            out.write_all(&x.to_le_bytes())?;
        }
        out.write_all(&(self.words.len() as u64).to_le_bytes())?;
        let mut bytes = Vec::new();
        put(&mut bytes, &self.words);
        out.write_all(&bytes)?;
        out.write_all(&(self.kept.len() as u64).to_le_bytes())?;
        for group in &self.kept {
            bytes.clear();
            bytes.extend_from_slice(&(group.len() as u32).to_le_bytes());
            for l in group {
                let (ends, terms, texels) = l.parts();
                put(
                    &mut bytes,
                    &[l.surfel, len32(ends), len32(terms), len32(texels)],
                );
                put(&mut bytes, ends);
                put(&mut bytes, terms);
                put(&mut bytes, texels);
                bytes.extend_from_slice(&[0; 2][..texel_padding(texels.len())]);
            }
            out.write_all(&bytes)?;
        }
        out.write_all(&(self.operators.len() as u64).to_le_bytes())?;
        for (key, op) in &self.operators {
            bytes.clear();
            put_operator(&mut bytes, key, op.parts());
            out.write_all(&bytes)?;
        }
        match &self.direct {
            None => out.write_all(&[0])?,
            Some(d) => {
                bytes.clear();
                bytes.push(1);
                bytes.extend_from_slice(&d.geometry);
                bytes.extend_from_slice(&d.emitters);
                bytes.extend_from_slice(&(d.materials.len() as u64).to_le_bytes());
                for m in &d.materials {
                    bytes.extend_from_slice(m);
                }
                bytes.extend_from_slice(&(d.radiance.len() as u64).to_le_bytes());
                put(&mut bytes, &d.surfels);
                for e in &d.emitted {
                    put(&mut bytes, &e.to_array());
                }
                out.write_all(&bytes)?;
                for (r, e) in d.radiance.iter().zip(&d.irradiance) {
                    bytes.clear();
                    match (r, e) {
                        (SurfelRadiance::Rgb(c), None) => {
                            bytes.push(0);
                            put(&mut bytes, &c.to_array());
                        }
                        (SurfelRadiance::Rgb(c), Some(e)) => {
                            bytes.push(2);
                            put(&mut bytes, &c.to_array());
                            put(&mut bytes, &e.irradiance.to_array());
                            put(&mut bytes, &e.shading.to_array());
                        }
                        (SurfelRadiance::Map(m), _) => {
                            bytes.push(1);
                            m.write_to(&mut bytes);
                        }
                    }
                    out.write_all(&bytes)?;
                }
            }
        }
        Ok(())
    }

    /// Read the transport file `path`; the reason, in words, when it cannot be used. Its
    /// links stay in the mapped file where they can ([`Run::in_place`]), until the last is
    /// dropped.
    pub fn read(path: &Path) -> std::result::Result<KeptTransport, String> {
        let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
        // SAFETY: the map is read-only; a file truncated or rewritten under it by another
        // process while the links borrow it is the one hazard, as for the cache's own map
        // (wpbgi replaces its files by renaming new ones over them, which leaves a mapped
        // one as it was).
        let map = unsafe { memmap2::Mmap::map(&file) }.map_err(|e| e.to_string())?;
        parse(&(std::sync::Arc::new(map) as SharedBytes))
    }
}

/// A transport from the bytes of its file.
fn parse(file: &SharedBytes) -> std::result::Result<KeptTransport, String> {
    let bytes: &[u8] = (**file).as_ref();
    let body_len = bytes
        .len()
        .checked_sub(8)
        .ok_or("it is shorter than its header")?;
    let (body, trailer) = bytes.split_at(body_len);
    let mut r = Reader { bytes: body };
    if r.take(16)? != MAGIC {
        return Err("it is not a wpbgi transport file".into());
    }
    let version = r.u32()?;
    if version != VERSION {
        return Err(format!(
            "it has format {version}, this build reads {VERSION}"
        ));
    }
    let stored = u64::from_le_bytes(trailer.try_into().map_err(|_| "no checksum")?);
    // The checksum and the parse each take a pass over hundreds of MB: they run side by
    // side, and a file whose checksum fails is refused for that, whatever its parse found.
    let (digest, parsed) = rayon::join(|| xxhash_rust::xxh3::xxh3_64(body), || parse_body(r, file));
    if digest != stored {
        return Err("its checksum fails (damaged or truncated)".into());
    }
    parsed
}

/// The transport from the bytes of its file past its magic and version, before its
/// checksum.
fn parse_body(mut r: Reader, file: &SharedBytes) -> std::result::Result<KeptTransport, String> {
    let key: TransportKey = r.take(16)?.try_into().map_err(|_| "short key")?;
    let mut fields = [0u64; 8];
    for f in &mut fields {
        *f = r.u64()?;
    }
    let report = report_of(fields);
    let words = r.count(8)?;
    let words: Vec<u64> = get(r.take(words * 8)?);
    // The groups' bytes found first, from their receivers' counts alone, then parsed on all
    // threads: the copies out of the file are most of a read.
    let groups = r.count(4)?;
    let mut spans = Vec::with_capacity(groups);
    for _ in 0..groups {
        let start = r.bytes;
        let members = r.u32()? as usize;
        for _ in 0..members {
            r.take(4)?;
            let (ends, terms, texels) = (r.u32()?, r.u32()?, r.u32()?);
            let texels = texels as usize;
            r.take(ends as usize * 4 + terms as usize * 8 + texels * 2 + texel_padding(texels))?;
        }
        spans.push(&start[..start.len() - r.bytes.len()]);
    }
    let kept = spans
        .into_par_iter()
        .map(|span| parse_group(span, file))
        .collect::<std::result::Result<Vec<_>, String>>()?;
    let operators = (0..r.count(16 + 7 * 4 + 8)?)
        .map(|_| parse_operator(&mut r))
        .collect::<std::result::Result<Vec<_>, String>>()?;
    let direct = match r.take(1)?[0] {
        0 => None,
        1 => Some(parse_direct(&mut r)?),
        _ => return Err("its direct light is marked neither absent nor present".into()),
    };
    if !r.bytes.is_empty() {
        return Err("it has bytes past its direct light".into());
    }
    Ok(KeptTransport {
        key,
        report,
        words,
        kept,
        operators,
        direct,
    })
}

/// One receiver group's links from its bytes (as [`parse_body`] found them: their counts
/// already checked against the bytes), a span of `file`'s.
fn parse_group(
    bytes: &[u8],
    file: &SharedBytes,
) -> std::result::Result<Vec<ReceiverLinks>, String> {
    let mut r = Reader { bytes };
    let members = r.u32()? as usize;
    let mut group = Vec::with_capacity(members.min(r.bytes.len() / 16));
    for _ in 0..members {
        let surfel = r.u32()?;
        let (ends, terms, texels) = (r.u32()?, r.u32()?, r.u32()?);
        let ends = run(r.take(ends as usize * 4)?, file);
        let terms = run(r.take(terms as usize * 8)?, file);
        let texels = texels as usize;
        let map_texels = run(r.take(texels * 2)?, file);
        r.take(texel_padding(texels))?;
        group.push(ReceiverLinks::from_parts(surfel, ends, terms, map_texels));
    }
    Ok(group)
}

/// The values whose bytes are `bytes`, a span of `file`'s: left in place where the machine's
/// byte order is the file's and they are aligned, else copied out.
fn run<T: LittleEndian>(bytes: &[u8], file: &SharedBytes) -> Run<T> {
    let start = bytes.as_ptr() as usize - (**file).as_ref().as_ptr() as usize;
    cfg!(target_endian = "little")
        .then(|| Run::in_place(file, start..start + bytes.len()))
        .flatten()
        .unwrap_or_else(|| get(bytes).into())
}

/// The zero bytes after `texels` map texels (u16 each) that bring the next receiver to a
/// multiple of four bytes.
fn texel_padding(texels: usize) -> usize {
    2 * (texels % 2)
}

/// One BSDF operator's bytes, as the format table says.
fn put_operator(bytes: &mut Vec<u8>, key: &[u8; 16], p: OperatorParts) {
    bytes.extend_from_slice(key);
    let basis = match p.basis {
        Basis::Haar => 0,
        Basis::Texels => 1,
    };
    put(bytes, &[p.n, p.hemispheres, basis, u32::from(p.grey)]);
    put(bytes, &p.norms);
    bytes.extend_from_slice(&(p.rows.len() as u64).to_le_bytes());
    put(bytes, &p.starts);
    put(bytes, &p.rows);
    put(bytes, &p.values);
    put(bytes, &p.albedo);
    put(bytes, &p.cosines);
}

/// One BSDF operator from its bytes, checked ([`BsdfOperator::from_parts`]).
fn parse_operator(r: &mut Reader) -> std::result::Result<KeyedOperator, String> {
    let key: [u8; 16] = r.take(16)?.try_into().map_err(|_| "short key")?;
    let [n, hemispheres, basis, grey] = [r.u32()?, r.u32()?, r.u32()?, r.u32()?];
    let basis = match basis {
        0 => Basis::Haar,
        1 => Basis::Texels,
        _ => return Err("an operator is in no basis".into()),
    };
    let grey = match grey {
        0 => false,
        1 => true,
        _ => return Err("an operator is marked neither grey nor RGB".into()),
    };
    let norms: Vec<f32> = get(r.take(8)?);
    let per = if grey { 1 } else { 3 };
    let entries = r.count(4 + 4 * per)?;
    // The grid's size is checked by `from_parts`; bounded here by the bytes left.
    let size = (u64::from(hemispheres) * u64::from(n) * u64::from(n)) as usize;
    if size.saturating_mul(4 * 8) > r.bytes.len() {
        return Err("it is truncated".into());
    }
    let starts = get(r.take((size + 1) * 4)?);
    let rows = get(r.take(entries * 4)?);
    let values = get(r.take(entries * per * 4)?);
    let albedo = get(r.take(size * 6 * 4)?);
    let cosines = get(r.take(size * 4)?);
    let op = BsdfOperator::from_parts(OperatorParts {
        n,
        hemispheres,
        basis,
        starts,
        rows,
        values,
        grey,
        norms: [norms[0], norms[1]],
        albedo,
        cosines,
    })?;
    Ok((key, std::sync::Arc::new(op)))
}

/// Bytes of a [`Surfel`] in the file (and in memory).
const SURFEL_BYTES: usize = std::mem::size_of::<Surfel>();

/// The direct light's part of a transport file.
fn parse_direct(r: &mut Reader) -> std::result::Result<KeptDirect, String> {
    let hash = |r: &mut Reader| -> std::result::Result<[u8; 16], String> {
        r.take(16)?.try_into().map_err(|_| "short hash".to_string())
    };
    let geometry = hash(r)?;
    let emitters = hash(r)?;
    let materials = (0..r.count(16)?)
        .map(|_| hash(r))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let count = r.count(SURFEL_BYTES + 12 + 1 + 12)?;
    let surfels: Vec<Surfel> = get(r.take(count * SURFEL_BYTES)?);
    let emitted: Vec<f32> = get(r.take(count * 12)?);
    let emitted = emitted
        .chunks_exact(3)
        .map(|c| Rgb::new(c[0], c[1], c[2]))
        .collect();
    let mut radiance = Vec::with_capacity(count);
    let mut irradiance = Vec::with_capacity(count);
    let rgb = |r: &mut Reader| -> std::result::Result<Rgb, String> {
        let c: Vec<f32> = get(r.take(12)?);
        Ok(Rgb::new(c[0], c[1], c[2]))
    };
    for _ in 0..count {
        let (light, kept) = match r.take(1)?[0] {
            0 => (SurfelRadiance::Rgb(rgb(r)?), None),
            1 => {
                let (map, used) =
                    SparseHaar::read_from(r.bytes).ok_or("a surfel's direct light is damaged")?;
                r.take(used)?;
                (SurfelRadiance::Map(map), None)
            }
            2 => {
                let light = SurfelRadiance::Rgb(rgb(r)?);
                let e = KeptIrradiance {
                    irradiance: rgb(r)?,
                    shading: rgb(r)?,
                };
                (light, Some(e))
            }
            _ => return Err("a surfel's direct light is of no kind".into()),
        };
        radiance.push(light);
        irradiance.push(kept);
    }
    Ok(KeptDirect {
        geometry,
        emitters,
        materials,
        surfels,
        radiance,
        emitted,
        irradiance,
    })
}

/// A cursor over a file's bytes that refuses to read past them.
struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> std::result::Result<&'a [u8], String> {
        if n > self.bytes.len() {
            return Err("it is truncated".into());
        }
        let (head, rest) = self.bytes.split_at(n);
        self.bytes = rest;
        Ok(head)
    }

    fn u32(&mut self) -> std::result::Result<u32, String> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn u64(&mut self) -> std::result::Result<u64, String> {
        let b = self.take(8)?;
        Ok(u64::from_le_bytes([
            b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7],
        ]))
    }

    /// A count of items of at least `item` bytes each, refused where the bytes left could
    /// not hold them (so no allocation follows a damaged count).
    fn count(&mut self, item: usize) -> std::result::Result<usize, String> {
        let n = self.u64()?;
        match usize::try_from(n) {
            Ok(n) if n.saturating_mul(item) <= self.bytes.len() => Ok(n),
            _ => Err("it is truncated".into()),
        }
    }
}

/// Values whose every field is a little-endian number of 4 or 8 bytes (or 2), as the file
/// holds them.
trait LittleEndian: bytemuck::Pod {
    /// The value with its fields' bytes swapped (big-endian machines only).
    fn swapped(self) -> Self;
}

impl LittleEndian for u16 {
    fn swapped(self) -> Self {
        self.swap_bytes()
    }
}

impl LittleEndian for u32 {
    fn swapped(self) -> Self {
        self.swap_bytes()
    }
}

impl LittleEndian for f32 {
    fn swapped(self) -> Self {
        f32::from_bits(self.to_bits().swap_bytes())
    }
}

impl LittleEndian for u64 {
    fn swapped(self) -> Self {
        self.swap_bytes()
    }
}

impl LittleEndian for Surfel {
    fn swapped(self) -> Self {
        let f = |x: f32| x.swapped();
        Surfel {
            p: self.p.map(f),
            n: self.n.map(f),
            area: f(self.area),
            mesh: self.mesh.swap_bytes(),
            triangle: self.triangle.swap_bytes(),
            b: self.b.map(f),
        }
    }
}

impl LittleEndian for Term {
    fn swapped(self) -> Self {
        Term {
            slot: self.slot.swap_bytes(),
            w: f32::from_bits(self.w.to_bits().swap_bytes()),
        }
    }
}

/// Append `values` to `bytes` in the file's byte order.
fn put<T: LittleEndian>(bytes: &mut Vec<u8>, values: &[T]) {
    if cfg!(target_endian = "little") {
        bytes.extend_from_slice(bytemuck::cast_slice(values));
    } else {
        for v in values {
            bytes.extend_from_slice(bytemuck::bytes_of(&v.swapped()));
        }
    }
}

/// The values whose bytes, in the file's byte order, are `bytes` (a whole number of them,
/// at any alignment).
fn get<T: LittleEndian>(bytes: &[u8]) -> Vec<T> {
    // The links are read in place (`run`): what is copied here is small (the bitmap, the
    // surfels, the operators), or the links on a big-endian machine.
    let values: Vec<T> = bytemuck::pod_collect_to_vec(bytes);
    if cfg!(target_endian = "little") {
        values
    } else {
        values.into_iter().map(T::swapped).collect()
    }
}

/// A length that the bounces keep below 2³² (slots and pixels are numbered in 32 bits).
fn len32<T>(items: &[T]) -> u32 {
    items.len() as u32
}

fn report_fields(r: &TransportReport) -> [u64; 8] {
    [
        r.bytes,
        r.bytes_unbounded,
        r.kept_groups as u64,
        r.regathered_groups as u64,
        r.receivers as u64,
        r.read_slots as u64,
        r.slots,
        r.incident_bytes,
    ]
}

fn report_of(f: [u64; 8]) -> TransportReport {
    TransportReport {
        bytes: f[0],
        bytes_unbounded: f[1],
        kept_groups: f[2] as usize,
        regathered_groups: f[3] as usize,
        receivers: f[4] as usize,
        read_slots: f[5] as usize,
        slots: f[6],
        incident_bytes: f[7],
    }
}

/// A writer that hashes what goes through it.
struct Hashed<W: Write> {
    inner: W,
    hash: Xxh3,
}

impl<W: Write> Write for Hashed<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hash.update(&buf[..n]);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two groups: a diffuse receiver, and a directional one of four pixels and a
    /// four-texel map.
    fn sample() -> KeptTransport {
        let term = |slot, w| Term { slot, w };
        KeptTransport {
            key: [7; 16],
            report: TransportReport {
                bytes: 1,
                bytes_unbounded: 2,
                kept_groups: 2,
                regathered_groups: 3,
                receivers: 4,
                read_slots: 5,
                slots: 6,
                incident_bytes: 7,
            },
            words: vec![0b1011, u64::MAX],
            kept: vec![
                vec![ReceiverLinks::from_parts(
                    3,
                    Run::default(),
                    vec![term(0, 0.5), term(2, -1.25)].into(),
                    Run::default(),
                )],
                vec![ReceiverLinks::from_parts(
                    9,
                    vec![1, 1, 2, 3].into(),
                    vec![term(1, 1.0), term(0, 2.0), term(4, f32::MIN_POSITIVE)].into(),
                    vec![0, 3, u16::MAX, 1].into(),
                )],
                // An odd count of map texels, padded, and a receiver after it.
                vec![
                    ReceiverLinks::from_parts(
                        11,
                        vec![1].into(),
                        vec![term(3, 0.75)].into(),
                        vec![2, u16::MAX, 0].into(),
                    ),
                    ReceiverLinks::from_parts(
                        12,
                        Run::default(),
                        vec![term(1, 0.5)].into(),
                        Run::default(),
                    ),
                ],
            ],
            operators: vec![([8; 16], std::sync::Arc::new(gold_operator()))],
            direct: Some(KeptDirect {
                geometry: [3; 16],
                emitters: [4; 16],
                materials: vec![[5; 16], [6; 16]],
                surfels: vec![
                    Surfel {
                        p: glam::Vec3::new(1.0, 2.0, 3.0),
                        n: glam::Vec3::Z,
                        area: 0.25,
                        mesh: 7,
                        triangle: 11,
                        b: glam::Vec2::new(0.125, 0.5),
                    };
                    2
                ],
                radiance: vec![
                    SurfelRadiance::Rgb(Rgb::new(0.5, 1.0, -0.0)),
                    SurfelRadiance::Map(SparseHaar::compress(
                        &crate::haar::Haar2d::forward(
                            &(0..16).map(|i| Rgb::splat(i as f32)).collect::<Vec<_>>(),
                            4,
                        ),
                        0.0,
                    )),
                ],
                emitted: vec![Rgb::ZERO, Rgb::new(1.0, 2.0, 3.0)],
                irradiance: vec![
                    Some(KeptIrradiance {
                        irradiance: Rgb::new(2.0, 0.0, 1.5),
                        shading: glam::Vec3::new(0.0, 0.6, 0.8),
                    }),
                    None,
                ],
            }),
        }
    }

    /// A gold conductor's operator on the smallest grid (2² texels): RGB entries.
    fn gold_operator() -> BsdfOperator {
        use crate::bsdf::{Bsdf, Distribution, Microfacet, RoughConductor};
        let gold = Bsdf::Conductor(RoughConductor {
            distr: Microfacet::new(Distribution::Ggx, 0.3, 0.3),
            eta: glam::Vec3::new(0.143, 0.375, 1.442),
            k: glam::Vec3::new(3.983, 2.386, 1.603),
            specular_reflectance: Rgb::ONE,
        });
        BsdfOperator::new(&gold, 2, 0.01)
    }

    fn shared(bytes: Vec<u8>) -> SharedBytes {
        crate::bake::bounce::run::AlignedBytes::shared(&bytes)
    }

    fn file_bytes(t: &KeptTransport) -> Vec<u8> {
        let mut bytes = Vec::new();
        t.stream(&mut bytes).expect("in memory");
        let digest = xxhash_rust::xxh3::xxh3_64(&bytes);
        bytes.extend_from_slice(&digest.to_le_bytes());
        bytes
    }

    #[test]
    fn a_transport_reads_back_as_written() {
        let t = sample();
        let back = parse(&shared(file_bytes(&t))).expect("parse");
        assert_eq!(
            (back.key, back.report, &back.words),
            (t.key, t.report, &t.words)
        );
        assert_eq!(back.direct, t.direct);
        assert_eq!(back.operators, t.operators);
        assert_eq!(back.kept.len(), t.kept.len());
        for (a, b) in back.kept.iter().flatten().zip(t.kept.iter().flatten()) {
            assert_eq!((a.surfel, a.parts()), (b.surfel, b.parts()));
        }
        // Read from aligned bytes on a little-endian machine, the links stay in them.
        if cfg!(target_endian = "little") {
            assert!(back.kept.iter().flatten().all(ReceiverLinks::in_place));
        }
    }

    /// Every prefix of a file is refused, and so is every byte changed, without a panic: a
    /// change the checksum misses (none here) would still meet the counts' and the links'
    /// checks.
    #[test]
    fn damaged_files_are_refused_in_words() {
        let bytes = file_bytes(&sample());
        for len in 0..bytes.len() {
            assert!(
                parse(&shared(bytes[..len].to_vec())).is_err(),
                "a prefix of {len} bytes"
            );
        }
        for i in 0..bytes.len() {
            let mut damaged = bytes.clone();
            damaged[i] ^= 0x40;
            let why = parse(&shared(damaged)).err().unwrap_or_default();
            assert!(!why.is_empty(), "byte {i} changed");
        }
        // A count past the file's end, with a checksum that matches it, is refused before
        // anything is allocated for it.
        let mut bytes = Vec::new();
        sample().stream(&mut bytes).expect("in memory");
        let words_count = 16 + 4 + 16 + 64;
        bytes[words_count..words_count + 8].copy_from_slice(&u64::MAX.to_le_bytes());
        let digest = xxhash_rust::xxh3::xxh3_64(&bytes);
        bytes.extend_from_slice(&digest.to_le_bytes());
        assert_eq!(
            parse(&shared(bytes)).err().as_deref(),
            Some("it is truncated")
        );
    }

    /// The links' own check: slots past the read ones, pixel ends out of order or past the
    /// terms, and links of the wrong kind of receiver are refused.
    #[test]
    fn links_out_of_range_are_refused() {
        let t = sample();
        let (diffuse, directional) = (&t.kept[0][0], &t.kept[1][0]);
        assert!(diffuse.check(None, 3).is_ok());
        assert!(diffuse.check(None, 2).is_err(), "slot 2 of 2 read");
        assert!(diffuse.check(Some((4, 4)), 3).is_err(), "not directional");
        assert!(directional.check(Some((4, 4)), 5).is_ok());
        assert!(directional.check(Some((4, 16)), 5).is_err(), "map size");
        assert!(directional.check(None, 5).is_err(), "not diffuse");
        for (ends, why) in [
            (vec![2, 1, 2, 3], "ends out of order"),
            (vec![1, 1, 2, 2], "ends short of the terms"),
        ] {
            let (_, terms, texels) = directional.parts();
            let links = ReceiverLinks::from_parts(
                9,
                ends.into(),
                terms.to_vec().into(),
                texels.to_vec().into(),
            );
            assert!(links.check(Some((4, 4)), 5).is_err(), "{why}");
        }
    }
}

//! The `.wpc` cache file (docs/design.md §6): a validated container of named sections.
//!
//! Layout, all integers little-endian:
//!
//! ```text
//! offset  size  header (64 bytes)
//!      0     8  magic 89 'W' 'P' 'C' 0D 0A 1A 0A   (PNG-style: catches text-mode mangling)
//!      8     4  format version
//!     12     4  byte-order mark 0x01020304 (reads 0x04030201 on a big-endian writer's file)
//!     16    16  content hash: scene content + every bake setting + crate version (XXH3-128)
//!     32     8  section table offset
//!     40     4  section count
//!     44     4  reserved (0)
//!     48     8  XXH3-64 of the section table
//!     56     8  XXH3-64 of header bytes 0..56
//! then the sections, each starting on a 64-byte boundary (so every section can be memory-mapped
//! and cast in place), in the order given, coarse to fine, then the table: per section a
//! 16-byte name (NUL-padded), offset, length and XXH3-64 of its bytes (40 bytes each).
//! ```
//!
//! Writing goes to a temporary file in the same directory, is synced, then renamed over the
//! target: a killed bake leaves the previous file or none, never a half-written one. Reading
//! checks everything before handing out a byte and says exactly what is wrong.
//!
//! [`store`] lays a bake out in those sections and reads it back typed: the one place that
//! knows the records, so that the render, the preview and the plugin read a bake without
//! the bake's code.

pub mod store;

use crate::atomic::write_atomically;
use std::io::Write;
use std::path::{Path, PathBuf};
use xxhash_rust::xxh3::{xxh3_128, xxh3_64, Xxh3};

/// The first eight bytes of every cache file.
pub(crate) const MAGIC: [u8; 8] = [0x89, b'W', b'P', b'C', 0x0d, 0x0a, 0x1a, 0x0a];
/// The format version this build writes and the newest it reads.
pub const FORMAT_VERSION: u32 = 1;
const BYTE_ORDER_MARK: u32 = 0x0102_0304;
const HEADER_LEN: usize = 64;
const ENTRY_LEN: usize = 40;
/// Sections start on multiples of this.
pub const ALIGNMENT: usize = 64;
/// Longest section name.
pub(crate) const NAME_LEN: usize = 16;

pub use crate::error::CacheError;

/// The content hash of a cache: XXH3-128 over everything that determines its contents.
pub fn content_hash(parts: &[&[u8]]) -> [u8; 16] {
    let mut all = Vec::new();
    for p in parts {
        // Length-prefixed, so ("ab", "c") and ("a", "bc") differ.
        all.extend_from_slice(&(p.len() as u64).to_le_bytes());
        all.extend_from_slice(p);
    }
    xxh3_128(&all).to_le_bytes()
}

/// A content hash as 32 lowercase hexadecimal digits (as `wpbgi inspect` prints it).
pub fn hash_hex(hash: [u8; 16]) -> String {
    hash.iter().map(|b| format!("{b:02x}")).collect()
}

/// Write `sections` (name, bytes), in order, to `path` atomically. The layout is computed
/// first and the sections are streamed to the file, so the whole cache is never copied into
/// one buffer.
pub fn write(path: &Path, hash: [u8; 16], sections: &[(&str, &[u8])]) -> Result<(), CacheError> {
    write_pieces(path, hash, &whole(sections))
}

/// [`write()`] for sections each made of pieces (name, pieces), written one after the other
/// as one section: what a writer that encodes a large section on several threads hands in,
/// without joining the pieces into one buffer first. The file is the one [`write()`] writes
/// of the joined bytes, byte for byte.
pub fn write_pieces(
    path: &Path,
    hash: [u8; 16],
    sections: &[(&str, &[&[u8]])],
) -> Result<(), CacheError> {
    let werr = |reason: String| CacheError::Write {
        path: path.to_path_buf(),
        reason,
    };
    let layout = Layout::new(hash, sections).map_err(werr)?;
    write_atomically(path, |tmp| {
        let stream = || -> std::io::Result<()> {
            let mut f = std::io::BufWriter::new(std::fs::File::create(tmp)?);
            layout.stream(&mut f, sections)?;
            f.into_inner().map_err(|e| e.into_error())?.sync_all()
        };
        stream().map_err(|e| e.to_string())
    })
    .map_err(|e| werr(e.to_string()))
}

/// The bytes of a cache holding `sections` (in pieces, as [`write_pieces`]), in memory (what
/// [`write_pieces`] would write), for a reader that needs a cache that never goes to disk:
/// the bake's bounces read the tree of the previous bounce this way.
pub fn to_bytes(hash: [u8; 16], sections: &[(&str, &[&[u8]])]) -> Result<Vec<u8>, String> {
    let layout = Layout::new(hash, sections)?;
    let mut bytes = Vec::with_capacity(layout.table_offset + layout.table.len());
    layout
        .stream(&mut bytes, sections)
        .map_err(|e| e.to_string())?;
    Ok(bytes)
}

/// Sections of one piece each, as [`write_pieces`] takes them.
fn whole<'a>(sections: &'a [(&'a str, &'a [u8])]) -> Vec<(&'a str, &'a [&'a [u8]])> {
    sections
        .iter()
        .map(|(name, bytes)| (*name, std::slice::from_ref(bytes)))
        .collect()
}

/// The XXH3-64 of `pieces` joined: the same value as `xxh3_64` of their concatenation.
fn checksum(pieces: &[&[u8]]) -> u64 {
    match pieces {
        [one] => xxh3_64(one),
        _ => {
            let mut h = Xxh3::new();
            pieces.iter().for_each(|p| h.update(p));
            h.digest()
        }
    }
}

/// Where everything of a cache goes: its header, the sections' offsets and the table.
struct Layout {
    header: [u8; HEADER_LEN],
    offsets: Vec<usize>,
    table: Vec<u8>,
    table_offset: usize,
}

impl Layout {
    fn new(hash: [u8; 16], sections: &[(&str, &[&[u8]])]) -> Result<Layout, String> {
        let aligned = |x: usize| x.div_ceil(ALIGNMENT) * ALIGNMENT;
        let mut table = Vec::with_capacity(sections.len() * ENTRY_LEN);
        let mut offsets = Vec::with_capacity(sections.len());
        let mut at = HEADER_LEN;
        for (name, pieces) in sections {
            if name.is_empty() || name.len() > NAME_LEN || name.contains('\0') {
                return Err(format!("bad section name \"{name}\""));
            }
            let len: usize = pieces.iter().map(|p| p.len()).sum();
            at = aligned(at);
            offsets.push(at);
            let mut n = [0u8; NAME_LEN];
            n[..name.len()].copy_from_slice(name.as_bytes());
            table.extend_from_slice(&n);
            table.extend_from_slice(&(at as u64).to_le_bytes());
            table.extend_from_slice(&(len as u64).to_le_bytes());
            table.extend_from_slice(&checksum(pieces).to_le_bytes());
            at += len;
        }
        let table_offset = aligned(at);
        let mut h = [0u8; HEADER_LEN];
        h[0..8].copy_from_slice(&MAGIC);
        h[8..12].copy_from_slice(&FORMAT_VERSION.to_le_bytes());
        h[12..16].copy_from_slice(&BYTE_ORDER_MARK.to_le_bytes());
        h[16..32].copy_from_slice(&hash);
        h[32..40].copy_from_slice(&(table_offset as u64).to_le_bytes());
        h[40..44].copy_from_slice(&(sections.len() as u32).to_le_bytes());
        h[48..56].copy_from_slice(&xxh3_64(&table).to_le_bytes());
        let header_sum = xxh3_64(&h[..56]);
        h[56..64].copy_from_slice(&header_sum.to_le_bytes());
        Ok(Layout {
            header: h,
            offsets,
            table,
            table_offset,
        })
    }

    /// Write the header, the (aligned) sections and the table to `out`.
    fn stream(&self, out: &mut impl Write, sections: &[(&str, &[&[u8]])]) -> std::io::Result<()> {
        let zeros = [0u8; ALIGNMENT];
        let mut written = HEADER_LEN;
        out.write_all(&self.header)?;
        for ((_, pieces), &offset) in sections.iter().zip(&self.offsets) {
            out.write_all(&zeros[..offset - written])?;
            written = offset;
            for piece in *pieces {
                out.write_all(piece)?;
                written += piece.len();
            }
        }
        out.write_all(&zeros[..self.table_offset - written])?;
        out.write_all(&self.table)
    }
}

/// One section of a read cache.
#[derive(Clone, Debug, PartialEq)]
pub struct SectionInfo {
    /// The section's name (`plan`, `nodes`, …).
    pub name: String,
    /// Where it starts in the file (bytes).
    pub offset: u64,
    /// Its length (bytes).
    pub length: u64,
    /// Its XXH3-64 checksum.
    pub checksum: u64,
}

/// A cache file, fully validated.
#[derive(Debug)]
pub struct Cache {
    /// The file it was read from.
    pub path: PathBuf,
    /// The format version it was written in.
    pub version: u32,
    /// The content hash of what made it (a bake's: the scene, the settings and the version).
    pub hash: [u8; 16],
    /// Its sections, in file order.
    pub sections: Vec<SectionInfo>,
    bytes: CacheBytes,
}

/// A cache's bytes: the file mapped read-only into memory, or bytes made in memory.
#[derive(Debug)]
pub enum CacheBytes {
    /// Processes that map one file share its pages (the kernel's page cache): a node's
    /// render tasks hold one copy of the cache between them, not one each.
    Mapped(memmap2::Mmap),
    /// Bytes made in memory (a bake not yet written, a test's).
    Owned(Vec<u8>),
}

impl std::ops::Deref for CacheBytes {
    type Target = [u8];

    fn deref(&self) -> &[u8] {
        match self {
            CacheBytes::Mapped(m) => m,
            CacheBytes::Owned(v) => v,
        }
    }
}

impl From<Vec<u8>> for CacheBytes {
    fn from(bytes: Vec<u8>) -> Self {
        CacheBytes::Owned(bytes)
    }
}

impl Cache {
    /// Map and validate `path`. With `expected_hash`, a file baked from other content or
    /// settings is refused as stale.
    ///
    /// The file is memory-mapped read-only, so that every process reading one cache (a farm
    /// node's render tasks) shares its pages. wpbgi never writes a cache in place: a bake
    /// writes a temporary file and renames it over the old one, which leaves a mapped old
    /// file intact until its readers close it. Another program truncating the file while it
    /// is mapped would stop the reader (SIGBUS): caches are to be replaced, never rewritten
    /// (docs/farm.md).
    pub fn read(path: &Path, expected_hash: Option<[u8; 16]>) -> Result<Cache, CacheError> {
        let io = |source| CacheError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = std::fs::File::open(path).map_err(io)?;
        let bytes = if file.metadata().map_err(io)?.len() == 0 {
            // An empty file cannot be mapped; parse says what is wrong with it.
            CacheBytes::Owned(Vec::new())
        } else {
            // SAFETY: the map is read-only and private to this process; its contents are
            // checked (checksums, bounds) before any is used. The one hazard, another
            // process truncating the file meanwhile, is excluded by the rule above.
            CacheBytes::Mapped(unsafe { memmap2::Mmap::map(&file) }.map_err(io)?)
        };
        Self::parse(path, bytes, expected_hash)
    }

    /// Validate `bytes` as the contents of `path`.
    pub fn parse(
        path: &Path,
        bytes: impl Into<CacheBytes>,
        expected_hash: Option<[u8; 16]>,
    ) -> Result<Cache, CacheError> {
        let bytes = bytes.into();
        let p = || path.to_path_buf();
        let truncated = |what: &str| CacheError::Truncated {
            path: p(),
            what: what.to_string(),
        };
        if bytes.is_empty() {
            return Err(truncated("the file is empty"));
        }
        if bytes.len() < MAGIC.len() || bytes[..8] != MAGIC {
            // A short file that starts like ours is truncated, not foreign.
            return Err(if MAGIC.starts_with(&bytes[..bytes.len().min(8)]) {
                truncated("the header is incomplete")
            } else {
                CacheError::Foreign { path: p() }
            });
        }
        if bytes.len() < HEADER_LEN {
            return Err(truncated("the header is incomplete"));
        }
        let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
        let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().expect("8 bytes"));
        if u64_at(56) != xxh3_64(&bytes[..56]) {
            return Err(CacheError::Corrupted {
                path: p(),
                what: "the header".into(),
            });
        }
        let version = u32_at(8);
        if u32_at(12) != BYTE_ORDER_MARK {
            return Err(CacheError::ByteOrder { path: p() });
        }
        if version > FORMAT_VERSION {
            return Err(CacheError::NewerVersion {
                path: p(),
                found: version,
                supported: FORMAT_VERSION,
            });
        }
        let hash: [u8; 16] = bytes[16..32].try_into().expect("16 bytes");
        let table_offset = u64_at(32);
        let count = u32_at(40) as u64;
        let table_end = count
            .checked_mul(ENTRY_LEN as u64)
            .and_then(|l| l.checked_add(table_offset));
        let Some(table_end) = table_end else {
            return Err(CacheError::Malformed {
                path: p(),
                what: "the section table's extent overflows".into(),
            });
        };
        if table_end > bytes.len() as u64 {
            return Err(truncated("the section table is cut off"));
        }
        if table_end < bytes.len() as u64 {
            return Err(CacheError::Malformed {
                path: p(),
                what: format!(
                    "{} bytes follow the section table",
                    bytes.len() as u64 - table_end
                ),
            });
        }
        let table = &bytes[table_offset as usize..table_end as usize];
        if u64_at(48) != xxh3_64(table) {
            return Err(CacheError::Corrupted {
                path: p(),
                what: "the section table".into(),
            });
        }
        let mut sections = Vec::with_capacity(count as usize);
        for e in table.chunks_exact(ENTRY_LEN) {
            let name_bytes = &e[..NAME_LEN];
            let end = name_bytes.iter().position(|&b| b == 0).unwrap_or(NAME_LEN);
            let name = String::from_utf8_lossy(&name_bytes[..end]).into_owned();
            let f = |o: usize| u64::from_le_bytes(e[o..o + 8].try_into().expect("8 bytes"));
            let (offset, length, checksum) = (f(16), f(24), f(32));
            let fits = offset % ALIGNMENT as u64 == 0
                && offset >= HEADER_LEN as u64
                && offset
                    .checked_add(length)
                    .is_some_and(|end| end <= table_offset);
            if !fits {
                return Err(CacheError::Malformed {
                    path: p(),
                    what: format!("section \"{name}\" lies outside the data area"),
                });
            }
            let data = &bytes[offset as usize..(offset + length) as usize];
            if xxh3_64(data) != checksum {
                return Err(CacheError::Corrupted {
                    path: p(),
                    what: format!("section \"{name}\""),
                });
            }
            sections.push(SectionInfo {
                name,
                offset,
                length,
                checksum,
            });
        }
        // The padding between sections is not under any checksum: it must be zero, so that
        // every byte of the file is checked.
        let mut covered: Vec<(u64, u64)> = sections.iter().map(|s| (s.offset, s.length)).collect();
        covered.sort_unstable();
        let mut at = HEADER_LEN as u64;
        for (offset, length) in covered.into_iter().chain([(table_offset, 0)]) {
            if offset < at {
                return Err(CacheError::Malformed {
                    path: p(),
                    what: "sections overlap".into(),
                });
            }
            if bytes[at as usize..offset as usize].iter().any(|&b| b != 0) {
                return Err(CacheError::Corrupted {
                    path: p(),
                    what: format!("the padding at byte {at}"),
                });
            }
            at = offset + length;
        }
        let cache = Cache {
            path: path.to_path_buf(),
            version,
            hash,
            sections,
            bytes,
        };
        if let Some(h) = expected_hash {
            cache.check_fresh(h)?;
        }
        Ok(cache)
    }

    /// Refuse the cache as stale unless it was baked from content with hash `expected`.
    pub(crate) fn check_fresh(&self, expected: [u8; 16]) -> Result<(), CacheError> {
        if self.hash == expected {
            Ok(())
        } else {
            Err(CacheError::Stale {
                path: self.path.clone(),
            })
        }
    }

    /// The bytes of the section `name` (aligned to [`ALIGNMENT`] within the file).
    pub fn section(&self, name: &str) -> Result<&[u8], CacheError> {
        let s = self
            .sections
            .iter()
            .find(|s| s.name == name)
            .ok_or_else(|| CacheError::MissingSection {
                path: self.path.clone(),
                name: name.to_string(),
            })?;
        Ok(&self.bytes[s.offset as usize..(s.offset + s.length) as usize])
    }

    /// Size of the whole file.
    pub fn len(&self) -> usize {
        self.bytes.len()
    }

    /// Whether the file has no bytes (never, for a valid cache).
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }
}

//! Typed errors of the library. Every message is one sentence that names the file and, where
//! there is one, the object (mesh, material, accessor, texture) at fault.

use std::path::PathBuf;

/// Everything the library refuses or fails at; `Display` is the one-sentence message.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file at fault.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },

    /// A glTF file that does not parse.
    #[error("{path}: not a valid glTF file: {reason}")]
    GltfFormat {
        /// The file at fault.
        path: PathBuf,
        /// Why, in words.
        reason: String,
    },

    /// A glTF buffer that is missing or too short.
    #[error("{path}: buffer {buffer}: {reason}")]
    Buffer {
        /// The file at fault.
        path: PathBuf,
        /// The buffer's index.
        buffer: usize,
        /// Why, in words.
        reason: String,
    },

    /// A mesh primitive that cannot be imported (indices out of range, NaN positions, ...).
    #[error("{path}: mesh \"{mesh}\", primitive {primitive}: {reason}")]
    Mesh {
        /// The file at fault.
        path: PathBuf,
        /// The mesh's name.
        mesh: String,
        /// The primitive's index in the mesh.
        primitive: usize,
        /// Why, in words.
        reason: String,
    },

    /// A material that cannot be mapped onto Mitsuba's BSDFs.
    #[error("{path}: material \"{material}\": {reason}")]
    Material {
        /// The file at fault.
        path: PathBuf,
        /// The material's name.
        material: String,
        /// Why, in words.
        reason: String,
    },

    /// A texture image that cannot be read.
    #[error("{path}: texture image {image}: {reason}")]
    Texture {
        /// The file at fault.
        path: PathBuf,
        /// The image's name or URI.
        image: String,
        /// Why, in words.
        reason: String,
    },

    /// A USD stage that cannot be read or composed.
    #[error("{path}: {reason}")]
    Usd {
        /// The file at fault.
        path: PathBuf,
        /// Why, in words.
        reason: String,
    },

    /// A USD prim that cannot be imported.
    #[error("{path}: prim {prim}: {reason}")]
    UsdPrim {
        /// The file at fault.
        path: PathBuf,
        /// The prim's path.
        prim: String,
        /// Why, in words.
        reason: String,
    },

    /// A file whose extension names no scene format wpbgi reads.
    #[error(
        "{path}: unsupported scene format (expected .gltf, .glb, .usd, .usda, .usdc or .usdz)"
    )]
    UnsupportedFormat {
        /// The file at fault.
        path: PathBuf,
    },

    /// A scene without any light, which would render black.
    #[error("{path}: the scene has no emitter (no emissive material, light or environment), so it would render black; light it with an environment: --env FILE.exr, FILE.hdr or R,G,B on the command line, wpbgi_scene_set_environment in the C library")]
    NoEmitter {
        /// The file at fault.
        path: PathBuf,
    },

    /// A scene without triangles.
    #[error("{path}: the scene has no geometry to render")]
    EmptyScene {
        /// The file at fault.
        path: PathBuf,
    },

    /// A camera that is missing or cannot be used.
    #[error("{path}: {reason}")]
    Camera {
        /// The file at fault.
        path: PathBuf,
        /// Why, in words.
        reason: String,
    },

    /// A setting out of range: one sentence naming the setting, its value and its range.
    #[error("invalid setting: {0}")]
    InvalidSetting(String),

    /// An image that cannot be read as OpenEXR.
    #[error("{path}: cannot read as an OpenEXR image: {reason}")]
    ImageRead {
        /// The file at fault.
        path: PathBuf,
        /// Why, in words.
        reason: String,
    },

    /// An output file that cannot be written.
    #[error("cannot write {path}: {reason}")]
    Output {
        /// The file at fault.
        path: PathBuf,
        /// Why, in words.
        reason: String,
    },

    /// A cache file refused ([`CacheError`]).
    #[error(transparent)]
    Cache(#[from] CacheError),

    /// A scene edit (`wpbgi relight --set`) that cannot be parsed or applied.
    #[error("edit \"{edit}\": {reason}")]
    Edit {
        /// The edit as given.
        edit: String,
        /// Why, in words (naming what the scene or the target has).
        reason: String,
    },

    /// Worker threads that the system would not start.
    #[error("cannot start {count} worker threads: {reason}")]
    Threads {
        /// How many were asked for.
        count: usize,
        /// Why, in the system's words.
        reason: String,
    },

    /// The bake or render was stopped by its cancel flag.
    #[error("cancelled")]
    Cancelled,
}

/// The library's result: [`Error`] unless said otherwise.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Why a cache file was refused.
#[derive(Debug, thiserror::Error)]
pub enum CacheError {
    /// The cache could not be read.
    #[error("cannot read the cache {path}: {source}")]
    Io {
        /// The file at fault.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// Not a wpbgi cache.
    #[error("{path} is not a wpbgi cache (wrong magic bytes)")]
    Foreign {
        /// The file at fault.
        path: PathBuf,
    },
    /// A newer cache format than this build reads.
    #[error("{path} was written by a newer wpbgi (cache format {found}, this build reads up to {supported}); rebake or upgrade")]
    NewerVersion {
        /// The file at fault.
        path: PathBuf,
        /// The file's format version.
        found: u32,
        /// The newest version this build reads.
        supported: u32,
    },
    /// A cache of the other byte order.
    #[error("{path} was written with the other byte order and cannot be read here")]
    ByteOrder {
        /// The file at fault.
        path: PathBuf,
    },
    /// A cache shorter than its header says.
    #[error("{path} is truncated: {what}")]
    Truncated {
        /// The file at fault.
        path: PathBuf,
        /// The part at fault.
        what: String,
    },
    /// A section whose checksum fails.
    #[error("{path} is corrupted: {what} fails its checksum")]
    Corrupted {
        /// The file at fault.
        path: PathBuf,
        /// The part at fault.
        what: String,
    },
    /// A section whose contents are inconsistent.
    #[error("{path} is malformed: {what}")]
    Malformed {
        /// The file at fault.
        path: PathBuf,
        /// The part at fault.
        what: String,
    },
    /// A cache baked from another scene or other settings.
    #[error("{path} is stale: the scene or the bake settings changed since it was baked; rebake")]
    Stale {
        /// The file at fault.
        path: PathBuf,
    },
    /// A section the reader needs is missing.
    #[error("{path} has no \"{name}\" section")]
    MissingSection {
        /// The file at fault.
        path: PathBuf,
        /// The section's name.
        name: String,
    },
    /// The cache could not be written.
    #[error("cannot write the cache {path}: {reason}")]
    Write {
        /// The file at fault.
        path: PathBuf,
        /// Why, in words.
        reason: String,
    },
}

/// The message a caught panic carried (`panic!` with a literal or with formatting).
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".to_string())
}

/// `Err(Error::Cancelled)` once `cancel` is set: what the cancellable bake and render call
/// between units of work.
pub(crate) fn check_cancel(cancel: &std::sync::atomic::AtomicBool) -> Result<()> {
    if cancel.load(std::sync::atomic::Ordering::Relaxed) {
        Err(Error::Cancelled)
    } else {
        Ok(())
    }
}

//! Typed errors of the library. Every message is one sentence that names the file and, where
//! there is one, the object (mesh, material, accessor, texture) at fault.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    #[error("{path}: not a valid glTF file: {reason}")]
    GltfFormat { path: PathBuf, reason: String },

    #[error("{path}: buffer {buffer}: {reason}")]
    Buffer {
        path: PathBuf,
        buffer: usize,
        reason: String,
    },

    #[error("{path}: mesh \"{mesh}\", primitive {primitive}: {reason}")]
    Mesh {
        path: PathBuf,
        mesh: String,
        primitive: usize,
        reason: String,
    },

    #[error("{path}: material \"{material}\": {reason}")]
    Material {
        path: PathBuf,
        material: String,
        reason: String,
    },

    #[error("{path}: texture image {image}: {reason}")]
    Texture {
        path: PathBuf,
        image: String,
        reason: String,
    },

    #[error("{path}: {reason}")]
    Usd { path: PathBuf, reason: String },

    #[error("{path}: prim {prim}: {reason}")]
    UsdPrim {
        path: PathBuf,
        prim: String,
        reason: String,
    },

    #[error(
        "{path}: unsupported scene format (expected .gltf, .glb, .usd, .usda, .usdc or .usdz)"
    )]
    UnsupportedFormat { path: PathBuf },

    #[error("{path}: the scene has no emitter (no emissive material, light or environment), so it would render black; light it with an environment: --env FILE.exr, FILE.hdr or R,G,B on the command line, wpbgi_scene_set_environment in the C library")]
    NoEmitter { path: PathBuf },

    #[error("{path}: the scene has no geometry to render")]
    EmptyScene { path: PathBuf },

    #[error("{path}: {reason}")]
    Camera { path: PathBuf, reason: String },

    #[error("invalid setting: {0}")]
    InvalidSetting(String),

    #[error("{path}: cannot read as an OpenEXR image: {reason}")]
    ImageRead { path: PathBuf, reason: String },

    #[error("cannot write {path}: {reason}")]
    Output { path: PathBuf, reason: String },

    #[error(transparent)]
    Cache(#[from] CacheError),

    /// The bake or render was stopped by its cancel flag.
    #[error("cancelled")]
    Cancelled,
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Why a cache file was refused.
#[derive(Debug, thiserror::Error)]
pub enum CacheError {
    #[error("cannot read the cache {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path} is not a wpbgi cache (wrong magic bytes)")]
    Foreign { path: PathBuf },
    #[error("{path} was written by a newer wpbgi (cache format {found}, this build reads up to {supported}); rebake or upgrade")]
    NewerVersion {
        path: PathBuf,
        found: u32,
        supported: u32,
    },
    #[error("{path} was written with the other byte order and cannot be read here")]
    ByteOrder { path: PathBuf },
    #[error("{path} is truncated: {what}")]
    Truncated { path: PathBuf, what: String },
    #[error("{path} is corrupted: {what} fails its checksum")]
    Corrupted { path: PathBuf, what: String },
    #[error("{path} is malformed: {what}")]
    Malformed { path: PathBuf, what: String },
    #[error("{path} is stale: the scene or the bake settings changed since it was baked; rebake")]
    Stale { path: PathBuf },
    #[error("{path} has no \"{name}\" section")]
    MissingSection { path: PathBuf, name: String },
    #[error("cannot write the cache {path}: {reason}")]
    Write { path: PathBuf, reason: String },
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
pub fn check_cancel(cancel: &std::sync::atomic::AtomicBool) -> Result<()> {
    if cancel.load(std::sync::atomic::Ordering::Relaxed) {
        Err(Error::Cancelled)
    } else {
        Ok(())
    }
}

//! What the USD importer's parts share: the importer's state, the time attributes are read at,
//! and the small helpers for names and axes. The import itself is in the parent module, the
//! materials in [`super::shading`], the lights in [`super::lights`].

use crate::scene::model::Scene;
use glam::DMat4;
use openusd::sdf;
use openusd::usd::{Stage, TimeCode};
use std::collections::HashMap;
use std::path::Path;

/// The state of one stage's import.
pub(super) struct Importer<'a> {
    pub(super) path: &'a Path,
    pub(super) stage: &'a Stage,
    pub(super) time: Time,
    /// Stage units and up axis to the IR's metres, Y up (column vectors).
    pub(super) to_ir: DMat4,
    pub(super) scene: Scene,
    /// Material prim path (or "" for the default material) to its index.
    pub(super) materials: HashMap<String, usize>,
    /// Resolved texture file to its index, and whether `auto` reads it as sRGB.
    pub(super) textures: HashMap<String, (usize, bool)>,
    /// The primvars read by the textures of the material being imported.
    pub(super) uv_sets: Vec<String>,
    /// Each material's texture coordinate primvar (`st` unless its textures say otherwise).
    pub(super) uv_set_of: HashMap<usize, String>,
    /// Local-to-world matrices (column vectors, stage units) by prim path.
    pub(super) world: HashMap<String, DMat4>,
}

/// When attributes are read.
#[derive(Clone, Copy)]
pub(super) struct Time {
    pub(super) code: TimeCode,
    /// Asked for (`--time`): time samples win over default values.
    pub(super) explicit: bool,
}

/// An attribute's value at `time`: at an explicit time its time samples (else its default);
/// otherwise its default value, or where it has only time samples, its value at the stage's
/// start.
pub(super) fn sample(
    attr: &openusd::usd::Attribute,
    time: Time,
) -> anyhow::Result<Option<sdf::Value>> {
    if time.explicit {
        if let Some(v) = attr.get_at::<sdf::Value>(time.code)? {
            return Ok(Some(v));
        }
    }
    match attr.get::<sdf::Value>()? {
        Some(v) => Ok(Some(v)),
        None => attr.get_at::<sdf::Value>(time.code),
    }
}

/// Whether `path` is an absolute prim path of identifiers (what openusd 0.6 can resolve
/// without looping; see [`check_names`](super::check_names)).
pub(super) fn is_plain_prim_path(path: &str) -> bool {
    path.strip_prefix('/')
        .is_some_and(|p| !p.is_empty() && p.split('/').all(sdf::Path::is_valid_identifier))
}

/// `text` quoted for a message, cut to 60 characters (fuzzed names run for kilobytes).
pub(super) fn shown(text: &str) -> String {
    let cut: String = text.chars().take(60).collect();
    let more = if cut.len() < text.len() { "…" } else { "" };
    format!("{cut:?}{more}")
}

/// Whether the stage's `upAxis` is Z (Y otherwise, USD's default).
pub(super) fn stage_is_z_up(stage: &Stage) -> bool {
    stage
        .stage_metadata("upAxis")
        .ok()
        .flatten()
        .and_then(|v| v.cast::<String>().ok())
        .is_some_and(|a| a == "Z")
}

//! `wpbgi._native`: the Rust library for Python (pyo3). The package's public side is
//! `wpbgi/__init__.py`, which turns the renders into numpy arrays; this module does the work.
//!
//! Settings are keyword arguments named as the library's fields (`points`, `light_samples`,
//! `bounces`, `max_depth`, ...); what is not given keeps the library's default, the default of
//! the `wpbgi` command, and a value out of range is refused by the settings' `validate()` in
//! one sentence naming it. Long calls release the GIL and run on a worker thread while the
//! calling thread passes progress to the callback, so the callback runs in Python's thread;
//! a callback that returns True, or raises, or a Ctrl-C, cancels the work.

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use wpbgi::bake::bounce::BounceSettings;
use wpbgi::progress::{relay, Progress};
use wpbgi::render::{render_final_cancellable, GatherMode};
use wpbgi::scene::Camera;

create_exception!(
    _native,
    Error,
    PyException,
    "A wpbgi failure: one sentence naming the file, the object or the setting at fault."
);
create_exception!(
    _native,
    Cancelled,
    Error,
    "The work was cancelled by the progress callback or Ctrl-C."
);

fn to_py(e: wpbgi::Error) -> PyErr {
    match e {
        wpbgi::Error::Cancelled => Cancelled::new_err("cancelled"),
        e => Error::new_err(e.to_string()),
    }
}

/// A scene, loaded and validated.
#[pyclass(module = "wpbgi._native", frozen)]
struct Scene {
    inner: wpbgi::Scene,
}

#[pymethods]
impl Scene {
    /// Load a glTF (.gltf, .glb) or USD (.usd, .usda, .usdc, .usdz) scene; `time_code`: the
    /// USD time its attributes are read at (None: the stage's default time).
    #[new]
    #[pyo3(signature = (path, time_code=None))]
    fn new(path: PathBuf, time_code: Option<f64>) -> PyResult<Self> {
        let inner = wpbgi::Scene::load_at(&path, time_code).map_err(to_py)?;
        Ok(Scene { inner })
    }

    /// What the importer noticed and worked around.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings.iter().map(|w| w.0.clone()).collect()
    }

    /// The names of the scene's cameras.
    #[getter]
    fn cameras(&self) -> Vec<String> {
        self.inner.cameras.iter().map(|c| c.name.clone()).collect()
    }

    /// This scene with `edits` applied in order, each in the syntax of `wpbgi --set`
    /// ("NAME.PARAMETER=VALUE" or "NAME.PARAMETER*=VALUE"); an edit that names nothing raises
    /// `wpbgi.Error` naming it.
    fn edited(&self, edits: Vec<String>) -> PyResult<Scene> {
        let inner = self.inner.edited(&parse_edits(&edits)?).map_err(to_py)?;
        Ok(Scene { inner })
    }
}

/// `edits` in the syntax of `wpbgi --set`, parsed.
fn parse_edits(edits: &[String]) -> PyResult<Vec<wpbgi::scene::edit::Edit>> {
    edits.iter().map(|e| e.parse().map_err(to_py)).collect()
}

/// A baked cache, refused unless it was baked from `scene` as it is now.
#[pyclass(module = "wpbgi._native", frozen)]
struct Cache {
    inner: wpbgi::Cache,
}

#[pymethods]
impl Cache {
    #[new]
    fn new(scene: &Scene, path: PathBuf) -> PyResult<Self> {
        let inner = wpbgi::Cache::open_fresh(&scene.inner, &path)
            .map_err(|e| to_py(wpbgi::Error::Cache(e)))?;
        Ok(Cache { inner })
    }

    /// The content hash of the bake (32 hexadecimal digits).
    #[getter]
    fn hash(&self) -> String {
        wpbgi::cache::hash_hex(self.inner.cache.hash)
    }
}

/// Run `work` with a progress report and a cancel flag, on `threads` workers (0: one per
/// core), the GIL released; the reports reach `progress(stage, fraction)` on this thread, and
/// a true answer (or Ctrl-C, or an exception it raises) stops the work.
fn reporting<R: Send>(
    py: Python<'_>,
    threads: usize,
    progress: Option<PyObject>,
    work: impl FnOnce(Progress, &AtomicBool) -> wpbgi::error::Result<R> + Send,
) -> PyResult<R> {
    let mut raised: Option<PyErr> = None;
    let listen = |stage: &str, fraction: f32| {
        if raised.is_some() {
            return true;
        }
        let stop = Python::with_gil(|py| -> PyResult<bool> {
            py.check_signals()?;
            match &progress {
                Some(callback) => callback.call1(py, (stage, fraction))?.is_truthy(py),
                None => Ok(false),
            }
        });
        stop.unwrap_or_else(|e| {
            raised = Some(e);
            true
        })
    };
    let relayed = py.allow_threads(|| relay(threads, work, listen));
    if let Some(e) = raised {
        return Err(e);
    }
    let (result, cancelled) = relayed.map_err(to_py)?;
    if cancelled {
        return Err(Cancelled::new_err("cancelled"));
    }
    result.map_err(to_py)
}

fn refuse(key: &str, what: &str, allowed: &[&str]) -> PyErr {
    Error::new_err(format!(
        "{what} has no setting \"{key}\"; it takes {}",
        allowed.join(", ")
    ))
}

const BAKE_KEYS: &[&str] = &[
    "quality",
    "points",
    "light_samples",
    "threshold",
    "split_level",
    "seed",
    "max_cut",
    "bounces",
    "receiver_stride",
    "transport_memory",
    "surfel_density",
];

/// The bake's settings: the library's default (`wpbgi bake`'s), the preset `quality` names,
/// then each other key given.
fn bake_settings(settings: Option<&Bound<'_, PyDict>>) -> PyResult<wpbgi::BakeSettings> {
    let get = |key: &str| settings.and_then(|d| d.get_item(key).ok().flatten());
    let mut s = match get("quality") {
        Some(q) if !q.is_none() => {
            let name: String = q.extract()?;
            let quality = wpbgi::Quality::ALL
                .into_iter()
                .find(|q| q.name() == name)
                .ok_or_else(|| {
                    let names: Vec<&str> = wpbgi::Quality::ALL.iter().map(|q| q.name()).collect();
                    Error::new_err(format!(
                        "quality \"{name}\" is not a preset; it must be one of {}",
                        names.join(", ")
                    ))
                })?;
            wpbgi::BakeSettings::preset(quality)
        }
        _ => wpbgi::BakeSettings::default(),
    };
    for (key, value) in settings.into_iter().flat_map(|d| d.iter()) {
        let key: String = key.extract()?;
        if value.is_none() {
            continue;
        }
        match key.as_str() {
            "quality" => {}
            "points" => s.points = value.extract()?,
            "light_samples" => s.light_samples = value.extract()?,
            "threshold" => s.tau = value.extract()?,
            "split_level" => s.split_level = Some(value.extract()?),
            "seed" => s.seed = value.extract()?,
            "max_cut" => s.max_cut = value.extract()?,
            "bounces" => {
                let keep = s.bounces;
                s.bounces = match value.extract::<String>() {
                    Ok(a) if a == "auto" => BounceSettings::auto(),
                    Ok(a) => {
                        return Err(Error::new_err(format!(
                            "bounces \"{a}\" must be \"auto\" or a number"
                        )))
                    }
                    Err(_) => BounceSettings::exactly(value.extract()?),
                };
                s.bounces.receiver_stride = keep.receiver_stride;
                s.bounces.transport_budget = keep.transport_budget;
            }
            "receiver_stride" => s.bounces.receiver_stride = value.extract()?,
            "transport_memory" => {
                let mb: u64 = value.extract()?;
                s.bounces.transport_budget = Some(mb.saturating_mul(1_000_000));
            }
            "surfel_density" => {
                let d = value.downcast::<PyDict>()?;
                s.surfel_density = d
                    .iter()
                    .map(|(k, v)| Ok((k.extract::<String>()?, v.extract::<f32>()?)))
                    .collect::<PyResult<_>>()?;
            }
            other => return Err(refuse(other, "bake", BAKE_KEYS)),
        }
    }
    s.validate().map_err(to_py)?;
    Ok(s)
}

/// Bake `scene` to `cache_path` (written atomically: a failed or cancelled bake leaves what
/// was there). With `keep_transport`, the bounces' transport is also written beside it
/// (`cache_path` + ".transport", as `wpbgi bake --keep-transport`), for `relight` to
/// re-solve edits of reflectances, tints and transmittances from. Returns the bake's report.
#[pyfunction]
#[pyo3(signature = (scene, cache_path, *, threads=0, progress=None, keep_transport=false, **settings))]
fn bake(
    py: Python<'_>,
    scene: &Scene,
    cache_path: PathBuf,
    threads: usize,
    progress: Option<PyObject>,
    keep_transport: bool,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyDict>> {
    let s = bake_settings(settings)?;
    let scene = &scene.inner;
    let start = std::time::Instant::now();
    let mut handoff = wpbgi::bake::bounce::TransportHandoff {
        keep: keep_transport,
        ..Default::default()
    };
    let baked = reporting(py, threads, progress, |report, cancel| {
        wpbgi::bake::bake_with_transport(scene, &s, report, cancel, &mut handoff)
    })?;
    wpbgi::bake::store::save(&cache_path, scene, &baked)
        .map_err(|e| to_py(wpbgi::Error::Cache(e)))?;
    if let Some(kept) = handoff.kept.take() {
        kept.write(&wpbgi::bake::bounce::kept::beside(&cache_path))
            .map_err(to_py)?;
    }
    let report = PyDict::new(py);
    report.set_item("surfels", baked.surfels.len())?;
    report.set_item("bounces", baked.bounces.as_ref().map_or(0, |b| b.bounces))?;
    report.set_item("seconds", start.elapsed().as_secs_f64())?;
    report.set_item(
        "hash",
        wpbgi::cache::hash_hex(wpbgi::cache::store::bake_hash(scene, &s.to_json())),
    )?;
    Ok(report.unbind())
}

/// Relight the cache at `cache_path`, a fresh bake of `scene`, for `scene` with `edits`
/// applied (see `Scene.edited`), writing the new cache to `output`: rescaled where every
/// emitter changes by one factor, baked again otherwise. Returns {"how": "rescaled" or
/// "rebaked", "factor" or "why", "seconds"}; the new cache is fresh for `scene.edited(edits)`.
#[pyfunction]
#[pyo3(signature = (scene, cache_path, output, edits, *, threads=0, progress=None))]
fn relight(
    py: Python<'_>,
    scene: &Scene,
    cache_path: PathBuf,
    output: PathBuf,
    edits: Vec<String>,
    threads: usize,
    progress: Option<PyObject>,
) -> PyResult<Py<PyDict>> {
    let edits = parse_edits(&edits)?;
    let cache = wpbgi::Cache::read(&cache_path, None).map_err(|e| to_py(wpbgi::Error::Cache(e)))?;
    let scene = &scene.inner;
    let relit = reporting(py, threads, progress, |report, cancel| {
        wpbgi::bake::relight::relight(scene, &cache, &edits, &output, report, cancel)
    })?;
    let out = PyDict::new(py);
    match &relit.how {
        wpbgi::bake::relight::Relighting::Rescaled { factor } => {
            out.set_item("how", "rescaled")?;
            out.set_item("factor", factor.to_array().to_vec())?;
        }
        wpbgi::bake::relight::Relighting::Resolved { why, .. } => {
            out.set_item("how", "resolved")?;
            out.set_item("why", why)?;
        }
        wpbgi::bake::relight::Relighting::Rebaked { why } => {
            out.set_item("how", "rebaked")?;
            out.set_item("why", why)?;
        }
    }
    out.set_item("seconds", relit.seconds)?;
    Ok(out.unbind())
}

/// The content hash a bake of `scene` with these settings would have (equal to `Cache.hash`
/// of its cache), without baking.
#[pyfunction]
#[pyo3(signature = (scene, **settings))]
fn bake_hash(scene: &Scene, settings: Option<&Bound<'_, PyDict>>) -> PyResult<String> {
    let s = bake_settings(settings)?;
    Ok(wpbgi::cache::hash_hex(wpbgi::cache::store::bake_hash(
        &scene.inner,
        &s.to_json(),
    )))
}

const RENDER_KEYS: &[&str] = &[
    "gather",
    "mb_size",
    "adaptive",
    "glossy_below",
    "adaptive_share",
    "adaptive_levels",
    "light_samples",
    "specular_below",
    "chain_depth",
    "max_depth",
    "clusters",
    "far_eps",
    "spp",
    "paths_through_glossy",
    "retrace_glossy",
    "sparse",
    "seed",
    "supersample",
];

/// The final render's settings: the library's default (`wpbgi render`'s), then each key given.
fn render_settings(settings: Option<&Bound<'_, PyDict>>) -> PyResult<wpbgi::RenderSettings> {
    let mut s = wpbgi::RenderSettings::default();
    for (key, value) in settings.into_iter().flat_map(|d| d.iter()) {
        let key: String = key.extract()?;
        if value.is_none() {
            continue;
        }
        match key.as_str() {
            "gather" => {
                s.gather = match value.extract::<String>()?.as_str() {
                    "fpbgi" => GatherMode::Fpbgi,
                    "pbgi" => GatherMode::Pbgi,
                    "paths" => GatherMode::Paths,
                    g => {
                        return Err(Error::new_err(format!(
                            "gather \"{g}\" must be \"fpbgi\", \"pbgi\" or \"paths\""
                        )))
                    }
                }
            }
            "mb_size" => s.mb_size = value.extract()?,
            "adaptive" => s.adaptive = value.extract()?,
            "glossy_below" => s.glossy_below = value.extract()?,
            "adaptive_share" => s.adaptive_share = value.extract()?,
            "adaptive_levels" => s.adaptive_levels = value.extract()?,
            "light_samples" => s.light_samples = value.extract()?,
            "specular_below" => s.specular_below = value.extract()?,
            "chain_depth" => s.chain_depth = value.extract()?,
            "max_depth" => s.max_depth = value.extract()?,
            "clusters" => s.clusters = value.extract()?,
            "far_eps" => s.far_eps = value.extract()?,
            "spp" => s.spp = value.extract()?,
            "paths_through_glossy" => s.paths_through_glossy = value.extract()?,
            "retrace_glossy" => s.retrace_glossy = value.extract()?,
            "sparse" => s.sparse = value.extract()?,
            "seed" => s.seed = value.extract()?,
            "supersample" => s.supersample = Some(value.extract()?),
            other => return Err(refuse(other, "render", RENDER_KEYS)),
        }
    }
    s.validate().map_err(to_py)?;
    Ok(s)
}

/// The final render of `scene` from `cache`: (little-endian float32 RGB bytes, rows top
/// first; height; width). `width` and `height` default as `wpbgi render`'s: the scene's
/// render settings, else `Camera::DEFAULT_SIZE`; `camera` names a scene camera (None: the
/// scene's first, or one that frames the scene).
#[pyfunction]
#[pyo3(signature = (scene, cache, width=None, height=None, camera=None, *, threads=0, progress=None, **settings))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    scene: &Scene,
    cache: &Cache,
    width: Option<u32>,
    height: Option<u32>,
    camera: Option<String>,
    threads: usize,
    progress: Option<PyObject>,
    settings: Option<&Bound<'py, PyDict>>,
) -> PyResult<(Bound<'py, PyBytes>, u32, u32)> {
    let s = render_settings(settings)?;
    let scene = &scene.inner;
    let (w, h) = match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (None, None) => scene
            .render_product
            .as_ref()
            .and_then(|p| p.resolution)
            .unwrap_or(Camera::DEFAULT_SIZE),
        _ => return Err(Error::new_err("give both width and height, or neither")),
    };
    let camera = scene.camera(camera.as_deref(), w, h).map_err(to_py)?;
    let cache = &cache.inner;
    let out = reporting(py, threads, progress, |report, cancel| {
        render_final_cancellable(scene, cache, &camera, &s, report, cancel)
    })?;
    let bytes: Vec<u8> = out
        .beauty
        .pixels
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    Ok((PyBytes::new(py, &bytes), h, w))
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scene>()?;
    m.add_class::<Cache>()?;
    m.add_function(wrap_pyfunction!(bake, m)?)?;
    m.add_function(wrap_pyfunction!(bake_hash, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(relight, m)?)?;
    m.add("Error", m.py().get_type::<Error>())?;
    m.add("Cancelled", m.py().get_type::<Cancelled>())?;
    m.add("__version__", wpbgi::VERSION)?;
    Ok(())
}

//! `wpbgi preview`: the cache splatted with Vulkan, headless to an image (or in a window).

use crate::CameraArgs;
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use serde_json::json;
use std::path::PathBuf;
use std::sync::Arc;
use wpbgi::bake::relight::relight;
use wpbgi::cache::store::BakedCache;
use wpbgi::image::{write_exr, write_png};
use wpbgi::preview::device::Gpu;
use wpbgi::preview::window::{run_window, WindowSettings};
use wpbgi::preview::{bounds, framing_camera, Frame, Preview, Show, DEFAULT_CUT_PIXELS};
use wpbgi::scene::edit::Edit;
use wpbgi::scene::{Camera, Scene};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ShowArg {
    /// Emitters and the reflected light splatted from the cache.
    Total,
    /// The reflected light only (all bounces the cache holds, without emission).
    Indirect,
    /// The emitters only.
    Direct,
    /// The cut's nodes as depth-tested discs (the point-cloud view).
    Surfels,
    /// Each node of the cut in its own colour.
    Cut,
}

impl From<ShowArg> for Show {
    fn from(s: ShowArg) -> Show {
        match s {
            ShowArg::Total => Show::Total,
            ShowArg::Indirect => Show::Indirect,
            ShowArg::Direct => Show::Direct,
            ShowArg::Surfels => Show::Surfels,
            ShowArg::Cut => Show::Cut,
        }
    }
}

#[derive(Args)]
pub struct PreviewArgs {
    /// The cache (.wpc).
    pub cache: PathBuf,
    /// The scene the cache was baked from: its meshes receive the splats and its emitters are
    /// drawn. Without it, the cache's surfels are drawn as discs (point-cloud view).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Render one frame to --output and exit, without a window.
    #[arg(long)]
    pub headless: bool,
    /// The headless frame: PNG (sRGB) or OpenEXR (linear float), by extension.
    #[arg(short, long, required_if_eq("headless", "true"))]
    pub output: Option<PathBuf>,
    /// Windowed: draw this many frames with a scripted camera (a full orbit that ends where
    /// it started), refine the cut, then exit. For tests and demos.
    #[arg(long, conflicts_with = "headless")]
    pub frames: Option<u32>,
    /// Windowed: read the last frame back from the window's swapchain into this PNG.
    #[arg(long, conflicts_with = "headless")]
    pub screenshot: Option<PathBuf>,
    /// Windowed, scripted (--frames): apply this edit (the --set syntax) in the window before
    /// the first frame, as typing it after the key e does. For tests and demos.
    #[arg(long, value_name = "EDIT", requires = "frames", requires = "scene")]
    pub window_edit: Option<String>,
    /// What to show.
    #[arg(long, value_enum, default_value = "total")]
    pub show: ShowArg,
    /// The cut's screen-space bound: nodes whose bounding spheres span at most this many
    /// pixels are drawn whole (smaller: sharper and slower).
    #[arg(long, default_value_t = DEFAULT_CUT_PIXELS)]
    pub cut_pixels: f32,
    /// Write one JSON document to standard output: the files, the size, the device and the
    /// last frame's cut and draw times; a failure as {"error": ..., "exit": ...}.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub camera: CameraArgs,
}

pub fn preview_command(a: PreviewArgs) -> Result<()> {
    if !(a.cut_pixels.is_finite() && a.cut_pixels > 0.0) {
        bail!("--cut-pixels must be a positive number");
    }
    let scene = a
        .scene
        .as_ref()
        .map(|p| -> Result<Scene> {
            let s = crate::load_scene(p)?;
            crate::warn(&s);
            Ok(s)
        })
        .transpose()?;
    let cache = match &scene {
        Some(s) => BakedCache::open_fresh(s, &a.cache)?,
        None => BakedCache::read(&a.cache, None)?,
    };
    let (w, h) = a.camera.size_for(scene.as_ref());
    let camera = match &scene {
        Some(s) => crate::pick_camera(s, &a.camera)?,
        None => pick_camera_without_scene(&cache, &a.camera)?,
    };
    if !a.headless {
        return windowed(&a, &cache, scene.as_ref(), camera);
    }
    let output = a.output.context("--headless needs --output")?;
    let (frame, gpu) =
        headless_frame(&cache, scene.as_ref(), &camera, a.show.into(), a.cut_pixels)?;
    match output.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("exr") => write_exr(&output, &frame.image)?,
        Some(e) if e.eq_ignore_ascii_case("png") => write_png(&output, &frame.image)?,
        _ => bail!("{}: the output must end in .png or .exr", output.display()),
    }
    say!(
        "wrote {} ({w}x{h} on {}): cut of {} nodes in {:.1} ms, drawn in {:.1} ms",
        output.display(),
        gpu.name,
        frame.cut_size,
        1e3 * frame.cut_seconds,
        1e3 * frame.draw_seconds
    );
    let validation = gpu.validation_messages();
    for m in &validation {
        eprintln!("validation: {m}");
    }
    if a.json {
        println!(
            "{}",
            json!({
                "command": "preview",
                "output": output.display().to_string(),
                "size": [w, h],
                "device": gpu.name,
                "cut_nodes": frame.cut_size,
                "cut_seconds": frame.cut_seconds,
                "draw_seconds": frame.draw_seconds,
                "validation": validation,
            })
        );
    }
    Ok(())
}

/// One frame of `cache` through `camera` (at the camera's size), drawn headless on the device
/// `WPBGI_VULKAN_DEVICE` names or the first there is; also the device, for its name and
/// validation messages.
pub(crate) fn headless_frame(
    cache: &BakedCache,
    scene: Option<&Scene>,
    camera: &Camera,
    show: Show,
    cut_pixels: f32,
) -> Result<(Frame, Arc<Gpu>)> {
    let gpu = Arc::new(Gpu::from_env()?);
    let mut preview = Preview::new(gpu.clone(), cache, scene, (camera.width, camera.height))?;
    let frame = preview.frame(camera, show, cut_pixels)?;
    Ok((frame, gpu))
}

/// The --eye camera, or one that frames the cache.
fn pick_camera_without_scene(cache: &BakedCache, args: &CameraArgs) -> Result<Camera> {
    if args.camera_name().is_some() {
        bail!("--camera names a scene camera and needs --scene");
    }
    let (w, h) = args.size_for(None);
    match args.eye_camera((w, h))? {
        Some(c) => Ok(c),
        None => {
            framing_camera(bounds(cache, None), w, h).context("the cache holds no surfels to frame")
        }
    }
}

/// The windowed preview: an orbit camera (left drag: orbit, right or middle drag: pan, wheel:
/// zoom; keys 1–5 or t, i, d, s, c: what to show; r: back to the start; e: type an edit,
/// Enter relights; Esc or q: quit).
fn windowed(
    a: &PreviewArgs,
    cache: &BakedCache,
    scene: Option<&Scene>,
    camera: Camera,
) -> Result<()> {
    let settings = WindowSettings {
        show: a.show.into(),
        cut_pixels: a.cut_pixels,
        frames: a.frames,
        screenshot: a.screenshot.clone(),
        validate: std::env::var("WPBGI_VALIDATE").is_ok_and(|v| v == "1"),
        edit: a.window_edit.clone(),
    };
    let mut relights = 0;
    // The transports kept beside the relit caches (hard links, see `relight`), removed when
    // the window closes: the next edit re-solves from the one beside the cache it relights.
    let mut kept_transports = Vec::new();
    // The window's edits (key e): relit through a cache file that lives as long as its
    // memory map (the name is removed at once).
    let mut relighter = |scene: &Scene, cache: &BakedCache, text: &str| {
        let edit: Edit = text.parse().map_err(|e: wpbgi::Error| e.to_string())?;
        relights += 1;
        let path = std::env::temp_dir().join(format!(
            "wpbgi-preview-relit-{}-{relights}.wpc",
            std::process::id()
        ));
        let relit = relight(
            scene,
            cache,
            &[edit],
            &path,
            &|_, _| {},
            crate::interrupt::flag(),
        )
        .map_err(|e| e.to_string())?;
        let cache = BakedCache::read(&path, None).map_err(|e| e.to_string());
        let _ = std::fs::remove_file(&path);
        kept_transports.push(wpbgi::bake::bounce::kept::beside(&path));
        say!("{text}: {}", relit.how);
        Ok((relit.scene, cache?))
    };
    let report = run_window(cache, scene, camera, &settings, Some(&mut relighter));
    for t in &kept_transports {
        let _ = std::fs::remove_file(t);
    }
    let report = report?;
    say!(
        "{} frames on {}; the last: cut of {} nodes in {:.1} ms, drawn in {:.1} ms",
        report.frames,
        report.device,
        report.last_cut_size,
        1e3 * report.last_cut_seconds,
        1e3 * report.last_draw_seconds
    );
    for m in &report.validation {
        eprintln!("validation: {m}");
    }
    if let Some(p) = &a.screenshot {
        say!("wrote {}", p.display());
    }
    if a.json {
        println!(
            "{}",
            json!({
                "command": "preview",
                "screenshot": a.screenshot.as_ref().map(|p| p.display().to_string()),
                "frames": report.frames,
                "device": report.device,
                "cut_nodes": report.last_cut_size,
                "cut_seconds": report.last_cut_seconds,
                "draw_seconds": report.last_draw_seconds,
                "validation": report.validation,
            })
        );
    }
    Ok(())
}

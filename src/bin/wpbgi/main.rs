//! The `wpbgi` command line: a thin shell over the library that parses arguments, shows progress
//! and turns every error into one sentence and a non-zero exit code.

/// `eprintln!` unless `-q`: what a command did and its figures (warnings and errors are
/// always printed, with `eprintln!`).
macro_rules! say {
    ($($arg:tt)*) => {
        if !$crate::verbosity::quiet() {
            eprintln!($($arg)*);
        }
    };
}

/// `eprintln!` with `-v` only.
macro_rules! detail {
    ($($arg:tt)*) => {
        if $crate::verbosity::verbose() {
            eprintln!($($arg)*);
        }
    };
}

mod assemble_cmd;
mod bake_cmd;
mod compare_cmd;
mod frames;
mod heap;
mod interrupt;
mod preview_cmd;
mod relight_cmd;
mod render_cmd;
mod verbosity;

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Duration;
use wpbgi::bake::bounce::BounceReport;
use wpbgi::image::{write_exr, write_png};
use wpbgi::reference::{render, RenderOutput, RenderSettings};
use wpbgi::scene::{Camera, Scene};

/// The Cornell box compiled into the binary for `wpbgi demo`.
const DEMO_SCENE: &[u8] = include_bytes!("../../../scenes/cbox-rough.gltf");

/// Mitsuba 3's render of it at 256², max_depth 8 (see scenes/README.md).
const DEMO_REFERENCE: &[u8] = include_bytes!("../../../scenes/cbox-rough_d8_ref.exr");

#[derive(Parser)]
#[command(name = "wpbgi", version, about = "Noise-free global illumination for glTF and USD scenes with Mitsuba's diffuse, roughconductor and roughdielectric materials.", long_about = None)]
struct Cli {
    /// Worker threads (default: all cores). Results are identical for any count.
    #[arg(long, global = true)]
    threads: Option<usize>,
    /// Read USD scenes at this time code (default: the stage's default time; glTF scenes have
    /// no time). Named so as not to clash with `reference --time SECONDS`.
    #[arg(long, global = true, allow_hyphen_values = true)]
    time_code: Option<f64>,
    /// Light the scene with an environment: a latitude-longitude image (.exr or .hdr; OpenEXR's
    /// orientation, +Y up and the image's centre towards +Z) or one radiance R,G,B (or V) from
    /// every direction. It replaces the scene's own dome light, and a cache baked under it is
    /// stale without it (the environment is part of the cache's hash).
    #[arg(long, global = true, value_name = "FILE|R,G,B")]
    env: Option<String>,
    /// Edit the scene as loaded: NAME.PARAMETER=VALUE sets, NAME.PARAMETER*=VALUE multiplies
    /// (NAME a material, light or the environment; VALUE one number or r,g,b). Parameters:
    /// emission (any material), reflectance (diffuse), specular_reflectance and alpha
    /// (roughconductor), specular_reflectance, specular_transmittance and alpha
    /// (roughdielectric), base_color, metallic and roughness (glTF metallic-roughness),
    /// intensity (a light, the environment). Repeatable, applied in order. The edits are part
    /// of the scene, so of a cache's hash: `relight --set` makes the cache that `render --set`
    /// with the same edits accepts.
    #[arg(long = "set", global = true, value_name = "EDIT", value_parser = parse_edit)]
    edits: Vec<wpbgi::scene::edit::Edit>,
    /// Multiplies --env's image.
    #[arg(long, global = true, default_value_t = 1.0)]
    env_intensity: f32,
    /// Turns --env's image about the world's +Y axis by this many degrees (its centre towards
    /// +X for 90).
    #[arg(long, global = true, default_value_t = 0.0, allow_hyphen_values = true)]
    env_rotate: f32,
    /// Say nothing on standard error but warnings and errors: no progress bars, plans or
    /// summaries.
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    quiet: bool,
    /// Say more on standard error: also the scene as loaded (meshes, triangles, materials,
    /// textures, lights) and the final render's gather statistics.
    #[arg(short, long, global = true)]
    verbose: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Path-trace the ground truth of a scene (unidirectional, next-event estimation with MIS,
    /// Russian roulette; Mitsuba `path` semantics) and write a float EXR.
    Reference(ReferenceArgs),
    /// The main job on the bundled Cornell box (rough gold box, glass sphere): bake it as
    /// `wpbgi bake` does (preview preset, automatic bounces) to DIR/demo.wpc, render it from the
    /// cache to DIR/demo.exr and DIR/demo.png, print the times and the error against Mitsuba
    /// 3's path-traced render (max_depth 8, DIR/mitsuba_reference.exr), and draw the cache
    /// with the Vulkan previewer, headless, to DIR/preview.png.
    Demo(DemoArgs),
    /// Bake a scene's light into a cache: Poisson-disk surfels, their direct light, then the
    /// indirect bounces (until they fade, unless --bounces says otherwise); their outgoing
    /// radiance (RGB for diffuse surfaces, Haar wavelets over directions otherwise) in the
    /// surfel tree with hierarchical wavelet coding. Prints the bake plan first.
    Bake(bake_cmd::BakeArgs),
    /// Check a cache and print its header, plan, sections and statistics.
    Inspect(bake_cmd::InspectArgs),
    /// Make a cache for the scene with its materials and lights edited (--set
    /// 'light.emission*=2'): edits that scale every emitter by one factor rescale the cache in
    /// the time of copying it; others re-solve the bounces from the transport kept beside the
    /// cache (CACHE.transport, from `bake --keep-transport`) where it fits, or else bake the
    /// edited scene again with the cache's settings; both write what a bake of the edited
    /// scene writes. The new cache is fresh for the edited scene and stale for the original.
    Relight(relight_cmd::RelightArgs),
    /// Render the final image from a cache: primary hits and direct light by ray tracing,
    /// indirect light gathered from the cache through microbuffers (FPBGI clusters by
    /// default), glossy receivers through BSDF-refined buffers, mirrors and clear glass by
    /// following their chains. Writes an EXR with optional AOV layers.
    Render(render_cmd::RenderArgs),
    /// Look at a cache with Vulkan (lavapipe or any GPU): its nodes splatted onto the scene's
    /// surfaces with radiance cache splatting, a view-dependent cut of the tree per frame.
    /// Headless to a PNG or EXR, or in a window with an orbit camera.
    Preview(preview_cmd::PreviewArgs),
    /// Measure error against run time: bake and render at each quality preset, against the
    /// path tracer's curve (1, 2, 4, … spp up to the longest bake + render) raw and denoised
    /// by OIDN, all held to one reference (given, or path-traced here). Writes report.json,
    /// error_vs_time.svg and .png, and summary.md.
    Compare(compare_cmd::CompareArgs),
    /// Stitch the tiles of one frame (`render --tile` or `--crop`, e.g. from a farm) into the
    /// frame: the tiles' data windows say where each goes; a missing or overlapping tile is
    /// refused. The frame equals a render of the whole image byte for byte (docs/farm.md).
    Assemble(assemble_cmd::AssembleArgs),
}

#[derive(Args)]
pub(crate) struct CameraArgs {
    /// Image size as WIDTHxHEIGHT (default: the USD stage's render settings' resolution, or
    /// 512x512).
    #[arg(long, value_parser = parse_size)]
    pub(crate) size: Option<(u32, u32)>,
    /// Use the scene camera with this name (default: the USD stage's render settings' camera,
    /// else the first camera, or an automatic framing).
    #[arg(long)]
    camera: Option<String>,
    /// Place a camera at this point instead (x,y,z); needs --target.
    #[arg(long, value_parser = parse_vec3, requires = "target", conflicts_with = "camera")]
    eye: Option<Vec3>,
    /// The point the --eye camera looks at (x,y,z).
    #[arg(long, value_parser = parse_vec3, requires = "eye")]
    target: Option<Vec3>,
    /// Vertical field of view of the --eye camera, in degrees.
    #[arg(long, default_value_t = 40.0)]
    fov: f32,
}

#[derive(Args)]
struct ReferenceArgs {
    /// The scene (.gltf, .glb, .usd, .usda, .usdc or .usdz).
    scene: PathBuf,
    /// Output image (OpenEXR, float32 RGB). Default: the USD stage's RenderProduct
    /// productName.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Samples per pixel.
    #[arg(long, conflicts_with = "time", required_unless_present = "time")]
    spp: Option<u32>,
    /// Render for this many seconds instead (in passes of 4 samples per pixel).
    #[arg(long)]
    time: Option<f64>,
    /// Longest path in segments, as Mitsuba's max_depth: 2 = direct light only, -1 = unlimited.
    #[arg(long, default_value_t = RenderSettings::default().max_depth, allow_hyphen_values = true)]
    max_depth: i32,
    /// Depth at which Russian roulette starts.
    #[arg(long, default_value_t = RenderSettings::default().rr_depth)]
    rr_depth: u32,
    /// Seed of the random streams.
    #[arg(long, default_value_t = RenderSettings::default().seed)]
    seed: u64,
    /// Also write the per-pixel variance of a one-sample estimate (OpenEXR; of the raw
    /// render with --denoise).
    #[arg(long)]
    variance: Option<PathBuf>,
    /// Denoise with Intel Open Image Denoise (its RT filter, HDR): the light after the first
    /// hit, guided by the first hit's albedo and normal; the emission the camera sees
    /// directly is kept as rendered. The library is loaded at run time, found on the library
    /// path or as the active Python's pyoidn (`pip install pyoidn`), or wherever
    /// WPBGI_OIDN_LIBRARY names it (docs/render.md).
    #[arg(long)]
    denoise: bool,
    /// Also write an 8-bit sRGB preview: PNG, or JPEG for a name ending in .jpg (see
    /// --exposure and --view).
    #[arg(long)]
    png: Option<PathBuf>,
    /// Render frames FIRST-LAST[:STEP] (or one FRAME): the scene at each frame's USD time
    /// code, one image each, named by `$F4` (zero-padded), `$F` or `####` in --output, --png
    /// and --variance.
    #[arg(long, value_parser = frames::parse_frames)]
    frames: Option<frames::Frames>,
    /// Write one JSON document to standard output: per frame its files, size, samples per
    /// pixel and seconds; a failure as {"error": ...}.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    display: DisplayArgs,
    #[command(flatten)]
    camera: CameraArgs,
}

/// How the 8-bit preview image (`--png`) shows the render's linear radiance.
#[derive(Args, Clone, Copy, Debug)]
pub(crate) struct DisplayArgs {
    /// Exposure of the --png image in stops: its values are scaled by 2^EV (the EXR is not).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,
    /// View transform of the --png image.
    #[arg(long, value_enum, default_value = "srgb")]
    pub view: ViewArg,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum ViewArg {
    /// sRGB's curve on values clamped to [0, 1]: above 1 clips.
    Srgb,
    /// Filmic: ACES's output transform as fitted by Narkowicz, then sRGB's curve; highlights
    /// roll off to white.
    Aces,
}

impl DisplayArgs {
    /// Write `img` as the PNG (or JPEG, by its extension) preview.
    pub fn write(&self, path: &Path, img: &wpbgi::image::Image) -> Result<()> {
        let view = match self.view {
            ViewArg::Srgb => wpbgi::image::ViewTransform::Srgb,
            ViewArg::Aces => wpbgi::image::ViewTransform::Aces,
        };
        Ok(wpbgi::image::write_display(path, img, self.exposure, view)?)
    }
}

#[derive(Args)]
struct DemoArgs {
    /// Output folder.
    #[arg(short, long, default_value = "wpbgi-demo")]
    output: PathBuf,
    /// Write one JSON document to standard output: the files, the bake's and the render's
    /// seconds, and the error against Mitsuba's render; a failure as {"error": ...}.
    #[arg(long)]
    json: bool,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or("expected WIDTHxHEIGHT, e.g. 512x512")?;
    let w: u32 = w.trim().parse().map_err(|_| format!("bad width \"{w}\""))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height \"{h}\""))?;
    Camera::check_size(w, h)?;
    Ok((w, h))
}

fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected x,y,z numbers, got \"{s}\""))?;
    if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
        return Err(format!("expected three finite numbers x,y,z, got \"{s}\""));
    }
    Ok(Vec3::from_slice(&v))
}

/// A command's seconds by stage (`bake`, `render`, `relight`) as one JSON object.
pub(crate) fn stage_seconds_json(timings: &[(&str, f64)]) -> serde_json::Value {
    timings
        .iter()
        .map(|(k, v)| (k.to_string(), serde_json::json!(v)))
        .collect::<serde_json::Map<_, _>>()
        .into()
}

/// A command's seconds by stage, a line each, in order.
pub(crate) fn say_stages(timings: &[(&str, f64)]) {
    for (stage, secs) in timings {
        say!("  {stage}: {secs:.2} s");
    }
}

/// What the bounces of a bake or a re-solving relight did, as their JSON reports it: the
/// cache's record ([`BounceReport::to_json`]) with each bounce's seconds and those of the
/// final maps.
pub(crate) fn bounces_json(r: &BounceReport) -> serde_json::Value {
    let mut json = r.to_json();
    json["seconds"] = serde_json::json!(r.seconds);
    json["final_seconds"] = serde_json::json!(r.final_seconds);
    json
}

/// The bounces' line under a bake's or a relight's stages: how many, each one's seconds and
/// the final maps' (together the "bounces" stage), the residual and the tail.
pub(crate) fn say_bounces(r: &BounceReport) {
    let per: Vec<String> = r.seconds.iter().map(|s| format!("{s:.2}")).collect();
    say!(
        "  {} bounces ({} s each) and {:.2} s turning their light into maps, residual {:.1e}{}",
        r.bounces,
        per.join(", "),
        r.final_seconds,
        r.residual,
        r.extrapolated.map_or(String::new(), |[red, green, blue]| format!(
            ", tail extrapolated (× {red:.2}, {green:.2}, {blue:.2} of the last bounce's red, green, blue)"
        )),
    );
}

pub(crate) fn progress_bar(what: &str) -> ProgressBar {
    if verbosity::quiet() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {percent}% ({elapsed}, eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}

/// A progress bar for work in named stages: the message follows the stage.
pub(crate) struct StagedBar {
    bar: ProgressBar,
    stage: std::sync::Mutex<String>,
}

impl StagedBar {
    pub(crate) fn new(what: &str) -> Self {
        StagedBar {
            bar: progress_bar(what),
            stage: Default::default(),
        }
    }

    /// Show stage `stage` at `fraction` done (from any thread).
    pub(crate) fn update(&self, stage: &str, fraction: f32) {
        let mut current = self.stage.lock().unwrap_or_else(|e| e.into_inner());
        if *current != stage {
            self.bar.set_message(stage.to_string());
            *current = stage.to_string();
        }
        self.bar.set_position((fraction * 1000.0) as u64);
    }

    pub(crate) fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

fn run_render(scene: &Scene, camera: &Camera, settings: &RenderSettings) -> Result<RenderOutput> {
    let bar = progress_bar("path tracing");
    let out = render(scene, camera, settings, &|f| {
        bar.set_position((f * 1000.0) as u64)
    })?;
    bar.finish_and_clear();
    Ok(out)
}

/// `-o`, or else the scene's RenderProduct productName (the scene is read for it once more,
/// at `--time-code`); an error naming both when neither is there.
pub(crate) fn output_or_product(output: Option<&Path>, scene: &Path) -> Result<PathBuf> {
    if let Some(o) = output {
        return Ok(o.to_path_buf());
    }
    let product = load_scene(scene)?.render_product.and_then(|p| p.name);
    product.map(PathBuf::from).with_context(|| {
        format!(
            "{}: no output: give -o (the scene has no RenderProduct with a productName)",
            scene.display()
        )
    })
}

impl CameraArgs {
    /// `--size`, or else the render settings' resolution of `scene`, or else 512x512.
    pub(crate) fn size_for(&self, scene: Option<&Scene>) -> (u32, u32) {
        self.size
            .or_else(|| scene?.render_product.as_ref()?.resolution)
            .unwrap_or(Camera::DEFAULT_SIZE)
    }

    /// The camera of --eye, --target and --fov, if given, at `size`.
    pub(crate) fn eye_camera(&self, (w, h): (u32, u32)) -> Result<Option<Camera>> {
        let (Some(eye), Some(target)) = (self.eye, self.target) else {
            return Ok(None);
        };
        if !(self.fov > 0.0 && self.fov < 180.0) {
            bail!("--fov must be between 0 and 180 degrees");
        }
        Camera::look_at("command line", eye, target, self.fov.to_radians(), w, h)
            .context("--eye and --target must be different points")
            .map(Some)
    }

    pub(crate) fn camera_name(&self) -> Option<&str> {
        self.camera.as_deref()
    }
}

/// The camera the options name (`--eye`, `--camera`), or else the render settings' camera,
/// or else the scene's first (or a framing one), at [`CameraArgs::size_for`].
pub(crate) fn pick_camera(scene: &Scene, args: &CameraArgs) -> Result<Camera> {
    let (w, h) = args.size_for(Some(scene));
    if let Some(c) = args.eye_camera((w, h))? {
        return Ok(c);
    }
    let settings_camera = scene
        .render_product
        .as_ref()
        .and_then(|p| p.camera.as_deref());
    Ok(scene.camera(args.camera_name().or(settings_camera), w, h)?)
}

/// The `--time-code` of this run.
static TIME_CODE: std::sync::OnceLock<Option<f64>> = std::sync::OnceLock::new();

/// The run's `--set` edits.
static EDITS: std::sync::OnceLock<Vec<wpbgi::scene::edit::Edit>> = std::sync::OnceLock::new();

/// The run's `--set` edits (`relight` applies them itself; every other command loads the
/// scene with them applied).
pub(crate) fn edits() -> &'static [wpbgi::scene::edit::Edit] {
    EDITS.get().map_or(&[], Vec::as_slice)
}

fn parse_edit(s: &str) -> std::result::Result<wpbgi::scene::edit::Edit, String> {
    s.parse().map_err(|e: wpbgi::Error| e.to_string())
}

/// The run's `--env`, read once.
static ENVIRONMENT: std::sync::OnceLock<Option<wpbgi::scene::Environment>> =
    std::sync::OnceLock::new();

/// The environment `--env` names: a radiance `R,G,B` or `V`, or an image file.
fn environment_of(cli: &Cli) -> Result<Option<wpbgi::scene::Environment>> {
    let Some(spec) = &cli.env else {
        return Ok(None);
    };
    let env = wpbgi::scene::Environment::from_spec(spec, cli.env_intensity, cli.env_rotate)
        .with_context(|| format!("--env {spec}"))?;
    if env.map.is_none() && cli.env_rotate != 0.0 {
        eprintln!("warning: --env-rotate turns nothing: the environment {spec} is one colour");
    }
    Ok(Some(env))
}

/// Load a scene at the run's `--time-code`, with its `--set` edits.
pub(crate) fn load_scene(path: &Path) -> Result<Scene> {
    load_scene_at(path, None)
}

/// Load a scene at time code `time` (a frame's), or without one at the run's `--time-code`,
/// with the run's `--set` edits.
pub(crate) fn load_scene_at(path: &Path, time: Option<f64>) -> Result<Scene> {
    let mut scene = load_unedited_at(path, time)?;
    scene.apply_edits(edits())?;
    Ok(scene)
}

/// Load a scene at the run's `--time-code`, without its `--set` edits (`relight`'s original).
pub(crate) fn load_unedited(path: &Path) -> Result<Scene> {
    load_unedited_at(path, None)
}

fn load_unedited_at(path: &Path, time: Option<f64>) -> Result<Scene> {
    let mut scene = Scene::load_at(path, time.or(TIME_CODE.get().copied().flatten()))?;
    if let Some(env) = ENVIRONMENT.get().cloned().flatten() {
        if let Some(own) = &scene.environment {
            scene.warnings.push(wpbgi::scene::Warning(format!(
                "--env replaces the scene's environment {}",
                own.name
            )));
        }
        scene.environment = Some(env);
    }
    detail!("{}", scene_summary(&scene));
    Ok(scene)
}

/// One line on what a scene holds, for `-v`.
fn scene_summary(scene: &Scene) -> String {
    let triangles: usize = scene.meshes.iter().map(|m| m.triangles.len()).sum();
    let textured = |m: &wpbgi::scene::Material| {
        m.normal_map.is_some() || m.cutout.is_some() || m.has_textured_roughness()
    };
    format!(
        "loaded {}: {} meshes, {triangles} triangles, {} materials ({} with textured \
         roughness, normal maps or cut-outs), {} textures, {} lights{}",
        scene.path.display(),
        scene.meshes.len(),
        scene.materials.len(),
        scene.materials.iter().filter(|m| textured(m)).count(),
        scene.textures.len(),
        scene.lights.len(),
        if scene.environment.is_some() {
            ", an environment"
        } else {
            ""
        }
    )
}

/// Whether the run named a `--time-code`.
pub(crate) fn time_code_given() -> bool {
    TIME_CODE.get().copied().flatten().is_some()
}

pub(crate) fn warn(scene: &Scene) {
    for w in &scene.warnings {
        eprintln!("warning: {}: {}", scene.path.display(), w.0);
    }
}

fn reference(a: ReferenceArgs) -> Result<()> {
    let output = output_or_product(a.output.as_deref(), &a.scene)?;
    let frames = frames::outputs(a.frames, &output, a.png.as_deref())?;
    let variance = |time: Option<f64>| -> Result<Option<PathBuf>> {
        match (&a.variance, time) {
            (Some(p), Some(f)) => frames::named(p, f as i64).map(Some),
            (v, _) => Ok(v.clone()),
        }
    };
    let mut guarded = Vec::new();
    for f in &frames {
        guarded.extend([f.output.clone()].into_iter().chain(f.png.clone()));
        guarded.extend(variance(f.time)?);
    }
    interrupt::guard_outputs(guarded);
    let time_limit = match a.time {
        Some(t) if t > 0.0 && t.is_finite() => Some(Duration::from_secs_f64(t)),
        Some(_) => bail!("--time must be a positive number of seconds"),
        None => None,
    };
    let mut records = Vec::new();
    for f in &frames {
        let (time, output, png) = (f.time, &f.output, &f.png);
        let scene = load_scene_at(&a.scene, time)?;
        warn(&scene);
        let camera = pick_camera(&scene, &a.camera)?;
        let settings = RenderSettings {
            spp: a.spp.unwrap_or(4),
            max_depth: a.max_depth,
            rr_depth: a.rr_depth,
            seed: a.seed,
            time_limit,
            first_hits: a.denoise,
            ..Default::default()
        };
        let mut out = run_render(&scene, &camera, &settings)?;
        if let Some(denoised) = out.denoised(rayon::current_num_threads()) {
            let t = std::time::Instant::now();
            out.mean = denoised?;
            out.seconds += t.elapsed().as_secs_f64();
        }
        write_exr(output, &out.mean)?;
        if let Some(p) = variance(time)? {
            write_exr(&p, &out.variance)?;
        }
        if let Some(p) = png {
            a.display.write(p, &out.mean)?;
        }
        let mp = (camera.width as f64 * camera.height as f64) / 1e6;
        say!(
            "wrote {} ({}x{}, {} spp, {:.2} s, {:.3} s/spp/MP)",
            output.display(),
            camera.width,
            camera.height,
            out.spp,
            out.seconds,
            out.seconds / (out.spp as f64 * mp)
        );
        records.push(serde_json::json!({
            "time_code": time,
            "output": output.display().to_string(),
            "png": png.as_ref().map(|p| p.display().to_string()),
            "size": [camera.width, camera.height],
            "spp": out.spp,
            "seconds": out.seconds,
            "denoised": a.denoise,
        }));
    }
    if a.json {
        println!(
            "{}",
            serde_json::json!({"command": "reference", "frames": records})
        );
    }
    Ok(())
}

fn demo(a: DemoArgs) -> Result<()> {
    if !edits().is_empty() {
        bail!(
            "demo compares the bundled scene with Mitsuba's render of it as it is; --set edits \
             a scene that bake, render or preview load"
        );
    }
    let start = std::time::Instant::now();
    std::fs::create_dir_all(&a.output)
        .with_context(|| format!("cannot create the folder {}", a.output.display()))?;
    let scene = Scene::from_gltf_bytes(Path::new("cbox-rough.gltf (bundled)"), DEMO_SCENE)?;
    warn(&scene);
    // Bake as `wpbgi bake` does by default: the preview preset, with automatic bounces.
    let settings = wpbgi::bake::BakeSettings::default();
    let bar = StagedBar::new("baking");
    let baked = wpbgi::bake::bake(&scene, &settings, &|stage, f| bar.update(stage, f))?;
    bar.finish();
    let cache_path = a.output.join("demo.wpc");
    wpbgi::bake::store::save(&cache_path, &scene, &baked)?;
    let bake_seconds = start.elapsed().as_secs_f64();
    // Render from the cache.
    let cache = wpbgi::cache::store::BakedCache::open_fresh(&scene, &cache_path)?;
    let camera = scene.default_camera(256, 256)?;
    let t = std::time::Instant::now();
    let out = render_cmd::run_final(&scene, &cache, &camera, &Default::default())?;
    let render_seconds = t.elapsed().as_secs_f64();
    let exr = a.output.join("demo.exr");
    let png = a.output.join("demo.png");
    wpbgi::image::write_exr_layers(&exr, &out.beauty, &[])?;
    write_png(&png, &out.beauty)?;
    // Against Mitsuba 3's path-traced render of the same scene (max_depth 8: what the
    // cache's bounces leave beyond eight segments is below the cache's own error).
    let reference_path = a.output.join("mitsuba_reference.exr");
    std::fs::write(&reference_path, DEMO_REFERENCE)
        .with_context(|| format!("cannot write {}", reference_path.display()))?;
    let reference = wpbgi::image::read_exr(&reference_path)?;
    say!(
        "wrote {} and {}: bake {:.2} s ({} surfels, {} bounces), render {:.2} s, total {:.2} s",
        exr.display(),
        png.display(),
        bake_seconds,
        baked.surfels.len(),
        baked.bounces.as_ref().map_or(0, |b| b.bounces),
        render_seconds,
        start.elapsed().as_secs_f64()
    );
    let error = wpbgi::image::error_against(&out.beauty, &reference);
    if let Some((mse, rel)) = error {
        say!(
            "error against Mitsuba 3 (path tracing, max_depth 8, 8192 spp): MSE {mse:.3e}, relMSE {rel:.3e}"
        );
    }
    // The cache as the previewer shows it: Vulkan, headless. A machine without a Vulkan
    // driver (lavapipe or a GPU's) still gets the rest of the demo.
    let preview_png = a.output.join("preview.png");
    let preview = match preview_cmd::headless_frame(
        &cache,
        Some(&scene),
        &camera,
        wpbgi::preview::Show::Total,
        wpbgi::preview::DEFAULT_CUT_PIXELS,
    ) {
        Ok((frame, gpu)) => {
            write_png(&preview_png, &frame.image)?;
            say!(
                "wrote {} (the preview on {}: a cut of {} nodes in {:.1} ms, drawn in {:.1} ms)",
                preview_png.display(),
                gpu.name,
                frame.cut_size,
                1e3 * frame.cut_seconds,
                1e3 * frame.draw_seconds
            );
            Some(serde_json::json!({
                "file": preview_png.display().to_string(),
                "device": gpu.name,
                "cut_nodes": frame.cut_size,
                "cut_seconds": frame.cut_seconds,
                "draw_seconds": frame.draw_seconds,
            }))
        }
        Err(e) => {
            say!("no preview frame: {e:#} (the previewer needs a Vulkan driver: lavapipe, from mesa-vulkan-drivers, or a GPU's)");
            None
        }
    };
    if a.json {
        println!(
            "{}",
            serde_json::json!({
                "command": "demo",
                "files": [exr.display().to_string(), png.display().to_string()],
                "surfels": baked.surfels.len(),
                "bake_seconds": bake_seconds,
                "render_seconds": render_seconds,
                "total_seconds": start.elapsed().as_secs_f64(),
                "mse": error.map(|e| e.0),
                "rel_mse": error.map(|e| e.1),
                "bounces": baked.bounces.as_ref().map(|b| b.bounces),
                "preview": preview,
            })
        );
    }
    Ok(())
}

fn main() {
    heap::keep_freed_memory();
    let cli = Cli::parse();
    verbosity::set(cli.quiet, cli.verbose);
    interrupt::install();
    if cli.time_code.is_some_and(|t| !t.is_finite()) {
        eprintln!("error: --time-code must be a finite number");
        std::process::exit(2);
    }
    let _ = TIME_CODE.set(cli.time_code);
    let _ = EDITS.set(cli.edits.clone());
    match environment_of(&cli) {
        Ok(env) => {
            let _ = ENVIRONMENT.set(env);
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::exit(2);
        }
    }
    if let Some(n) = cli.threads {
        if n == 0
            || rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build_global()
                .is_err()
        {
            eprintln!("error: --threads must be a positive number");
            std::process::exit(2);
        }
    }
    // Commands whose --json puts their result, or their error, on standard output.
    let json_errors = match &cli.command {
        Command::Render(a) => a.json,
        Command::Reference(a) => a.json,
        Command::Bake(a) => a.json,
        Command::Inspect(a) => a.json,
        Command::Relight(a) => a.json,
        Command::Preview(a) => a.json,
        Command::Compare(a) => a.json,
        Command::Demo(a) => a.json,
        Command::Assemble(a) => a.json,
    };
    let result = match cli.command {
        Command::Reference(a) => reference(a),
        Command::Demo(a) => demo(a),
        Command::Bake(a) => bake_cmd::bake_command(a),
        Command::Inspect(a) => bake_cmd::inspect_command(a),
        Command::Relight(a) => relight_cmd::relight_command(a),
        Command::Render(a) => render_cmd::render_command(a),
        Command::Preview(a) => preview_cmd::preview_command(a),
        Command::Compare(a) => compare_cmd::compare_command(a),
        Command::Assemble(a) => assemble_cmd::assemble_command(a),
    };
    if let Err(e) = result {
        let cancelled = matches!(e.downcast_ref(), Some(wpbgi::Error::Cancelled));
        if cancelled || interrupt::interrupted() {
            if json_errors {
                println!(
                    "{}",
                    serde_json::json!({"error": "interrupted", "exit": 130})
                );
            }
            interrupt::exit_interrupted();
        }
        let message = one_sentence(&e);
        if json_errors {
            println!("{}", serde_json::json!({"error": message, "exit": 1}));
        }
        eprintln!("error: {message}");
        std::process::exit(1);
    }
}

/// An error and its causes in one line, outermost first, leaving out a cause that the
/// message before it already says (a library error that names its OS error and also returns
/// it as its source read "… (os error 2): No such file or directory (os error 2)").
fn one_sentence(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if out.contains(&text) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&text);
    }
    out
}

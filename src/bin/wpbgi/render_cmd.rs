//! `wpbgi render`: the final image from a cache.

use crate::CameraArgs;
use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};
use std::time::Instant;
use wpbgi::cache::store::BakedCache;
use wpbgi::image::{
    exr_capture_date, read_exr, write_exr_channels, ExrChannels, ExrCompression, ExrHeader,
    ExrOptions, ExrPrecision, Image,
};
use wpbgi::render::{grid_crop, render_final_cancellable, FinalOutput, FinalSettings, GatherMode};
use wpbgi::scene::{Camera, Scene};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum GatherArg {
    /// One tree cut and microbuffer per receiver.
    Pbgi,
    /// Receivers clustered per tile (32×32 pixels, 64×64 from 512) share the far field (faster, the same image).
    Fpbgi,
    /// Rays drawn from each receiver's BSDF (--spp of them), taking the cache's light where
    /// they hit: the first bounce traced, the rest from the cache (which a draft bake
    /// serves nearly as well).
    Paths,
}

impl GatherArg {
    /// Its name on the command line.
    fn name(self) -> &'static str {
        match self {
            GatherArg::Pbgi => "pbgi",
            GatherArg::Fpbgi => "fpbgi",
            GatherArg::Paths => "paths",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ExrPrecisionArg {
    /// 16-bit floats: half the size, 11 bits of mantissa, values up to 65 504.
    Half,
    /// 32-bit floats.
    Float,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ExrCompressionArg {
    None,
    /// Run lengths: fast, large.
    Rle,
    /// zlib per scan line.
    Zips,
    /// zlib per 16 scan lines (what compositing tools write by default).
    Zip,
    /// Wavelet and Huffman: small files of noisy images.
    Piz,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Aov {
    /// Emission and direct light.
    Direct,
    /// Light from the cache.
    Indirect,
    /// Light from the cache on diffuse surfaces seen directly (indirect_diffuse).
    IndirectDiffuse,
    /// Light from the cache on glossy and specular first hits, and on everything seen through
    /// mirrors and glass (indirect_glossy).
    IndirectGlossy,
    /// Surface colour of the first hit.
    Albedo,
    /// World-space shading normal of the first hit (N.X, N.Y, N.Z).
    Normal,
    /// Distance to the first hit (Z; 0 where none).
    Depth,
    /// All of the above.
    All,
}

#[derive(Args)]
pub struct RenderArgs {
    /// The scene the cache was baked from (.gltf, .glb, .usd, .usda, .usdc or .usdz).
    pub scene: PathBuf,
    /// The cache (.wpc); refused if the scene or its bake settings changed since.
    #[arg(long)]
    pub cache: PathBuf,
    /// Output image (OpenEXR: the beauty as R, G, B and its coverage as A; --aov depth as Z,
    /// normal as N.X/N.Y/N.Z, the others as NAME.R/G/B; the header carries software,
    /// worldToCamera, worldToNDC, capDate and a `wpbgi` text attribute with the settings, the
    /// cache's hash and the render's seconds. With SOURCE_DATE_EPOCH set, capDate is that time
    /// and the seconds are left out, so that two renders give the same file byte for byte).
    /// Default: the USD stage's RenderProduct productName.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Sample precision of the EXR.
    #[arg(long, value_enum, default_value = "float")]
    pub exr_precision: ExrPrecisionArg,
    /// Lossless compression of the EXR.
    #[arg(long, value_enum, default_value = "zip")]
    pub exr_compression: ExrCompressionArg,
    /// How receivers gather the cache's light.
    #[arg(long, value_enum, default_value = "fpbgi")]
    pub gather: GatherArg,
    /// Extra layers in the EXR (comma-separated, or all).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub aov: Vec<Aov>,
    /// Microbuffer pixels per side (even).
    #[arg(long, default_value_t = FinalSettings::default().mb_size)]
    pub mb_size: u32,
    /// Uniform microbuffers for glossy receivers too (no BSDF-importance refinement).
    #[arg(long)]
    pub uniform: bool,
    /// Every receiver gathers (by default receivers gather on a grid of every 4th pixel, every
    /// 8th in frames of 512 pixels a side or more, halved where a cell fails down to every
    /// 2nd, and interpolate between where the light is smooth on one surface, seen directly or
    /// through the same mirrors and glass; in frames of 512 and more, edge pixels and what
    /// fails the finest cells first take the light of the pixels beside them: docs/render.md).
    #[arg(long)]
    pub dense: bool,
    /// Emitter samples per pixel for direct light (at each rough hit; a pixel of many camera
    /// samples, on an edge or a mirror, shares them out, at least two per sample). A diffuse
    /// hit under a few emitting triangles of constant radiance, and no other light, has its
    /// unshadowed light exact, and they only say how much is blocked: from 512 pixels on the
    /// frame's shorter side, it takes half of them.
    #[arg(long, default_value_t = FinalSettings::default().light_samples)]
    pub light_samples: u32,
    /// Longest path in segments, as Mitsuba's max_depth (-1: everything the cache holds).
    #[arg(long, default_value_t = FinalSettings::default().max_depth, allow_hyphen_values = true)]
    pub max_depth: i32,
    /// FPBGI: clusters per 32×32 pixels of a tile's gathering receivers (fewer where a tile has fewer
    /// receivers that gather than pixels).
    #[arg(long, default_value_t = FinalSettings::default().clusters)]
    pub clusters: usize,
    /// FPBGI: a node is far (shared by a cluster) when cluster radius / distance is at most
    /// this (the thesis used 0.01 at 1024² in large scenes; see docs/render.md).
    #[arg(long, default_value_t = FinalSettings::default().far_eps)]
    pub far: f32,
    /// Paths gather: rays per receiver.
    #[arg(long, default_value_t = FinalSettings::default().spp)]
    pub spp: u32,
    /// Render at N times the width and height and average each N×N block of pixels into
    /// one (1 to 4). Default: 2 for a frame whose shorter side is from 256 to 511 pixels
    /// gathered on the sparse grid (the render's grid and samples follow the frame, so at
    /// twice the size it gathers as often: at 256² that halved the error against Mitsuba on
    /// most of the reference scenes, for 0.7 to 1.8 times the time; docs/render.md), else 1.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(wpbgi::render::MAX_SUPERSAMPLE)))]
    pub supersample: Option<u32>,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Denoise the beauty with Intel Open Image Denoise (its RT filter, HDR, guided by the
    /// first hit's albedo and normal), for the noisy `--gather paths` mode, whose rays then go
    /// on through glossy and glass hits to the first rough one rather than reading the cache's
    /// blurred maps there (less bias, more noise, for the denoiser to take). The library is
    /// loaded at run time, found on the library path or as the active Python's pyoidn
    /// (`pip install pyoidn`), or wherever WPBGI_OIDN_LIBRARY names it (docs/render.md).
    #[arg(long)]
    pub denoise: bool,
    /// Render only the pixels x0 ≤ x < x1, y0 ≤ y < y1 (x0,y0,x1,y1), each exactly as in
    /// the whole image: the EXR's data window is the crop, its display window the whole
    /// image, so crops assemble into the whole image byte for byte (tiles for a farm).
    #[arg(long, value_parser = parse_crop, conflicts_with = "tile")]
    pub crop: Option<[u32; 4]>,
    /// Render only tile COLUMN,ROW (from 1,1 at the top left) of the --tile-grid: the crop
    /// of that part of the image (inner bounds on multiples of 32 pixels where the grid
    /// allows). `wpbgi assemble` stitches the tiles of a frame (docs/farm.md).
    #[arg(long, value_parser = parse_pair, requires = "tile_grid")]
    pub tile: Option<[u32; 2]>,
    /// The grid of tiles a frame is split into, COLUMNSxROWS (see --tile).
    #[arg(long, value_parser = parse_grid, requires = "tile")]
    pub tile_grid: Option<[u32; 2]>,
    /// Also write an 8-bit sRGB preview: PNG, or JPEG for a name ending in .jpg (see
    /// --exposure and --view).
    #[arg(long)]
    pub png: Option<PathBuf>,
    #[command(flatten)]
    pub display: crate::DisplayArgs,
    /// Write one JSON document to standard output: per frame its files, size, seconds per
    /// stage, gather statistics, peak memory and error against --reference; a failure as
    /// {"error": ...}. The human report stays on standard error.
    #[arg(long)]
    pub json: bool,
    /// Render frames FIRST-LAST[:STEP] (or one FRAME): the scene at each frame's USD time code,
    /// one image each, named by `$F4` (zero-padded), `$F` or `####` in --output and --png
    /// (e.g. `-o beauty.$F4.exr`). The cache must be fresh for every frame (a camera may move;
    /// geometry that moves needs a bake per frame).
    #[arg(long, value_parser = crate::frames::parse_frames)]
    pub frames: Option<crate::frames::Frames>,
    /// Print the error (MSE, relative MSE, MSSIM) against this reference image, and store it
    /// next to the output as OUTPUT.error.json.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    #[command(flatten)]
    pub camera: CameraArgs,
}

/// `s` as `N` comma-separated numbers, or a message saying `expected`.
fn parse_numbers<const N: usize>(s: &str, expected: &str) -> std::result::Result<[u32; N], String> {
    let refused = || format!("expected {expected}, got \"{s}\"");
    let v: Vec<u32> = s
        .split(',')
        .map(|t| t.trim().parse::<u32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| refused())?;
    <[u32; N]>::try_from(v).map_err(|_| refused())
}

/// `x0,y0,x1,y1` as four pixel bounds.
fn parse_crop(s: &str) -> std::result::Result<[u32; 4], String> {
    parse_numbers(s, "x0,y0,x1,y1 (four pixel bounds)")
}

/// `column,row` as two numbers.
fn parse_pair(s: &str) -> std::result::Result<[u32; 2], String> {
    parse_numbers(s, "COLUMN,ROW (two numbers from 1)")
}

/// `COLUMNSxROWS` as two numbers.
fn parse_grid(s: &str) -> std::result::Result<[u32; 2], String> {
    crate::parse_size(s)
        .map(|(c, r)| [c, r])
        .map_err(|_| format!("expected COLUMNSxROWS (e.g. 2x2), got \"{s}\""))
}

/// Render with a progress bar, stopping on Ctrl-C (see [`crate::interrupt`]).
pub fn run_final(
    scene: &Scene,
    cache: &BakedCache,
    camera: &Camera,
    settings: &FinalSettings,
) -> Result<FinalOutput> {
    let bar = crate::StagedBar::new("rendering");
    let out = render_final_cancellable(
        scene,
        cache,
        camera,
        settings,
        &|stage, f| bar.update(stage, f),
        crate::interrupt::flag(),
    )?;
    bar.finish();
    Ok(out)
}

/// The EXR options of a render of `camera`: precision, compression and the header (see
/// `--output`), with `record` (wpbgi's settings) and the render's `seconds` in its `wpbgi`
/// attribute.
pub fn exr_options(
    camera: &Camera,
    mut record: serde_json::Value,
    seconds: f64,
    precision: ExrPrecisionArg,
    compression: ExrCompressionArg,
) -> ExrOptions {
    // The reproducible-builds convention: a fixed date, and no time measured.
    let fixed = std::env::var("SOURCE_DATE_EPOCH")
        .ok()
        .and_then(|s| s.trim().parse::<u64>().ok());
    let now = fixed.unwrap_or_else(|| {
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs())
    });
    if fixed.is_none() {
        record["render_seconds"] = serde_json::json!(seconds);
    }
    ExrOptions {
        precision: match precision {
            ExrPrecisionArg::Half => ExrPrecision::Half,
            ExrPrecisionArg::Float => ExrPrecision::Float,
        },
        compression: match compression {
            ExrCompressionArg::None => ExrCompression::None,
            ExrCompressionArg::Rle => ExrCompression::Rle,
            ExrCompressionArg::Zips => ExrCompression::Zips,
            ExrCompressionArg::Zip => ExrCompression::Zip,
            ExrCompressionArg::Piz => ExrCompression::Piz,
        },
        display: (camera.width, camera.height),
        origin: (0, 0),
        header: ExrHeader {
            software: Some(format!("wpbgi {}", wpbgi::VERSION)),
            world_to_camera: Some(camera.world_to_camera()),
            world_to_ndc: Some(camera.world_to_ndc()),
            capture_date: Some(exr_capture_date(now)),
            comments: None,
            wpbgi: Some(record.to_string()),
        },
    }
}

pub fn print_summary(out: &FinalOutput) {
    let s = &out.stats;
    detail!(
        "  {} camera samples, {} receivers ({} interpolated, {} of them glossy; {} in {} clusters)",
        out.samples,
        s.receivers,
        s.interpolated,
        s.interpolated_glossy,
        s.clustered,
        s.clusters
    );
    detail!(
        "  cut: {} nodes visited and {} splatted by receivers, {} and {} by clusters; {} near \
         surfels, {} rays traced through near fields and {} through bright pixels",
        s.receiver_cut.visited,
        s.receiver_cut.splats,
        s.cluster_cut.visited,
        s.cluster_cut.splats,
        s.receiver_cut.near_leaves,
        s.near_rays,
        s.bright_rays
    );
    crate::say_stages(&out.timings);
    if let Some(b) = wpbgi::compare::memory::peak() {
        say!("  peak memory {} MB", b / 1_000_000);
    }
}

pub fn render_command(a: RenderArgs) -> Result<()> {
    let output = crate::output_or_product(a.output.as_deref(), &a.scene)?;
    let frames = crate::frames::outputs(a.frames, &output, a.png.as_deref())?;
    let cache = BakedCache::read(&a.cache, None)?;
    crate::interrupt::guard_outputs(
        frames
            .iter()
            .flat_map(|f| std::iter::once(f.output.clone()).chain(f.png.clone())),
    );
    let mut records = Vec::new();
    for f in &frames {
        records.push(render_frame(
            &a,
            &cache,
            f.time,
            &f.output,
            f.png.as_deref(),
        )?);
    }
    if a.json {
        println!(
            "{}",
            serde_json::json!({"command": "render", "frames": records})
        );
    }
    Ok(())
}

/// Render one frame: the scene at `time` (a frame's time code; `None`: `--time-code`'s) from
/// `cache`, refused if stale for the scene at that time, to `output` (and `png`). Returns the
/// frame's record for `--json`.
fn render_frame(
    a: &RenderArgs,
    cache: &BakedCache,
    time: Option<f64>,
    output: &Path,
    png: Option<&Path>,
) -> Result<serde_json::Value> {
    let start = Instant::now();
    let scene = crate::load_scene_at(&a.scene, time)?;
    crate::warn(&scene);
    let camera = crate::pick_camera(&scene, &a.camera)?;
    cache.check_scene(&scene)?;
    let bounces = cache.bounces();
    if a.max_depth >= 0 && bounces > 0 {
        eprintln!(
            "warning: the cache holds {bounces} indirect bounces, which --max-depth {} cannot cut: \
             its light is rendered whole (bake with --bounces 0 for a depth-limited render)",
            a.max_depth
        );
    }
    if a.light_samples == 0 {
        bail!("--light-samples must be at least 1");
    }
    let settings = FinalSettings {
        gather: match a.gather {
            GatherArg::Pbgi => GatherMode::Pbgi,
            GatherArg::Fpbgi => GatherMode::Fpbgi,
            GatherArg::Paths => GatherMode::Paths,
        },
        spp: a.spp,
        paths_through_glossy: a.denoise,
        mb_size: a.mb_size,
        adaptive: !a.uniform,
        sparse: !a.dense,
        light_samples: a.light_samples,
        max_depth: a.max_depth,
        clusters: a.clusters,
        far_eps: a.far,
        seed: a.seed,
        supersample: a.supersample,
        crop: match (a.tile, a.tile_grid) {
            (Some(tile), Some(grid)) => Some(grid_crop((camera.width, camera.height), grid, tile)?),
            _ => a.crop,
        },
        ..Default::default()
    };
    let reference = a.reference.as_deref().map(read_exr).transpose()?;
    if let (Some(r), Some(path)) = (&reference, &a.reference) {
        wpbgi::compare::check_size(r, camera.width, camera.height)
            .map_err(|m| anyhow::anyhow!("{}: {m} (set --size)", path.display()))?;
    }
    // A crop is compared with the same part of the reference.
    let reference = match (reference, settings.crop) {
        (Some(r), Some([x0, y0, x1, y1])) => {
            r.crop(x0, y0, x1.saturating_sub(x0), y1.saturating_sub(y0))
        }
        (r, _) => r,
    };
    let mut out = run_final(&scene, cache, &camera, &settings)?;
    if a.denoise {
        out.denoise_indirect(rayon::current_num_threads())?;
    }
    let all = a.aov.contains(&Aov::All);
    let wanted = |x: Aov| all || a.aov.contains(&x);
    let mut layers: Vec<(&str, &Image)> = Vec::new();
    for (aov, name, img) in [
        (Aov::Direct, "direct", &out.direct),
        (Aov::Indirect, "indirect", &out.indirect),
        (
            Aov::IndirectDiffuse,
            "indirect_diffuse",
            &out.indirect_diffuse,
        ),
        (Aov::IndirectGlossy, "indirect_glossy", &out.indirect_glossy),
        (Aov::Albedo, "albedo", &out.albedo),
    ] {
        if wanted(aov) {
            layers.push((name, img));
        }
    }
    let z: Vec<f32> = out.depth.pixels.iter().map(|d| d.x).collect();
    let channels = ExrChannels {
        alpha: Some(&out.alpha),
        z: wanted(Aov::Depth).then_some(&z[..]),
        normal: wanted(Aov::Normal).then_some(&out.normal),
        layers,
        ..ExrChannels::of(&out.beauty)
    };
    let record = serde_json::json!({
        "cache_hash": wpbgi::cache::hash_hex(cache.cache.hash),
        "cache": a.cache.display().to_string(),
        "camera": camera.name,
        "settings": {
            "gather": a.gather.name(),
            "mb_size": a.mb_size,
            "uniform": a.uniform,
            "dense": a.dense,
            "light_samples": a.light_samples,
            "max_depth": a.max_depth,
            "clusters": a.clusters,
            "far": a.far,
            "spp": a.spp,
            "seed": a.seed,
            "denoise": a.denoise,
        },
    });
    let mut options = exr_options(
        &camera,
        record,
        start.elapsed().as_secs_f64(),
        a.exr_precision,
        a.exr_compression,
    );
    options.origin = out.origin;
    write_exr_channels(output, &channels, &options)?;
    if let Some(p) = png {
        a.display.write(p, &out.beauty)?;
    }
    say!(
        "wrote {} ({}x{}, {} gather, {:.2} s)",
        output.display(),
        camera.width,
        camera.height,
        a.gather.name(),
        start.elapsed().as_secs_f64()
    );
    print_summary(&out);
    let s = &out.stats;
    let mut frame = serde_json::json!({
        "time_code": time,
        "output": output.display().to_string(),
        "png": png.map(|p| p.display().to_string()),
        "size": [camera.width, camera.height],
        "origin": [out.origin.0, out.origin.1],
        "seconds": start.elapsed().as_secs_f64(),
        "timings": crate::stage_seconds_json(&out.timings),
        "camera_samples": out.samples,
        "receivers": s.receivers,
        "interpolated": s.interpolated,
        "interpolated_glossy": s.interpolated_glossy,
        "peak_memory_bytes": wpbgi::compare::memory::peak(),
    });
    if let (Some(r), Some(path)) = (&reference, &a.reference) {
        let (mse, rel_mse, mssim) = wpbgi::compare::errors(&out.beauty, r)?;
        frame["error_against_reference"] = serde_json::json!({
            "reference": path.display().to_string(),
            "mse": mse,
            "rel_mse": rel_mse,
            "mssim": mssim,
        });
        say!(
            "  error against the reference: MSE {mse:.3e}, relMSE {rel_mse:.3e}, MSSIM {mssim:.4}"
        );
        let record = serde_json::json!({
            "image": output.display().to_string(),
            "reference": path.display().to_string(),
            "mse": mse,
            "rel_mse": rel_mse,
            "mssim": mssim,
            "render_s": out.timings.iter().map(|t| t.1).sum::<f64>(),
        });
        let sidecar = output.with_extension("error.json");
        wpbgi::atomic::write_atomically(&sidecar, |tmp| {
            std::fs::write(tmp, format!("{record:#}\n")).map_err(|e| e.to_string())
        })?;
        say!("  wrote {}", sidecar.display());
    }
    Ok(frame)
}

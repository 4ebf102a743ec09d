//! The final render's figures against Mitsuba 3's references (256², max_depth 3):
//!
//! 1. Equal time: bake + render (FPBGI, the defaults), then our path tracer for the same wall
//!    time; the relMSE and MSE of both.
//! 2. FPBGI against plain PBGI on the same cache: gather time, nodes visited (the cut) and
//!    splats (the rasterisation), and the relMSE between the two images.
//! 3. Adaptive against uniform microbuffers for the glossy scene: error and gather time of
//!    the adaptive 16² buffer and of uniform buffers of 16² and 32².
//!
//! `cargo run --release --example bench_render [-- SCENE_NAME]` (cbox-diffuse, cbox-rough or
//! cbox-glossy from tests/data/mitsuba; default: all three for 1 and 2, glossy for 3).
//!
//! `cargo run --release --example bench_render -- modes [SCENE_NAME ...]` (issue 20): the
//! gather modes on the default multi-bounce cache of each of the five reference scenes, at
//! 256² and 512² against Mitsuba's max_depth 8 reference (a 512² image averaged 2 × 2 down to
//! it: the reference's pixel filter is a box): every receiver gathering by FPBGI (the
//! default issue 20 measured, which the others are held to), the sparse FPBGI gather (the
//! default), and the paths gather at 16 rays, raw and denoised (`WPBGI_OIDN_LIBRARY`), each
//! with its render seconds and its ratios to the first. At 256², this version's default
//! `wpbgi render` of the same cache (`cargo build --release` first) beside, with
//! `WPBGI_PREVIOUS=/path/to/an/older/wpbgi`, that binary's, and with `WPBGI_ANCHOR_PYTHON`
//! (see `bench_bounces`) Mitsuba + OIDN at 256 spp, with the ratios; then, for cbox-diffuse,
//! cbox-rough and cbox-glossy, the whole job (`wpbgi bake` + `wpbgi render`) at Mitsuba +
//! OIDN's error (the defaults, then the denoised paths gather at rays in steps of √2 up to
//! 256, until one reaches it). `WPBGI_SIZES=256` renders 256² only.

use wpbgi::bake::bounce::BounceSettings;
use wpbgi::bake::{BakeSettings, Quality};
use wpbgi::cache::store::BakedCache;
use wpbgi::image::{error_against, read_exr};
use wpbgi::render::{render_final, FinalOutput, FinalSettings, GatherMode, GatherStats};
use wpbgi::scene::camera::Camera;
use wpbgi::scene::Scene;

mod common;

use common::data;

fn gather_seconds(o: &FinalOutput) -> f64 {
    o.timings
        .iter()
        .find(|(k, _)| *k == "gather")
        .map_or(0.0, |(_, s)| *s)
}

/// Render plain PBGI with `settings` and print its figures against the FPBGI render `fast`.
fn fpbgi_vs_pbgi(
    scene: &Scene,
    cache: &BakedCache,
    camera: &Camera,
    fast: &FinalOutput,
    settings: &FinalSettings,
) -> Result<(), Box<dyn std::error::Error>> {
    let plain = render_final(
        scene,
        cache,
        camera,
        &FinalSettings {
            gather: GatherMode::Pbgi,
            ..settings.clone()
        },
        &|_, _| {},
    )?;
    let (_, between) = error_against(&fast.beauty, &plain.beauty).ok_or("size")?;
    let (p, f) = (&plain.stats, &fast.stats);
    let visited = |s: &GatherStats| s.receiver_cut.visited + s.cluster_cut.visited;
    let splats = |s: &GatherStats| s.receiver_cut.splats + s.cluster_cut.splats;
    println!(
        "  FPBGI vs PBGI at {}x{}: gather {:.2} s vs {:.2} s ({:.2}×); cut: {} vs {} nodes visited ({:.2}×); \
         rasterisation: {} vs {} splats ({:.2}×); relMSE between {between:.2e}; {} of {} receivers in {} clusters",
        camera.width,
        camera.height,
        gather_seconds(fast),
        gather_seconds(&plain),
        gather_seconds(&plain) / gather_seconds(fast),
        visited(f),
        visited(p),
        visited(p) as f64 / visited(f) as f64,
        splats(f),
        splats(p),
        splats(p) as f64 / splats(f) as f64,
        f.clustered,
        f.receivers,
        f.clusters
    );
    Ok(())
}

/// A gather mode of `bench_render modes`: its settings, and whether its indirect light is
/// denoised (`render --denoise`).
struct Mode {
    name: &'static str,
    settings: FinalSettings,
    denoised: bool,
}

/// The gather modes compared by `bench_render modes`; the first, every receiver gathering by
/// FPBGI, is the default that issue 20 measured, which the others are held to.
fn modes() -> Vec<Mode> {
    let paths = FinalSettings {
        gather: GatherMode::Paths,
        spp: 16,
        ..Default::default()
    };
    vec![
        Mode {
            name: "fpbgi, every receiver (issue 20's)",
            settings: FinalSettings {
                sparse: false,
                ..Default::default()
            },
            denoised: false,
        },
        Mode {
            name: "fpbgi, sparse (default)",
            settings: FinalSettings::default(),
            denoised: false,
        },
        Mode {
            name: "paths, 16 rays",
            settings: paths.clone(),
            denoised: false,
        },
        Mode {
            name: "paths, 16 rays, denoised",
            // As `render --denoise` sets it: through glossy hits, for the denoiser.
            settings: FinalSettings {
                paths_through_glossy: true,
                ..paths
            },
            denoised: true,
        },
    ]
}

/// An anchor's seconds and relMSE against Mitsuba's max_depth 8 reference at 256².
type Anchor = Option<(f64, f64)>;

/// `wpbgi render` of binary `bin` with `args` on `cache` at 256², as a user runs it, from the
/// error record it writes beside its image: its render seconds and relMSE.
fn cli_render(
    bin: &std::path::Path,
    name: &str,
    cache: &std::path::Path,
    args: &[&str],
) -> Result<(f64, f64), Box<dyn std::error::Error>> {
    let out = std::env::temp_dir().join("wpbgi-bench-cli-render.exr");
    common::run_ok(
        &bin.display().to_string(),
        std::process::Command::new(bin)
            .arg("render")
            .arg(data(&format!("{name}.gltf")))
            .arg("--cache")
            .arg(cache)
            .args(["--size", "256x256", "-o"])
            .arg(&out)
            .arg("--reference")
            .arg(data(&format!("{name}_d8_ref.exr")))
            .args(args),
    )?;
    let record: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.with_extension("error.json"))?)?;
    let field = |k: &str| record[k].as_f64().ok_or("no error record");
    Ok((field("render_s")?, field("rel_mse")?))
}

/// `wpbgi bake` of binary `bin` on scene `name` at `quality` (`None`: its defaults), as a
/// user runs it: the cache's path and the seconds the process took.
fn cli_bake(
    bin: &std::path::Path,
    name: &str,
    quality: Option<&str>,
) -> Result<(std::path::PathBuf, f64), Box<dyn std::error::Error>> {
    let cache = std::env::temp_dir().join(format!("wpbgi-bench-cli-{name}.wpc"));
    let start = std::time::Instant::now();
    let mut command = std::process::Command::new(bin);
    command
        .arg("bake")
        .arg(data(&format!("{name}.gltf")))
        .arg("-o")
        .arg(&cache)
        .arg("-q");
    if let Some(q) = quality {
        command.args(["--quality", q]);
    }
    common::run_ok(&bin.display().to_string(), &mut command)?;
    Ok((cache, start.elapsed().as_secs_f64()))
}

/// Mitsuba + OIDN at 256 spp on scene `name` (`scripts/anchor`), through `python`.
fn oidn_anchor(python: &std::path::Path, name: &str) -> Result<Anchor, Box<dyn std::error::Error>> {
    let scene = data(&format!("{name}.gltf"));
    let runs = common::mitsuba_anchor(
        python,
        &scene,
        &data(&format!("{name}_d8_ref.exr")),
        &common::ANCHOR_SPP,
    )?;
    Ok(runs
        .iter()
        .find(|(spp, _)| *spp == 256)
        .and_then(|(_, v)| Some((v["oidn_total_s"].as_f64()?, v["oidn"][1].as_f64()?))))
}

/// The paths gather's rays per receiver that [`equal_error`] tries, cheapest first.
const EQUAL_ERROR_SPP: [u32; 9] = [16, 24, 32, 48, 64, 96, 128, 192, 256];

/// The whole job at equal error (issue 20): `wpbgi bake` of binary `bin` (the version
/// `version`) at `quality` (`None` for its defaults) and its `wpbgi render` (fresh
/// processes), tried from the cheapest render up, until one reaches the relMSE of Mitsuba +
/// OIDN at 256 spp (`oidn`). Prints each try's bake + render seconds and relMSE, and the
/// first that reaches it as a ratio of Mitsuba + OIDN's seconds.
fn equal_error(
    (bin, version): (&std::path::Path, &str),
    name: &str,
    quality: Option<&str>,
    oidn: (f64, f64),
) -> Result<(), Box<dyn std::error::Error>> {
    let (cache, bake_s) = cli_bake(bin, name, quality)?;
    // The path-traced gather's rays per receiver in steps of √2, so that the first try to
    // reach the error costs at most about √2 times what the exact count would.
    let mut tries: Vec<(String, Vec<String>)> = vec![("defaults".into(), Vec::new())];
    for spp in EQUAL_ERROR_SPP {
        let args = ["--gather", "paths", "--spp", &spp.to_string(), "--denoise"];
        tries.push((
            format!("paths {spp}, denoised"),
            args.map(String::from).to_vec(),
        ));
    }
    let mut reached = None;
    let mut shown = Vec::new();
    for (what, args) in &tries {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (render_s, rel) = match cli_render(bin, name, &cache, &args) {
            Ok(r) => r,
            Err(e) => {
                shown.push(format!("{what}: not run ({e})"));
                continue;
            }
        };
        let total = bake_s + render_s;
        shown.push(format!("{what}: {total:.2} s, {rel:.3e}"));
        if rel <= oidn.1 {
            reached = Some((what, total));
            break;
        }
    }
    let _ = std::fs::remove_file(&cache);
    println!(
        "| {name} | {version} | {} | {:.2} s, {:.3e} | {bake_s:.2} | {} | {} |",
        quality.unwrap_or("default"),
        oidn.0,
        oidn.1,
        shown.join("; "),
        reached.map_or("not reached".into(), |(what, t)| format!(
            "{:.2} ({what})",
            t / oidn.0
        ))
    );
    Ok(())
}

/// `bench_render modes`: one table row per scene, size and mode, rendered in this process;
/// and at 256² this version's default `wpbgi render` beside the previous version's
/// (`WPBGI_PREVIOUS`) and Mitsuba + OIDN at 256 spp (`WPBGI_ANCHOR_PYTHON`), each a fresh
/// process, with the ratios, from the same run. `WPBGI_SIZES=256` skips 512².
fn compare_modes(names: &[String]) -> Result<(), Box<dyn std::error::Error>> {
    let previous = std::env::var_os("WPBGI_PREVIOUS");
    let python = std::env::var_os("WPBGI_ANCHOR_PYTHON");
    let this_bin = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/release/wpbgi");
    let sizes: Vec<u32> = std::env::var("WPBGI_SIZES")
        .ok()
        .map(|v| v.split(',').filter_map(|s| s.parse().ok()).collect())
        .unwrap_or_else(|| vec![256, 512]);
    println!("threads: {}", rayon::current_num_threads());
    println!(
        "| scene | size | mode | render s | gather s | relMSE | s / first's | relMSE / first's | \
         interpolated receivers |"
    );
    println!("|---|---|---|---:|---:|---|---:|---:|---:|");
    let mut anchors: Vec<(String, [Anchor; 3])> = Vec::new();
    for name in names {
        let scene = Scene::load(&data(&format!("{name}.gltf")))?;
        let reference = read_exr(&data(&format!("{name}_d8_ref.exr")))?;
        // What `wpbgi bake SCENE` does: the preview preset with automatic bounces.
        let settings = BakeSettings {
            bounces: BounceSettings::auto(),
            ..BakeSettings::preset(Quality::Preview).direct_only()
        };
        let (_, cache, _) = common::bake_cache(&scene, &settings, &format!("{name}-modes"))?;
        for &size in &sizes {
            let camera = scene.default_camera(size, size)?;
            let mut first: Option<(f64, f64)> = None;
            for mode in modes() {
                let (mut out, mut seconds) =
                    common::timed_render(&scene, &cache, &camera, &mode.settings)?;
                if mode.denoised {
                    let start = std::time::Instant::now();
                    if let Err(e) = out.denoise_indirect(rayon::current_num_threads()) {
                        println!("| {name} | {size}² | {} | not run: {e} |", mode.name);
                        continue;
                    }
                    seconds += start.elapsed().as_secs_f64();
                }
                // Against Mitsuba's 256² reference; a larger render averaged down to it by
                // the reference's own box filter.
                let image = out
                    .beauty
                    .box_downsample(size / reference.width)
                    .ok_or("size")?;
                let (_, rel) = error_against(&image, &reference).ok_or("size")?;
                let (first_s, first_rel) = *first.get_or_insert((seconds, rel));
                println!(
                    "| {name} | {size}² | {} | {seconds:.2} | {:.2} | {rel:.3e} | {:.3} | {:.3} | {} of {} |",
                    mode.name,
                    gather_seconds(&out),
                    seconds / first_s,
                    rel / first_rel,
                    out.stats.interpolated,
                    out.stats.receivers
                );
            }
        }
        // Fresh processes: a render in this one, after a bake of several GB, ran up to 25 %
        // slower than the same render from the command line on the glass scenes.
        let this = match this_bin.exists() {
            true => Some(cli_render(&this_bin, name, &cache.cache.path, &[])?),
            false => None,
        };
        let before = match &previous {
            Some(bin) => Some(cli_render(
                std::path::Path::new(bin),
                name,
                &cache.cache.path,
                &[],
            )?),
            None => None,
        };
        let oidn = match &python {
            Some(py) => oidn_anchor(std::path::Path::new(py), name)?,
            None => None,
        };
        anchors.push((name.clone(), [this, before, oidn]));
        // Up to 240 MB a scene: not left in the temporary folder (the mapping stays valid).
        let _ = std::fs::remove_file(&cache.cache.path);
    }
    println!();
    println!(
        "`wpbgi render` (defaults) at 256², this version against the previous one and Mitsuba + \
         OIDN at 256 spp, same run (render s, relMSE against Mitsuba's max_depth 8):"
    );
    println!(
        "| scene | this version | previous version | Mitsuba + OIDN | previous s / this | \
         relMSE / previous's | this s / OIDN's | relMSE / OIDN's |"
    );
    println!("|---|---|---|---|---:|---:|---:|---:|");
    let shown = |a: &Anchor| a.map_or("not run".into(), |(s, r)| format!("{s:.2}, {r:.3e}"));
    let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) => format!("{:.2}", a / b),
        _ => "-".into(),
    };
    for (name, [this, before, oidn]) in &anchors {
        let (s, r) = (this.map(|a| a.0), this.map(|a| a.1));
        println!(
            "| {name} | {} | {} | {} | {} | {} | {} | {} |",
            shown(this),
            shown(before),
            shown(oidn),
            ratio(before.map(|a| a.0), s),
            ratio(r, before.map(|a| a.1)),
            ratio(s, oidn.map(|a| a.0)),
            ratio(r, oidn.map(|a| a.1)),
        );
    }
    if !this_bin.exists() {
        println!("(this version's binary not found: `cargo build --release` first)");
        return Ok(());
    }
    println!();
    println!(
        "The whole job at Mitsuba + OIDN's error (256 spp), same run: this version's `wpbgi \
         bake` (its default preset, then the draft preset, whose cache the paths gather reads \
         only at secondary hits; and the previous version's, `WPBGI_PREVIOUS`, at its default) \
         and `wpbgi render` from the cheapest render up, bake + render seconds and relMSE per \
         try, until one reaches it:"
    );
    println!(
        "| scene | version | bake preset | Mitsuba + OIDN | bake s | tries | time / OIDN's at its error |"
    );
    println!("|---|---|---|---|---:|---|---:|");
    for (name, [_, _, oidn]) in &anchors {
        if !["cbox-diffuse", "cbox-rough", "cbox-glossy"].contains(&name.as_str()) {
            continue;
        }
        match oidn {
            Some(oidn) => {
                if let Some(bin) = &previous {
                    equal_error((std::path::Path::new(bin), "previous"), name, None, *oidn)?;
                }
                for quality in [None, Some("draft")] {
                    equal_error((&this_bin, "this"), name, quality, *oidn)?;
                }
            }
            None => println!("| {name} | | | not run (`WPBGI_ANCHOR_PYTHON`) | | | |"),
        }
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1).peekable();
    if args.peek().map(String::as_str) == Some("modes") {
        let names: Vec<String> = args.skip(1).collect();
        let five = [
            "cbox-diffuse",
            "cbox-rough",
            "cbox-glossy",
            "cbox-mirror",
            "caustic",
        ];
        let names = if names.is_empty() {
            five.map(String::from).to_vec()
        } else {
            names
        };
        return compare_modes(&names);
    }
    let only = std::env::args().nth(1);
    let names: Vec<String> = match &only {
        Some(n) => vec![n.clone()],
        None => ["cbox-diffuse", "cbox-rough", "cbox-glossy"]
            .map(String::from)
            .to_vec(),
    };
    println!("threads: {}", rayon::current_num_threads());
    for name in &names {
        let scene = Scene::load(&data(&format!("{name}.gltf")))?;
        let reference = read_exr(&data(&format!("{name}_d3_ref.exr")))?;
        let camera = scene.default_camera(256, 256)?;
        // 1. Bake + render against the path tracer at equal time.
        let settings = BakeSettings::preset(Quality::Draft).direct_only();
        let (_, cache, bake_s) = common::bake_cache(&scene, &settings, name)?;
        let depth3 = FinalSettings {
            max_depth: 3,
            ..Default::default()
        };
        let (fast, render_s) = common::timed_render(&scene, &cache, &camera, &depth3)?;
        let total = bake_s + render_s;
        let (mse, rel) = error_against(&fast.beauty, &reference).ok_or("size")?;
        let pt = common::path_tracer_for(&scene, &camera, 3, total)?;
        let (pt_mse, pt_rel) = error_against(&pt.mean, &reference).ok_or("size")?;
        println!(
            "{name}: bake {bake_s:.2} s + render {render_s:.2} s = {total:.2} s: relMSE {rel:.3e}, MSE {mse:.3e}; \
             path tracer in {:.2} s ({} spp): relMSE {pt_rel:.3e}, MSE {pt_mse:.3e} ({:.1}× our relMSE)",
            pt.seconds,
            pt.spp,
            pt_rel / rel
        );
        // 2. FPBGI against PBGI, at the reference's 256² and at the scene camera's 512².
        fpbgi_vs_pbgi(&scene, &cache, &camera, &fast, &depth3)?;
        let own = scene.default_camera(512, 512)?;
        let fast_512 = render_final(&scene, &cache, &own, &depth3, &|_, _| {})?;
        fpbgi_vs_pbgi(&scene, &cache, &own, &fast_512, &depth3)?;
        let f = &fast.stats;
        // 3. Adaptive against uniform buffers.
        if name == "cbox-glossy" {
            println!(
                "  adaptive 16²: gather {:.2} s, relMSE {rel:.3e}, {} buffer pixels",
                gather_seconds(&fast),
                f.pixels
            );
            for n in [16, 32] {
                let u = render_final(
                    &scene,
                    &cache,
                    &camera,
                    &FinalSettings {
                        adaptive: false,
                        mb_size: n,
                        ..depth3.clone()
                    },
                    &|_, _| {},
                )?;
                let (_, urel) = error_against(&u.beauty, &reference).ok_or("size")?;
                println!(
                    "  uniform {n}²: gather {:.2} s, relMSE {urel:.3e}, {} buffer pixels",
                    gather_seconds(&u),
                    u.stats.pixels
                );
            }
        }
    }
    Ok(())
}

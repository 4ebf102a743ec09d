//! A still frame's whole job against deep references, beside Mitsuba 3 alone and Mitsuba 3 +
//! Intel OIDN from the same run (issue 75).
//!
//! For each scene: `wpbgi bake` and `wpbgi render --size 256x256` with their defaults, as a
//! user runs them (fresh processes, wall seconds each), the image's relMSE against Mitsuba's
//! max_depth 64 reference with that reference's own noise taken out (its per-sample variance
//! over its samples, as `mitsuba_oidn.py` does with `REF_VAR`), on caustic.gltf also the
//! relMSE inside the caustic spot under its sphere; then the seconds Mitsuba 3 alone and
//! Mitsuba 3 + OIDN take to the same relMSE (`scripts/anchor/mitsuba_oidn.py` at 4 to 1 024
//! spp, one render each denoised or not, read log-log between the two sample counts that
//! bracket it), and the still's ratios: bake + render over each.
//! With `WPBGI_PREVIOUS=/path/to/an/older/wpbgi`, the same for that binary, from the same run.
//!
//! ```sh
//! cargo build --release
//! WPBGI_ANCHOR_PYTHON=target/anchor/bin/python WPBGI_DEEP_REFS=DIR \
//!     cargo run --release --example bench_still [-- SCENE ...]
//! ```
//!
//! Scenes: the five of `tests/data/mitsuba` and the three of `tests/data/indirect` (default:
//! all eight). The indirect-lit scenes' deep references are in `tests/data/indirect` (16 384
//! spp: at 4 096 their pixels' noise inflated the relMSE, docs/testing.md); the five's are too large to keep in the repository: `WPBGI_DEEP_REFS` names a folder
//! of `{scene}_d64_ref.exr` and `{scene}_d64_var.exr` (`scripts/anchor/mitsuba_ref.py SCENE
//! OUT.exr 64 4096 --var VAR.exr`, about two minutes each on a 2-core machine), over the
//! samples written beside each (`{scene}_d64_ref.spp`), else `WPBGI_DEEP_SPP` (4 096). A
//! scene without one is listed and skipped. caustic.gltf needs 8 192 or more: its
//! reference's fireflies (the lamp through the sphere, seen from the ceiling) make the
//! variance estimate of 1 024 samples unreliable, and our relMSE against it came out three
//! times what the 8 192-sample reference gives. Without
//! `WPBGI_ANCHOR_PYTHON` (`scripts/anchor/README.md`) Mitsuba + OIDN is not run.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;
use wpbgi::image::{read_exr, Image};

#[allow(dead_code)] // the benchmarks' shared helpers, of which this one uses a few
mod common;

use common::DeepReference;

/// The image size: the references'.
const SIZE: &str = "256x256";

/// Mitsuba + OIDN's sample counts, each twice the last.
const ANCHOR_SPP: [u32; 9] = [4, 8, 16, 32, 64, 128, 256, 512, 1024];

/// caustic.gltf's focused spot at 256² (issue 75): rows 205–235 and columns 100–156.
const CAUSTIC_SPOT: ([usize; 2], [usize; 2]) = ([205, 236], [100, 157]);

const SCENES: [&str; 8] = [
    "cbox-diffuse",
    "cbox-rough",
    "cbox-glossy",
    "cbox-mirror",
    "caustic",
    "ceiling-diffuse",
    "ceiling-rough",
    "wall-glossy",
];

/// A scene and its deep reference.
struct Subject {
    name: String,
    scene: PathBuf,
    reference: DeepReference,
}

/// Scene `name`'s glTF file and deep reference, or why it has none.
fn subject(name: &str) -> Result<Subject, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let indirect = root.join("indirect");
    let (scene, refs, spp) = if indirect.join(format!("{name}.gltf")).exists() {
        (indirect.join(format!("{name}.gltf")), indirect, 16384)
    } else if !root.join(format!("mitsuba/{name}.gltf")).exists() {
        return Err("no such scene in tests/data/mitsuba or tests/data/indirect".into());
    } else {
        let refs = std::env::var_os("WPBGI_DEEP_REFS")
            .map(PathBuf::from)
            .ok_or("no deep reference (WPBGI_DEEP_REFS names none)")?;
        // The sample count mitsuba_ref.py wrote beside the image, else WPBGI_DEEP_SPP's.
        let spp = std::fs::read_to_string(refs.join(format!("{name}_d64_ref.spp")))
            .ok()
            .or_else(|| std::env::var("WPBGI_DEEP_SPP").ok())
            .and_then(|s| s.trim().parse().ok())
            .unwrap_or(4096);
        (root.join(format!("mitsuba/{name}.gltf")), refs, spp)
    };
    let reference = DeepReference {
        image: refs.join(format!("{name}_d64_ref.exr")),
        variance: refs.join(format!("{name}_d64_var.exr")),
        spp,
    };
    for path in [&scene, &reference.image, &reference.variance] {
        if !path.exists() {
            return Err(format!("{} not found", path.display()));
        }
    }
    Ok(Subject {
        name: name.into(),
        scene,
        reference,
    })
}

/// The relMSE of `image` against `reference` with the reference's own noise taken out:
/// the mean over pixels and channels of ((x − r)² − σ²/n) / (r² + 0.01), inside `rows` ×
/// `columns` when given.
fn rel_mse_less_noise(
    image: &Image,
    reference: &Image,
    (variance, spp): (&Image, u32),
    window: Option<([usize; 2], [usize; 2])>,
) -> f64 {
    let w = reference.width as usize;
    let (rows, columns) = window.unwrap_or(([0, reference.height as usize], [0, w]));
    let (mut sum, mut count) = (0.0f64, 0usize);
    for y in rows[0]..rows[1] {
        for x in columns[0]..columns[1] {
            let k = y * w + x;
            let (a, r, v) = (image.pixels[k], reference.pixels[k], variance.pixels[k]);
            for c in 0..3 {
                let (a, r, v) = (f64::from(a[c]), f64::from(r[c]), f64::from(v[c]));
                sum += ((a - r).powi(2) - v / f64::from(spp)) / (r * r + 0.01);
                count += 1;
            }
        }
    }
    sum / count as f64
}

/// One version's still: bake and render seconds, relMSE, and the caustic spot's.
struct Still {
    bake_s: f64,
    render_s: f64,
    rel: f64,
    spot: Option<f64>,
}

/// `wpbgi bake` then `wpbgi render` of binary `bin` on `subject` with their defaults, as a
/// user runs them, held to its deep reference.
fn still(bin: &Path, subject: &Subject) -> common::Result<Still> {
    let dir = std::env::temp_dir();
    let cache = dir.join(format!("wpbgi-bench-still-{}.wpc", subject.name));
    let image = dir.join(format!("wpbgi-bench-still-{}.exr", subject.name));
    let timed = |command: &mut Command| -> common::Result<f64> {
        let start = Instant::now();
        common::run_ok(&bin.display().to_string(), command)?;
        Ok(start.elapsed().as_secs_f64())
    };
    let bake_s = timed(
        Command::new(bin)
            .arg("bake")
            .arg(&subject.scene)
            .arg("-o")
            .arg(&cache)
            .arg("-q"),
    )?;
    let render_s = timed(
        Command::new(bin)
            .arg("render")
            .arg(&subject.scene)
            .arg("--cache")
            .arg(&cache)
            .args(["--size", SIZE, "-o"])
            .arg(&image),
    )?;
    let _ = std::fs::remove_file(&cache);
    let ours = read_exr(&image)?;
    let reference = read_exr(&subject.reference.image)?;
    let variance = read_exr(&subject.reference.variance)?;
    if (ours.width, ours.height) != (reference.width, reference.height) {
        return Err(format!("{}: the reference is not {SIZE}", subject.name).into());
    }
    let noise = (&variance, subject.reference.spp);
    Ok(Still {
        bake_s,
        render_s,
        rel: rel_mse_less_noise(&ours, &reference, noise, None),
        spot: (subject.name == "caustic")
            .then(|| rel_mse_less_noise(&ours, &reference, noise, Some(CAUSTIC_SPOT))),
    })
}

/// One anchor's (spp, seconds, relMSE) by sample count: Mitsuba alone, and Mitsuba + OIDN.
struct Anchors {
    mitsuba: Vec<(u32, f64, f64)>,
    oidn: Vec<(u32, f64, f64)>,
}

/// Mitsuba's and Mitsuba + OIDN's runs on `subject`, from the same renders.
fn anchor(python: &Path, subject: &Subject) -> common::Result<Anchors> {
    let runs =
        common::mitsuba_anchor_deep(python, &subject.scene, &subject.reference, &ANCHOR_SPP)?;
    let series = |seconds: &str, error: &str| -> Vec<(u32, f64, f64)> {
        runs.iter()
            .filter_map(|(spp, v)| Some((*spp, v[seconds].as_f64()?, v[error][1].as_f64()?)))
            .collect()
    };
    Ok(Anchors {
        mitsuba: series("pt_s", "pt"),
        oidn: series("oidn_total_s", "oidn"),
    })
}

/// `runs`' seconds to relMSE `target` as a table cell, and the still's `total` seconds over
/// them ("<" where the runs never reach it: the ratio is below that).
fn versus(runs: Option<&[(u32, f64, f64)]>, target: f64, total: f64) -> (String, String) {
    match runs.map(|r| seconds_to(r, target)) {
        None => ("not run".to_string(), "-".to_string()),
        Some(Ok(t)) => (format!("{t:.2}"), format!("{:.2}", total / t)),
        Some(Err(last)) => (
            format!("not reached in {last:.1}"),
            format!("< {:.2}", total / last),
        ),
    }
}

/// The seconds `runs` take to relMSE `target`: the first sample count that reaches it,
/// read log-log from the one before; `Err` with the last run's seconds when none does.
fn seconds_to(runs: &[(u32, f64, f64)], target: f64) -> Result<f64, f64> {
    let at = runs
        .iter()
        .position(|r| r.2 <= target)
        .ok_or_else(|| runs.last().map_or(0.0, |r| r.1))?;
    let (_, t1, e1) = runs[at];
    let Some(&(_, t0, e0)) = at.checked_sub(1).map(|i| &runs[i]) else {
        return Ok(t1);
    };
    if !(e0 > e1 && e1 > 0.0 && target > 0.0) {
        return Ok(t1);
    }
    let along = (e0 / target).ln() / (e0 / e1).ln();
    Ok(t0 * (t1 / t0).powf(along))
}

fn main() -> common::Result<()> {
    let names: Vec<String> = std::env::args().skip(1).collect();
    let names = if names.is_empty() {
        SCENES.map(String::from).to_vec()
    } else {
        names
    };
    let this = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/release/wpbgi");
    if !this.exists() {
        return Err("target/release/wpbgi not found: `cargo build --release` first".into());
    }
    let previous = std::env::var_os("WPBGI_PREVIOUS").map(PathBuf::from);
    let python = std::env::var_os("WPBGI_ANCHOR_PYTHON").map(PathBuf::from);
    println!(
        "A still at 256², `wpbgi bake` + `wpbgi render` (defaults) against Mitsuba's max_depth \
         64, its noise taken out; Mitsuba's and Mitsuba + OIDN's seconds to the same relMSE; {} threads.",
        rayon::current_num_threads()
    );
    println!(
        "| scene | version | bake s | render s | relMSE | caustic spot relMSE | Mitsuba s to that \
         relMSE | still ÷ Mitsuba | Mitsuba + OIDN s to that relMSE | still ÷ Mitsuba + OIDN |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for name in &names {
        let subject = match subject(name) {
            Ok(s) => s,
            Err(why) => {
                println!("| {name} | not run: {why} | | | | | | | | |");
                continue;
            }
        };
        let mut versions = vec![("this", this.clone())];
        versions.extend(previous.clone().map(|p| ("previous", p)));
        let stills: Vec<(&str, Still)> = versions
            .iter()
            .map(|(version, bin)| Ok((*version, still(bin, &subject)?)))
            .collect::<common::Result<_>>()?;
        let runs = match &python {
            Some(py) => Some(anchor(py, &subject)?),
            None => None,
        };
        for (version, s) in &stills {
            let total = s.bake_s + s.render_s;
            let (mitsuba_s, mitsuba_ratio) =
                versus(runs.as_ref().map(|r| &r.mitsuba[..]), s.rel, total);
            let (oidn_s, oidn_ratio) = versus(runs.as_ref().map(|r| &r.oidn[..]), s.rel, total);
            println!(
                "| {name} | {version} | {:.2} | {:.2} | {:.3e} | {} | {mitsuba_s} | \
                 {mitsuba_ratio} | {oidn_s} | {oidn_ratio} |",
                s.bake_s,
                s.render_s,
                s.rel,
                s.spot.map_or("-".into(), |e| format!("{e:.3e}")),
            );
        }
    }
    Ok(())
}

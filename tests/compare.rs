//! `wpbgi compare` and `wpbgi render --reference` from the outside: on the bundled scene (its
//! reference path-traced by compare) and on cbox-glossy (against Mitsuba 3's render), compare
//! writes report.json as docs/commands.md documents it, a plot with both curves as SVG and PNG, and
//! a summary; render stores the error it prints, equal to the error recomputed from the files.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use wpbgi::image::{read_exr, write_exr};

const WPBGI: &str = env!("CARGO_BIN_EXE_wpbgi");

fn root(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn dir(name: &str) -> common::Scratch {
    common::Scratch::new(&format!("compare-{name}"))
}

fn wpbgi(args: &[&str]) -> Output {
    let out = Command::new(WPBGI).args(args).output().expect("runs");
    assert!(
        out.status.success(),
        "wpbgi {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Mitsuba's 256² render of `name` (max_depth 8) box-filtered down to 32²: each 8 × 8 block's
/// mean is exactly the 32² box filter.
fn mitsuba_32(name: &str, out: &Path) {
    let r = read_exr(&root(&format!("tests/data/mitsuba/{name}_d8_ref.exr"))).expect("reference");
    write_exr(out, &r.box_downsample(8).expect("256 / 8")).expect("write reference");
}

/// The report's files exist and say what docs/commands.md says they do.
fn check_report(report: &Path, rendered_reference: bool) {
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(report.join("report.json")).expect("report.json"),
    )
    .expect("valid JSON");
    assert_eq!(json["width"], 32);
    assert_eq!(json["height"], 32);
    let reference = &json["reference"];
    if rendered_reference {
        assert_eq!(reference["spp"], 32);
        assert!(reference["seconds"].as_f64().is_some_and(|t| t > 0.0));
        assert!(report.join("reference.exr").exists());
    } else {
        assert!(reference["path"].is_string());
    }
    let runs = json["runs"].as_array().expect("runs");
    let denoised_expected = std::env::var_os("WPBGI_OIDN_LIBRARY").is_some();
    assert_eq!(
        json["denoiser_missing"].is_null(),
        denoised_expected,
        "{}",
        json["denoiser_missing"]
    );
    for run in runs {
        let method = run["method"].as_str().expect("method");
        for key in ["bake_s", "render_s", "total_s", "mse", "rel_mse", "mssim"] {
            let v = run[key].as_f64().unwrap_or(f64::NAN);
            assert!(v.is_finite() && v >= 0.0, "{method} {key} = {}", run[key]);
        }
        assert!(run["rel_mse"].as_f64().unwrap_or(0.0) > 0.0);
        assert!(run["mssim"].as_f64().unwrap_or(2.0) <= 1.0);
        // Linux reports the peak resident set.
        assert!(run["peak_memory_bytes"]
            .as_u64()
            .is_some_and(|b| b > 1_000_000));
    }
    // One cache point (one preset), then the two curves, each in the order of its samples,
    // and so of its time.
    assert_eq!(runs[0]["method"], "wpbgi");
    assert_eq!(runs[0]["preset"], "draft");
    assert_eq!(runs[0]["surfels"], 20_000);
    let curve = |method: &str| -> Vec<(u64, f64, f64)> {
        runs.iter()
            .filter(|r| r["method"] == method)
            .map(|r| {
                assert!(r["preset"].is_null());
                (
                    r["spp"].as_u64().expect("spp"),
                    r["total_s"].as_f64().expect("time"),
                    r["rel_mse"].as_f64().expect("relMSE"),
                )
            })
            .collect()
    };
    let traced = curve("path tracer");
    let denoised = curve("path tracer + OIDN");
    assert_eq!(runs.len(), 1 + traced.len() + denoised.len());
    // 1, 2, 4, … samples (the last pass shortened), the time growing with them.
    assert!(traced.len() >= 6, "{} points: {traced:?}", traced.len());
    assert_eq!(traced[0].0, 1);
    for w in traced.windows(2) {
        assert!(w[1].0 > w[0].0 && w[1].0 <= 2 * w[0].0, "samples: {w:?}");
        assert!(w[1].1 > w[0].1, "time not growing: {w:?}");
    }
    // The denoised curve: the same images, each later by its first hits and its denoise.
    if denoised_expected {
        assert_eq!(denoised.len(), traced.len());
        for (d, t) in denoised.iter().zip(&traced) {
            assert!(d.0 == t.0 && d.1 > t.1, "denoised {d:?} against {t:?}");
        }
    } else {
        assert!(denoised.is_empty());
    }
    // The raw curve ends at the cache's wall time (its last pass may run a little over).
    let cache_s = runs[0]["total_s"].as_f64().unwrap_or(0.0);
    let traced_s = traced.last().map_or(0.0, |p| p.1);
    assert!(
        traced_s >= 0.9 * cache_s,
        "path tracer {traced_s} s against the cache's {cache_s} s"
    );
    // Noise falls with the samples: the last raw point is below the first.
    assert!(
        traced.last().map(|p| p.2) < traced.first().map(|p| p.2),
        "{traced:?}"
    );
    // The curves are drawn: their colours in the SVG's strokes and among the PNG's pixels.
    let svg = std::fs::read_to_string(report.join("error_vs_time.svg")).expect("svg");
    assert!(svg.starts_with("<svg"));
    let png = image::open(report.join("error_vs_time.png"))
        .expect("png")
        .to_rgb8();
    assert_eq!(png.dimensions(), (900, 560));
    let mut colours = vec![("#1F77B4", [31u8, 119, 180]), ("#D62728", [214, 39, 40])];
    if denoised_expected {
        colours.push(("#2CA02C", [44, 160, 44]));
    }
    for (hex, rgb) in colours {
        assert!(
            svg.to_ascii_uppercase().contains(hex),
            "no {hex} curve in the SVG"
        );
        let pixels = png.pixels().filter(|p| p.0 == rgb).count();
        assert!(pixels > 20, "{pixels} pixels of {hex} in the PNG");
    }
    let summary = std::fs::read_to_string(report.join("summary.md")).expect("summary");
    assert!(summary.contains("wpbgi draft reaches relMSE"), "{summary}");
    assert!(summary.contains("The path tracer"), "{summary}");
    assert_eq!(
        summary.contains("Denoised, it"),
        denoised_expected,
        "{summary}"
    );
}

/// `wpbgi compare` of the bundled scene at 32², draft, into `out`, its reference path-traced
/// at 32 samples, with `extra`.
fn compare_bundled(out: &Path, extra: &[&str]) {
    let scene = root("scenes/cbox-rough.gltf");
    let mut args = vec!["compare", s(&scene), "-o", s(out), "--size", "32x32"];
    args.extend(["--presets", "draft", "--reference-spp", "32"]);
    // Direct-only caches: the files are what is tested here, and bounces cost CI minutes.
    args.extend(["--bounces", "0"]);
    args.extend(extra);
    wpbgi(&args);
}

#[test]
fn compare_writes_report_plot_and_summary() {
    let d = dir("report");
    // The bundled scene, its reference path-traced by compare.
    let bundled = d.join("bundled");
    compare_bundled(&bundled, &[]);
    check_report(&bundled, true);
    // cbox-glossy against Mitsuba's render.
    let reference = d.join("glossy-ref.exr");
    mitsuba_32("cbox-glossy", &reference);
    let glossy = d.join("glossy");
    wpbgi(&[
        "compare",
        s(&root("tests/data/mitsuba/cbox-glossy.gltf")),
        "--reference",
        s(&reference),
        "-o",
        s(&glossy),
        "--size",
        "32x32",
        "--presets",
        "draft",
        "--bounces",
        "0",
    ]);
    check_report(&glossy, false);
    // A reference of another size is refused before any work, in one sentence.
    let out = Command::new(WPBGI)
        .args([
            "compare",
            s(&root("tests/data/mitsuba/cbox-glossy.gltf")),
            "--reference",
            s(&reference),
            "-o",
            s(&d.join("wrong")),
            "--size",
            "16x16",
        ])
        .output()
        .expect("runs");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("is 32x32 but the render is 16x16"), "{err}");
}

#[test]
fn render_with_a_reference_stores_the_error_it_prints() {
    let d = dir("render");
    let scene = root("tests/data/mitsuba/cbox-glossy.gltf");
    let reference = d.join("ref.exr");
    mitsuba_32("cbox-glossy", &reference);
    let cache = d.join("glossy.wpc");
    wpbgi(&[
        "bake",
        s(&scene),
        "-o",
        s(&cache),
        "--points",
        "3000",
        "--light-samples",
        "16",
    ]);
    let image = d.join("frame.exr");
    let out = wpbgi(&[
        "render",
        s(&scene),
        "--cache",
        s(&cache),
        "-o",
        s(&image),
        "--size",
        "32x32",
        "--reference",
        s(&reference),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("relMSE"), "{stderr}");
    let stored: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(d.join("frame.error.json")).expect("frame.error.json"),
    )
    .expect("valid JSON");
    let (mse, rel_mse, mssim) = wpbgi::compare::errors(
        &read_exr(&image).expect("image"),
        &read_exr(&reference).expect("reference"),
    )
    .expect("same size");
    for (key, value) in [("mse", mse), ("rel_mse", rel_mse), ("mssim", mssim)] {
        let v = stored[key].as_f64().unwrap_or(f64::NAN);
        assert!(v == value, "{key}: stored {v}, recomputed {value}");
    }
}

/// `compare --frames 8` on the bundled scene: every method's frames and flicker in
/// report.json as docs/commands.md documents it. A still camera (`--orbit 0`) gives the cache a
/// temporal MSE of exactly 0 (the same cache, camera and seed give the same bytes) and the
/// path tracer, whose samples change with the frame, a positive one. Under an orbiting
/// camera every method's is positive: the references' own noise (32 samples) moves with the
/// frames and counts for all three alike, so their order is not tested here.
#[test]
fn compare_a_shot_reports_frames_and_flicker() {
    let d = dir("shot");
    let shot = |name: &str, orbit: &str| -> serde_json::Value {
        let out = d.join(name);
        compare_bundled(&out, &["--frames", "8", "--orbit", orbit]);
        for i in 1..=8 {
            assert!(out.join(format!("reference.{i:04}.exr")).exists());
        }
        let summary = std::fs::read_to_string(out.join("summary.md")).expect("summary");
        assert!(summary.contains("temporal MSE"), "{summary}");
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).expect("json"))
            .expect("valid JSON")
    };
    let denoised_expected = std::env::var_os("WPBGI_OIDN_LIBRARY").is_some();
    let check = |json: &serde_json::Value, orbit: f64| -> Vec<f64> {
        assert_eq!(json["shot"]["frames"], 8);
        assert_eq!(json["shot"]["orbit_degrees"].as_f64(), Some(orbit));
        assert_eq!(json["reference"]["spp"], 32);
        let runs = json["runs"].as_array().expect("runs");
        let methods: Vec<_> = runs.iter().map(|r| r["method"].clone()).collect();
        let mut expected = vec!["wpbgi", "path tracer"];
        if denoised_expected {
            expected.push("path tracer + OIDN");
        }
        assert_eq!(methods, expected);
        assert_eq!(runs[0]["preset"], "draft");
        for run in runs {
            let frames = run["frames"].as_array().expect("frames");
            assert_eq!(frames.len(), 8);
            for (i, f) in frames.iter().enumerate() {
                assert_eq!(f["frame"], i + 1);
                for key in ["render_s", "mse", "rel_mse"] {
                    let v = f[key].as_f64().unwrap_or(f64::NAN);
                    assert!(v.is_finite() && v >= 0.0, "{} {key} = {v}", run["method"]);
                }
                assert_eq!(f["spp"].is_null(), run["method"] == "wpbgi");
            }
            for key in ["seconds_per_frame", "mean_rel_mse", "temporal_mse"] {
                let v = run[key].as_f64().unwrap_or(f64::NAN);
                assert!(v.is_finite() && v >= 0.0, "{} {key} = {v}", run["method"]);
            }
        }
        // The path tracer renders each frame in about the cache's seconds per frame.
        let (cache_s, traced_s) = (
            runs[0]["seconds_per_frame"].as_f64().unwrap_or(0.0),
            runs[1]["seconds_per_frame"].as_f64().unwrap_or(0.0),
        );
        assert!(
            traced_s >= 0.9 * cache_s,
            "{traced_s} s against {cache_s} s"
        );
        runs.iter()
            .map(|r| r["temporal_mse"].as_f64().unwrap_or(f64::NAN))
            .collect()
    };
    let still = check(&shot("still", "0"), 0.0);
    assert_eq!(still[0], 0.0, "a still camera's cache flickers: {still:?}");
    assert!(still[1..].iter().all(|&t| t > 0.0), "{still:?}");
    let orbit = check(&shot("orbit", "20"), 20.0);
    assert!(orbit.iter().all(|&t| t > 0.0), "{orbit:?}");
}

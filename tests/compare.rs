//! `wpbgi compare` and `wpbgi render --reference` from the outside: on the bundled scene (its
//! reference path-traced by compare) and on cbox-glossy (against Mitsuba 3's render), compare
//! writes report.json as the README documents it, a plot with both curves as SVG and PNG, and
//! a summary; render stores the error it prints, equal to the error recomputed from the files.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use wpbgi::image::{read_exr, write_exr, Image};

const WPBGI: &str = env!("CARGO_BIN_EXE_wpbgi");

fn root(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("wpbgi-compare-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    d
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
    let mut img = Image::new(32, 32);
    for y in 0..32 {
        for x in 0..32 {
            let mut sum = glam::Vec3::ZERO;
            for k in 0..64 {
                sum += r.get(8 * x + k % 8, 8 * y + k / 8);
            }
            img.pixels[(y * 32 + x) as usize] = sum / 64.0;
        }
    }
    write_exr(out, &img).expect("write reference");
}

/// The report's files exist and say what the README says they do.
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
    assert_eq!(runs.len(), 2, "one preset: the cache and the path tracer");
    for (run, method) in runs.iter().zip(["wpbgi", "path tracer"]) {
        assert_eq!(run["method"], method);
        assert_eq!(run["preset"], "draft");
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
    assert_eq!(runs[0]["surfels"], 20_000);
    assert!(runs[1]["spp"].as_u64().is_some_and(|n| n >= 1));
    // The path tracer gets the cache's wall time (in passes, so it may run a little over).
    let (cache_s, traced_s) = (
        runs[0]["total_s"].as_f64().unwrap_or(0.0),
        runs[1]["total_s"].as_f64().unwrap_or(0.0),
    );
    assert!(
        traced_s >= 0.9 * cache_s,
        "path tracer {traced_s} s against the cache's {cache_s} s"
    );
    // Both curves are drawn: their colours in the SVG's strokes and among the PNG's pixels.
    let svg = std::fs::read_to_string(report.join("error_vs_time.svg")).expect("svg");
    assert!(svg.starts_with("<svg"));
    let png = image::open(report.join("error_vs_time.png"))
        .expect("png")
        .to_rgb8();
    assert_eq!(png.dimensions(), (900, 560));
    for (hex, rgb) in [("#1F77B4", [31u8, 119, 180]), ("#D62728", [214, 39, 40])] {
        assert!(
            svg.to_ascii_uppercase().contains(hex),
            "no {hex} curve in the SVG"
        );
        let pixels = png.pixels().filter(|p| p.0 == rgb).count();
        assert!(pixels > 20, "{pixels} pixels of {hex} in the PNG");
    }
    let summary = std::fs::read_to_string(report.join("summary.md")).expect("summary");
    assert!(summary.contains("wpbgi draft") && summary.contains("path tracer"));
}

#[test]
fn compare_writes_report_plot_and_summary() {
    let d = dir("report");
    // The bundled scene, its reference path-traced by compare.
    let bundled = d.join("bundled");
    wpbgi(&[
        "compare",
        s(&root("scenes/cbox-rough.gltf")),
        "-o",
        s(&bundled),
        "--size",
        "32x32",
        "--presets",
        "draft",
        "--reference-spp",
        "32",
        // Direct-only caches: the files are what is tested here, and bounces cost CI minutes.
        "--bounces",
        "0",
    ]);
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

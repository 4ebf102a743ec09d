//! `wpbgi preview` from the outside: the headless CLI, its errors, and the windowed mode under
//! Xvfb (a scripted orbit, then a screenshot read back from the swapchain that must match the
//! headless frame). CI installs Xvfb and lavapipe (scripts/test.sh); a missing one fails.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const WPBGI: &str = env!("CARGO_BIN_EXE_wpbgi");

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cbox-rough.gltf")
}

fn dir(name: &str) -> common::Scratch {
    common::Scratch::new(&format!("preview-{name}"))
}

fn run(cmd: &mut Command) -> Output {
    let out = cmd.output().expect("runs");
    assert!(
        out.status.success(),
        "{cmd:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// A small direct-only cache of the bundled scene.
fn bake(d: &Path) -> PathBuf {
    let cache = d.join("cbox.wpc");
    run(Command::new(WPBGI).args([
        "bake",
        scene().to_str().expect("utf-8"),
        "-o",
        cache.to_str().expect("utf-8"),
        "--points",
        "4000",
        "--light-samples",
        "16",
        "--bounces",
        "0",
    ]));
    cache
}

fn png(path: &Path) -> image::RgbImage {
    image::open(path).expect("a PNG").to_rgb8()
}

/// The windowed mode under Xvfb, with the validation layer: a scripted orbit of 6 frames that
/// ends where it started, then the refined frame read back from the swapchain. It shows the
/// scene (a third of its pixels or more lit) and equals the headless PNG of the same camera to
/// one 8-bit level: both are the same float frame, encoded to sRGB once by our `srgb8` and
/// once by the blit into the sRGB swapchain image, which may round the other way at a level's
/// edge (measured: at most 1 level).
#[test]
fn window_under_xvfb_matches_headless_frame() {
    let d = dir("window");
    let cache = bake(&d);
    let (headless, shot) = (d.join("headless.png"), d.join("shot.png"));
    let common = |c: &mut Command| {
        c.args([
            "preview",
            cache.to_str().expect("utf-8"),
            "--scene",
            scene().to_str().expect("utf-8"),
            "--size",
            "160x120",
        ])
        .env("WPBGI_VALIDATE", "1");
    };
    let mut c = Command::new(WPBGI);
    common(&mut c);
    let out = run(c.args(["--headless", "-o", headless.to_str().expect("utf-8")]));
    assert!(!String::from_utf8_lossy(&out.stderr).contains("validation:"));
    let mut c = Command::new("xvfb-run");
    c.args(["-a", "-s", "-screen 0 640x480x24", WPBGI]);
    common(&mut c);
    let out = run(c.args([
        "--frames",
        "6",
        "--screenshot",
        shot.to_str().expect("utf-8"),
    ]));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("validation:"), "{stderr}");
    assert!(stderr.contains("frames on"), "{stderr}");
    let (a, b) = (png(&headless), png(&shot));
    assert_eq!(a.dimensions(), b.dimensions());
    let worst = a
        .pixels()
        .zip(b.pixels())
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] as i32 - q[k] as i32).abs()))
        .max()
        .unwrap_or(0);
    let lit = b.pixels().filter(|p| p.0.iter().any(|&v| v > 8)).count();
    eprintln!("screenshot against headless: worst difference {worst} levels, {lit} lit pixels");
    assert!(worst <= 1, "the screenshot differs by {worst} levels");
    assert!(lit * 3 >= (160 * 120), "only {lit} lit pixels");
}

/// An edit typed into the window (scripted by --window-edit, through the same path as the key
/// e) shows what previewing the relit cache of the edited scene shows: the two screenshots are
/// equal byte for byte, and differ from the unedited scene's.
#[test]
fn an_edit_in_the_window_shows_the_relit_cache() {
    let d = dir("edit");
    let cache = bake(&d);
    let relit = d.join("relit.wpc");
    let edit = "light.emission*=1.5,1.2,0.8";
    let s = scene();
    let s = s.to_str().expect("utf-8");
    run(Command::new(WPBGI).args([
        "relight",
        cache.to_str().expect("utf-8"),
        "--scene",
        s,
        "-o",
        relit.to_str().expect("utf-8"),
        "--set",
        edit,
    ]));
    let shot = |name: &str, args: &[&str]| {
        let path = d.join(name);
        let mut c = Command::new("xvfb-run");
        c.args(["-a", "-s", "-screen 0 640x480x24", WPBGI, "preview"])
            .args(args)
            .args(["--scene", s, "--size", "160x120", "--frames", "4"])
            .args(["--screenshot", path.to_str().expect("utf-8")])
            .env("WPBGI_VALIDATE", "1");
        let out = run(&mut c);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!stderr.contains("validation:"), "{stderr}");
        std::fs::read(&path).expect("screenshot")
    };
    let c = cache.to_str().expect("utf-8");
    let in_window = shot("typed.png", &[c, "--window-edit", edit]);
    let relit_shot = shot(
        "relit.png",
        &[relit.to_str().expect("utf-8"), "--set", edit],
    );
    let unedited = shot("unedited.png", &[c]);
    assert!(
        in_window == relit_shot,
        "the window's edit differs from the relit cache"
    );
    assert!(in_window != unedited, "the edit changed nothing");
}

/// Headless PNG and EXR of the point-cloud view (no scene), and one-sentence errors.
#[test]
fn headless_cli_and_errors() {
    let d = dir("cli");
    let cache = bake(&d);
    let c = cache.to_str().expect("utf-8");
    for name in ["cloud.png", "cloud.exr"] {
        let out = d.join(name);
        run(Command::new(WPBGI).args([
            "preview",
            c,
            "--headless",
            "-o",
            out.to_str().expect("utf-8"),
            "--size",
            "64x48",
            "--show",
            "surfels",
        ]));
        assert!(out.metadata().expect("written").len() > 100);
    }
    let fails = |args: &[&str], says: &str| {
        let out = Command::new(WPBGI).args(args).output().expect("runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    };
    let bad = d.join("frame.tiff");
    fails(
        &[
            "preview",
            c,
            "--headless",
            "-o",
            bad.to_str().expect("utf-8"),
        ],
        "must end in .png or .exr",
    );
    fails(
        &["preview", "missing.wpc", "--headless", "-o", "x.png"],
        "missing.wpc",
    );
    fails(
        &[
            "preview",
            c,
            "--camera",
            "main",
            "--headless",
            "-o",
            "x.png",
        ],
        "needs --scene",
    );
    fails(
        &[
            "preview",
            c,
            "--cut-pixels",
            "0",
            "--headless",
            "-o",
            "x.png",
        ],
        "--cut-pixels",
    );
}

//! The path tracer against Mitsuba 3.9.1's reference renders of the same glTF scenes, by a
//! per-pixel z-test (Mitsuba's own render-regression method, `test_renders.py`).
//!
//! For each pixel and channel, z = (ours − ref) / sqrt(var_ours/N + var_ref/M), where var_ours is
//! our own per-pixel sample variance over N samples and var_ref the reference's per-sample
//! variance over its M samples. Under the hypothesis that both estimate the same expectation the
//! two-sided p-value falls below 0.01 for 1 % of pixel-channels.
//!
//! Variance: ours is floored by Mitsuba's per-sample variance of the same pixel. Both renderers
//! use the same sampling techniques (visible-normal BSDF sampling, area-uniform emitter sampling,
//! power-heuristic MIS, the same roulette), so they estimate the same per-sample variance, and
//! Mitsuba's comes from 4 096–16 384 samples where ours comes from N = 128. Without the floor,
//! pixels whose rare large samples (caustics through the glass, light-corner singularities) did
//! not occur in our N samples get both a low mean and a low variance — the known miscalibration
//! of z-tests on skewed data. Measured: the failing fraction then falls like 1/√N (cbox-glossy
//! d3: 9.1 % at 64 spp, 4.6 % at 256) with no spatial structure and image means equal to 1e-4,
//! i.e. no bias. The floor makes the test slightly conservative (measured 0.42–0.55 %).
//!
//! Bounds: at most 1.5 % fail (196 608 pixel-channels give a binomial sd of 0.02 % around 1 %, so
//! a bias confined to 2 % of the pixels already exceeds it), and the test must have power: the
//! same render scaled by 1.1 (a 10 % bias) must fail in more than 2 % of pixel-channels, twice the nominal rate (per-pixel
//! noise at 128 spp is 10–20 %, so per-pixel tests cannot see a few percent). Global biases of a
//! few tenths of a percent are caught by a second test on the image mean: |Δmean| ≤ 4 standard
//! errors (p = 6e-5), with the standard error from the same per-pixel variances.
//!
//! cbox-mirror (mirror and glass) is also held to the empirical null of the unfloored test:
//! Mitsuba's own 128-spp render fails it as often as ours (see `cbox_mirror_matches_mitsuba`).

use std::path::PathBuf;
use wpbgi::image::{read_exr, Image};
use wpbgi::reference::{render, RenderOutput, RenderSettings};
use wpbgi::scene::Scene;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/mitsuba")
        .join(name)
}

fn reference_spp(scene: &str, depth: i32) -> f64 {
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(data("manifest.json")).unwrap()).unwrap();
    m["renders"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["scene"] == scene && r["max_depth"] == depth)
        .and_then(|r| r["total_spp"].as_f64())
        .expect("manifest entry")
}

/// Render and return the fraction of pixel-channels failing the z-test at p < 0.01, for our
/// image as rendered and scaled by 1.1; checks the image mean too.
fn failing_fraction(name: &str, depth: i32, spp: u32) -> (f64, f64) {
    let ours = render_ours(name, depth, spp);
    let reference = Mitsuba::read(name, depth, reference_spp(name, depth));
    floored_z_test(&ours, &reference, &format!("{name} max_depth {depth}"))
}

/// Our path tracer's render of `name` at 256², `spp` samples, Mitsuba's `max_depth`.
fn render_ours(name: &str, depth: i32, spp: u32) -> RenderOutput {
    let scene = Scene::load(&data(&format!("{name}.gltf"))).unwrap();
    let camera = scene.default_camera(256, 256).unwrap();
    let settings = RenderSettings {
        spp,
        max_depth: depth,
        seed: 1,
        ..Default::default()
    };
    render(&scene, &camera, &settings, &|_| {}).unwrap()
}

/// Mitsuba's reference: its mean, per-sample variance and sample count.
struct Mitsuba {
    mean: Image,
    variance: Image,
    spp: f64,
}

impl Mitsuba {
    fn read(name: &str, depth: i32, spp: f64) -> Mitsuba {
        Mitsuba {
            mean: read_exr(&data(&format!("{name}_d{depth}_ref.exr"))).unwrap(),
            variance: read_exr(&data(&format!("{name}_d{depth}_var.exr"))).unwrap(),
            spp,
        }
    }
}

/// The floored z-test of the module docs: the fraction of pixel-channels failing at p < 0.01
/// for `ours` as rendered and scaled by 1.1; checks the image mean too.
fn floored_z_test(ours: &RenderOutput, reference: &Mitsuba, what: &str) -> (f64, f64) {
    let (r, rv, m) = (&reference.mean, &reference.variance, reference.spp);
    let n = ours.spp as f64;
    let (mut fail, mut fail_biased, mut total) = (0usize, 0usize, 0usize);
    let (mut mean_diff, mut mean_var) = ([0.0f64; 3], [0.0f64; 3]);
    for i in 0..r.pixels.len() {
        for c in 0..3 {
            let (a, b) = (ours.mean.pixels[i][c] as f64, r.pixels[i][c] as f64);
            // Our per-sample variance, floored by Mitsuba's estimate of the same quantity (see
            // the module docs): both estimators use the same sampling techniques, and Mitsuba's
            // variance comes from 4k–16k samples where ours comes from N.
            let per_sample = (ours.variance.pixels[i][c] as f64).max(rv.pixels[i][c] as f64);
            let var = per_sample / n + rv.pixels[i][c] as f64 / m;
            total += 1;
            let z_fails = |a: f64| {
                if var > 0.0 {
                    (a - b).abs() / var.sqrt() > 2.575_829 // two-sided p < 0.01
                } else {
                    (a - b).abs() > 1e-5 * b.abs().max(1e-6)
                }
            };
            fail += z_fails(a) as usize;
            fail_biased += z_fails(1.1 * a) as usize;
            mean_diff[c] += a - b;
            mean_var[c] += var;
        }
    }
    for c in 0..3 {
        // Mean of the per-pixel differences; pixels are independent, so variances add.
        let k = r.pixels.len() as f64;
        let z = (mean_diff[c] / k) / (mean_var[c].sqrt() / k);
        assert!(
            z.abs() <= 4.0,
            "{what}: image mean of channel {c} differs from Mitsuba's by {z:.2} standard errors"
        );
    }
    let frac = fail as f64 / total as f64;
    let biased = fail_biased as f64 / total as f64;
    eprintln!(
        "{what}: {:.3} % of pixel-channels fail at p < 0.01 ({} spp, mean {}); with a 10 % bias {:.1} %",
        100.0 * frac,
        ours.spp,
        ours.mean.mean(),
        100.0 * biased
    );
    (frac, biased)
}

fn check(name: &str) {
    for depth in [2, 3, 8] {
        let (f, biased) = failing_fraction(name, depth, 128);
        assert!(
            f <= 0.015,
            "{name} d{depth}: {:.3} % of pixel-channels fail the z-test (at most 1.5 % allowed)",
            100.0 * f
        );
        assert!(
            biased > 0.02,
            "{name} d{depth}: the test cannot see a 10 % bias ({:.2} % fail)",
            100.0 * biased
        );
    }
}

#[test]
fn cbox_diffuse_matches_mitsuba() {
    check("cbox-diffuse");
}

#[test]
fn cbox_rough_matches_mitsuba() {
    check("cbox-rough");
}

#[test]
fn cbox_glossy_matches_mitsuba() {
    check("cbox-glossy");
}

/// The fraction of pixel-channels where `image` fails the z-test with Mitsuba's per-sample
/// variance on both sides, z = (x − r) / sqrt(v_r/N + v_r/M), at p < 0.01; `scale` multiplies
/// `image` first.
fn mitsuba_variance_z_test(image: &Image, n: f64, reference: &Mitsuba, scale: f64) -> f64 {
    let (r, rv, m) = (&reference.mean, &reference.variance, reference.spp);
    let mut fail = 0usize;
    for (i, x) in image.pixels.iter().enumerate() {
        for c in 0..3 {
            let v = rv.pixels[i][c] as f64;
            let d = scale * x[c] as f64 - r.pixels[i][c] as f64;
            let var = v / n + v / m;
            fail += if var > 0.0 {
                d.abs() / var.sqrt() > 2.575_829
            } else {
                d.abs() > 1e-5 * (r.pixels[i][c] as f64).abs().max(1e-6)
            } as usize;
        }
    }
    fail as f64 / (3 * image.pixels.len()) as f64
}

/// cbox-mirror (an α = 0.001 mirror and a glass sphere; max_depth 8) against Mitsuba's
/// 4 096-spp reference (tests/data/README.md).
///
/// Issue 21 saw 4.2 % of pixel-channels fail the z-test with Mitsuba's variance on both sides
/// (no floor), nearly all bright, where 1 % is nominal, and read it as heavier firefly tails
/// than Mitsuba's. Mitsuba's own 128-spp renders fail that test as often: 4.37 % (seed 100,
/// stored in tests/data) and 4.29 % (seed 200), ours 4.22 % (4.49 % for ours and 4.43–4.59 %
/// for Mitsuba's at 256 spp). The excess is the skew of a mean of 128 samples whose
/// distribution has a long bright tail (caustics through the glass): a normal z-test does
/// not hold for it, whichever renderer draws the samples. Summed over the image our
/// per-sample variance came out 39 164 against Mitsuba's 40 403 (256 spp, its 4 096-spp
/// estimate). So ours is held to Mitsuba's own render's failing fraction under the same
/// test plus 0.5 points (the pixels' three channels fail together, so the binomial sd over
/// 65 536 pixels is 0.08 points: the margin is six of them), which a 10 % bias must exceed,
/// and to the floored test of the module docs (1.5 %; measured 0.075 %).
#[test]
fn cbox_mirror_matches_mitsuba() {
    let reference = Mitsuba::read("cbox-mirror", 8, 4096.0);
    let ours = render_ours("cbox-mirror", 8, 128);
    let n = ours.spp as f64;
    let theirs = read_exr(&data("cbox-mirror_d8_128spp_seed100.exr")).unwrap();
    let null = mitsuba_variance_z_test(&theirs, 128.0, &reference, 1.0);
    let ours_fail = mitsuba_variance_z_test(&ours.mean, n, &reference, 1.0);
    let biased = mitsuba_variance_z_test(&ours.mean, n, &reference, 1.1);
    eprintln!(
        "cbox-mirror, Mitsuba's variance on both sides: ours {:.3} % fail, Mitsuba's own \
         128 spp {:.3} %, ours with a 10 % bias {:.2} %",
        100.0 * ours_fail,
        100.0 * null,
        100.0 * biased
    );
    assert!(
        ours_fail <= null + 0.005,
        "cbox-mirror: {:.3} % fail where Mitsuba's own render fails {:.3} %",
        100.0 * ours_fail,
        100.0 * null
    );
    assert!(
        biased > null + 0.005,
        "the test cannot see a 10 % bias ({:.2} % fail)",
        100.0 * biased
    );
    let (f, biased) = floored_z_test(&ours, &reference, "cbox-mirror max_depth 8");
    assert!(
        f <= 0.015,
        "cbox-mirror: {:.3} % fail the floored z-test",
        100.0 * f
    );
    assert!(
        biased > 0.02,
        "the floored test cannot see a 10 % bias ({:.2} %)",
        100.0 * biased
    );
}

//! The bake as a whole (issue 3 acceptance): scale invariance, thread-count independence, and
//! the cache written from it read back.

mod common;

use std::path::Path;
use wpbgi::bake::store::write;
use wpbgi::bake::{bake, BakeSettings, Baked};
use wpbgi::cache::store::{bake_hash, BakedCache, NO_MAP};
use wpbgi::haar::Haar2d;
use wpbgi::scene::Scene;
use wpbgi::spectrum::Rgb;
use wpbgi::surfels::radiance::SurfelRadiance;

fn cbox() -> Scene {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/cbox-rough.gltf");
    Scene::load(&p).expect("bundled scene")
}

fn settings() -> BakeSettings {
    BakeSettings {
        points: 3000,
        light_samples: 32,
        tau: 2e-3,
        split_level: None,
        seed: 1,
        max_cut: 1000,
        bounces: wpbgi::bake::bounce::BounceSettings::exactly(0),
        surfel_density: Vec::new(),
    }
}

fn run(scene: &Scene) -> Baked {
    bake(scene, &settings(), &|_, _| {}).expect("bakes")
}

/// Every surfel's radiance as dense texels (RGB surfels as one value).
fn radiance_values(b: &Baked) -> Vec<Vec<Rgb>> {
    b.radiance
        .iter()
        .map(|r| match r {
            SurfelRadiance::Rgb(c) => vec![*c],
            SurfelRadiance::Map(m) => m.to_dense().inverse(),
        })
        .collect()
}

fn assert_radiance_close(a: &Baked, b: &Baked, factor: f32, tol: f32, what: &str) {
    assert_eq!(a.surfels.len(), b.surfels.len(), "{what}: surfel count");
    let (ra, rb) = (radiance_values(a), radiance_values(b));
    let scale = ra
        .iter()
        .flatten()
        .map(|c| c.max_element())
        .fold(0.0f32, f32::max);
    for (i, (x, y)) in ra.iter().zip(&rb).enumerate() {
        assert_eq!(x.len(), y.len(), "{what}: surfel {i} changed kind");
        for (p, q) in x.iter().zip(y) {
            assert!(
                (*p * factor - *q).abs().max_element() <= tol * scale * factor,
                "{what}: surfel {i}: {p} × {factor} vs {q}"
            );
        }
    }
}

/// Emitters × 10⁶ scale every stored radiance by 10⁶ (thresholds are relative, so the same
/// coefficients survive), to 1e-5 relative.
#[test]
fn radiance_scales_with_the_emitters() {
    let scene = cbox();
    let mut bright = cbox();
    for m in &mut bright.materials {
        if let Some(e) = &mut m.emission {
            e.radiance *= 1e6;
        }
    }
    let (a, b) = (run(&scene), run(&bright));
    assert_radiance_close(&a, &b, 1e6, 1e-5, "emitters × 1e6");
    // The coded tree keeps the same coefficients, scaled.
    assert_eq!(a.coded.stored_counts(), b.coded.stored_counts());
    let g = |x: &Baked| -> Haar2d<Rgb> { x.coded.reconstruct(&x.tree, 0).expect("root") };
    let (ga, gb) = (g(&a), g(&b));
    assert!(Haar2d::combine(&ga, 1e6, &gb, -1.0).norm() <= 1e-5 * gb.norm());
}

fn scaled(s: f32) -> Scene {
    let mut scene = cbox();
    for m in &mut scene.meshes {
        for p in &mut m.positions {
            *p *= s;
        }
    }
    for l in &mut scene.lights {
        l.position *= s;
    }
    scene
}

/// Scaling by powers of two is exact in floating point, so a bake free of absolute epsilons
/// gives bit-identical radiance at 2⁻¹⁰ (≈ 10⁻³) and 2¹³ (≈ 10⁴) times the size.
#[test]
fn radiance_is_identical_at_power_of_two_scales() {
    let reference = run(&cbox());
    for s in [2f32.powi(-10), 2f32.powi(13)] {
        let b = run(&scaled(s));
        assert!(
            radiance_values(&reference) == radiance_values(&b),
            "geometry × {s}: radiance changed"
        );
    }
}

/// At 10⁻³ and 10⁴ exactly, coordinates round differently, so Poisson elimination (a greedy
/// process) picks other surfels and their Monte Carlo samples differ. The radiance field is the
/// same: each mesh's area-weighted mean radiance agrees within 4 standard errors, the standard
/// error taken from the spread of surfel values about that mean (which also counts real
/// variation across the mesh, so the test errs towards passing, never failing by chance).
#[test]
fn radiance_field_is_independent_of_decimal_scales() {
    // Per mesh: (mean, standard error) of the red-green-blue maximum.
    let stats = |b: &Baked| -> Vec<(f64, f64)> {
        let meshes = b.surfels.iter().map(|s| s.mesh).max().unwrap_or(0) as usize + 1;
        let value = |r: &SurfelRadiance| match r {
            SurfelRadiance::Rgb(c) => c.max_element() as f64,
            // The map's mean over the sphere.
            SurfelRadiance::Map(m) => m.to_dense().scale.max_element() as f64,
        };
        (0..meshes)
            .map(|mesh| {
                let on: Vec<(f64, f64)> = b
                    .surfels
                    .iter()
                    .zip(&b.radiance)
                    .filter(|(s, _)| s.mesh as usize == mesh)
                    .map(|(s, r)| (s.area as f64, value(r)))
                    .collect();
                let area: f64 = on.iter().map(|(a, _)| a).sum();
                let mean = on.iter().map(|(a, v)| a * v).sum::<f64>() / area.max(f64::MIN_POSITIVE);
                let var = on
                    .iter()
                    .map(|(a, v)| (a * (v - mean)).powi(2))
                    .sum::<f64>();
                (mean, var.sqrt() / area.max(f64::MIN_POSITIVE))
            })
            .collect()
    };
    let reference = stats(&run(&cbox()));
    for s in [1e-3f32, 1e4] {
        let b = stats(&run(&scaled(s)));
        for (m, ((x, sx), (y, sy))) in reference.iter().zip(&b).enumerate() {
            let se = (sx * sx + sy * sy).sqrt();
            assert!(
                (x - y).abs() <= 4.0 * se + 1e-6 * x.abs(),
                "geometry × {s}, mesh {m}: mean radiance {x} vs {y} (standard error {se})"
            );
        }
    }
}

#[test]
fn cache_is_identical_for_any_thread_count_and_reads_back() {
    let scene = cbox();
    let dir = common::Scratch::new("bake");
    let hash = bake_hash(&scene, &settings().to_json());
    let mut files = Vec::new();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let baked = pool.install(|| run(&scene));
        let path = dir.join(format!("t{threads}.wpc"));
        write(&path, hash, &baked, serde_json::json!({})).expect("writes");
        files.push(std::fs::read(&path).expect("reads"));
        let c = BakedCache::read(&path, Some(hash)).expect("valid");
        assert_eq!(c.surfels.len(), baked.surfels.len());
        assert_eq!(c.nodes.len(), baked.tree.nodes.len());
        // Directional surfels point at their maps; diffuse ones carry RGB.
        let directional = baked
            .radiance
            .iter()
            .filter(|r| matches!(r, SurfelRadiance::Map(_)))
            .count();
        assert_eq!(
            c.surfels.iter().filter(|s| s.map != NO_MAP).count(),
            directional
        );
        // The root's maps decode to exactly what was coded.
        let root = c.nodes[0];
        assert_eq!(
            Some(c.map::<Rgb>(root.g).expect("I map")),
            baked.coded.nodes[0].g
        );
        assert_eq!(
            Some(c.map::<f32>(root.area_g).expect("P map")),
            baked.projected.nodes[0].g
        );
    }
    assert!(
        files[0] == files[1],
        "1 and 2 threads wrote different caches"
    );
}

/// The root's projected area P(ω) is Σ A |n·ω| over every surfel (at the 8 × 8 texel centres),
/// up to its stored map's threshold: relative L2 error ≤ τ √(dropped coefficients).
#[test]
fn root_projected_area_is_the_sum_over_surfels() {
    let b = run(&cbox());
    let p = b.projected.reconstruct(&b.tree, 0).expect("root").inverse();
    let exact: Vec<f32> = wpbgi::haar::texel_directions(3)
        .iter()
        .map(|&w| {
            b.surfels
                .iter()
                .map(|s| (s.area as f64 * s.n.dot(w).abs() as f64) as f32)
                .sum()
        })
        .collect();
    let norm = (exact.iter().map(|x| (*x as f64).powi(2)).sum::<f64>() / 64.0).sqrt();
    let err = (p
        .iter()
        .zip(&exact)
        .map(|(a, e)| ((a - e) as f64).powi(2))
        .sum::<f64>()
        / 64.0)
        .sqrt();
    let kept = b.projected.nodes[0]
        .g
        .as_ref()
        .expect("root map")
        .coefficient_count();
    let bound = settings().tau as f64 * ((64 - kept) as f64).sqrt() * norm;
    assert!(
        err <= bound + 1e-5 * norm,
        "error {err} > bound {bound} (norm {norm})"
    );
}

/// A bake stops with `Error::Cancelled` once its flag is set: at once when set before it
/// starts, and within the stage when the progress callback sets it (the plugin's cancel).
#[test]
fn a_cancelled_bake_stops_in_the_stage_that_sees_the_flag() {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Mutex;
    use wpbgi::bake::bake_cancellable;
    let scene = cbox();
    let mut s = settings();
    s.bounces = wpbgi::bake::bounce::BounceSettings::exactly(2);

    let set = AtomicBool::new(true);
    let r = bake_cancellable(&scene, &s, &|_, _| {}, &set);
    assert!(matches!(r, Err(wpbgi::Error::Cancelled)));

    for stop_at in ["surfels", "coding", "bounces"] {
        let cancel = AtomicBool::new(false);
        let seen = Mutex::new(Vec::new());
        let progress = |stage: &str, f: f32| {
            seen.lock().expect("lock").push((stage.to_string(), f));
            if stage == stop_at {
                cancel.store(true, Ordering::Relaxed);
            }
        };
        let r = bake_cancellable(&scene, &s, &progress, &cancel);
        assert!(
            matches!(r, Err(wpbgi::Error::Cancelled)),
            "stopped at {stop_at}"
        );
        // Nothing after the stage that saw the flag reported progress.
        let seen = seen.into_inner().expect("lock");
        let later = ["surfels", "direct light", "coding", "bounces"]
            .iter()
            .skip_while(|&&s| s != stop_at)
            .skip(1)
            .find(|&&s| seen.iter().any(|(x, _)| x == s));
        assert_eq!(later, None, "stopped at {stop_at}: {seen:?}");
    }
    assert_eq!(wpbgi::Error::Cancelled.to_string(), "cancelled");
}

/// A bake that cannot fit says so before any work, naming the figure: no progress is
/// reported. cbox-rough's glass (α = 0.1) needs 16² maps, so 259 transport slots per inner
/// node: 20 million surfels would need 5.2 billion, past 32-bit slots (16 519 105 points at
/// most: p·260 − 259 < 2³² − 1); 4·10⁹ surfels need more memory than a test machine has (the
/// structures alone take over a terabyte), and 10¹² are past the surfels' 32-bit numbering.
#[test]
fn a_bake_that_cannot_fit_is_refused_before_any_work() {
    use std::sync::Mutex;
    let scene = cbox();
    for (points, bounces, says) in [
        (20_000_000, 1, "bake at most about 16519105 points"),
        (
            4_000_000_000,
            0,
            "a bake of 4000000000 surfels needs at least",
        ),
        (4_000_000_000, 3, "more than 2^32"),
        // Surfels are numbered in 32 bits.
        (
            1_000_000_000_000,
            0,
            "BakeSettings.points is 1000000000000; it must be between 1 and 4294967295",
        ),
    ] {
        let s = BakeSettings {
            points,
            bounces: wpbgi::bake::bounce::BounceSettings::exactly(bounces),
            ..settings()
        };
        let seen = Mutex::new(Vec::new());
        let progress = |stage: &str, _: f32| seen.lock().expect("lock").push(stage.to_string());
        let message = match bake(&scene, &s, &progress) {
            Err(e @ wpbgi::Error::InvalidSetting(_)) => e.to_string(),
            Err(e) => panic!("{points} points, {bounces} bounces: {e}"),
            Ok(_) => panic!("{points} points, {bounces} bounces: baked"),
        };
        assert!(message.contains(says), "{message}");
        assert_eq!(seen.into_inner().expect("lock"), Vec::<String>::new());
    }
}

/// `--surfel-density`: the named material's surfaces get that many times the surfels per unit
/// area (the total unchanged), and a name no material has is refused before any work.
#[test]
fn surfel_density_refines_the_named_material() {
    let scene = cbox();
    let glass = |b: &Baked| {
        let on: Vec<_> = b
            .surfels
            .iter()
            .filter(|s| {
                scene.materials[scene.meshes[s.mesh as usize].material].name == "glass-a0.1"
            })
            .collect();
        (on.len(), on.iter().map(|s| f64::from(s.area)).sum::<f64>())
    };
    let uniform = run(&scene);
    let fine = bake(
        &scene,
        &BakeSettings {
            surfel_density: vec![("glass-a0.1".into(), 4.0)],
            ..settings()
        },
        &|_, _| {},
    )
    .expect("bakes");
    assert_eq!(fine.surfels.len(), uniform.surfels.len());
    let ((n1, a1), (n4, a4)) = (glass(&uniform), glass(&fine));
    // The sphere is a few per cent of the area: 4× its share of a fixed total is a little
    // less than 4× its count (the walls give up what it gains).
    let ratio = n4 as f64 / n1 as f64;
    assert!((3.4..4.2).contains(&ratio), "{n1} → {n4} glass surfels");
    // The same surface either way: the areas differ by the Voronoi counting's noise only.
    assert!((a4 / a1 - 1.0).abs() < 0.03, "glass area {a1} → {a4}");
    for (density, says) in [
        (
            ("no-such".to_string(), 2.0),
            "no material is named \"no-such\"",
        ),
        (("white".to_string(), 0.0), "must be a positive number"),
    ] {
        let s = BakeSettings {
            surfel_density: vec![density],
            ..settings()
        };
        let seen = std::sync::Mutex::new(Vec::new());
        let progress = |stage: &str, _: f32| seen.lock().expect("lock").push(stage.to_string());
        match bake(&scene, &s, &progress) {
            Err(e @ wpbgi::Error::InvalidSetting(_)) => {
                assert!(e.to_string().contains(says), "{e}")
            }
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("baked with {:?}", s.surfel_density),
        }
        assert_eq!(seen.into_inner().expect("lock"), Vec::<String>::new());
    }
}

/// Issue 19: the bounces record the light transport once and replay it. The cache of a
/// multi-bounce bake is byte-identical for 1 and 2 threads, and for any transport budget:
/// receivers past the budget gather again in every bounce through the same code (none kept,
/// about half kept, all kept). So is the transport kept beside it (issue 25), and a bake handed
/// a kept transport of about half the receivers replays it, gathers the rest, and writes the
/// same cache.
#[test]
fn multi_bounce_cache_is_identical_for_any_thread_count_and_transport_budget() {
    use wpbgi::bake::bake_with_transport;
    use wpbgi::bake::bounce::kept::beside;
    use wpbgi::bake::bounce::{BounceSettings, KeptTransport, TransportHandoff};
    let scene = cbox();
    let dir = common::Scratch::new("transport");
    let with_budget = |budget: Option<u64>| BakeSettings {
        bounces: BounceSettings {
            transport_budget: budget,
            ..BounceSettings::exactly(3)
        },
        ..settings()
    };
    let hash = bake_hash(&scene, &with_budget(None).to_json());
    let bake_handing = |threads: usize, budget: Option<u64>, handoff: &mut TransportHandoff| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let cancel = std::sync::atomic::AtomicBool::new(false);
        let baked = pool
            .install(|| {
                let settings = with_budget(budget);
                bake_with_transport(&scene, &settings, &|_, _| {}, &cancel, handoff)
            })
            .expect("bakes");
        let path = dir.join(format!("t{threads}-{budget:?}.wpc"));
        write(&path, hash, &baked, serde_json::json!({})).expect("writes");
        if let Some(kept) = handoff.kept.take() {
            kept.write(&beside(&path)).expect("writes the transport");
        }
        let report = baked.bounces.expect("bounces ran").transport;
        (std::fs::read(&path).expect("reads"), report)
    };
    let bake_with = |threads: usize, budget: Option<u64>| {
        let mut keep = TransportHandoff {
            keep: true,
            ..TransportHandoff::default()
        };
        bake_handing(threads, budget, &mut keep)
    };
    let transport = |threads: usize, budget: Option<u64>| {
        std::fs::read(beside(&dir.join(format!("t{threads}-{budget:?}.wpc")))).expect("reads")
    };
    let (reference, unbounded) = bake_with(1, None);
    assert_eq!(unbounded.regathered_groups, 0);
    assert_eq!(unbounded.bytes, unbounded.bytes_unbounded);
    assert!(unbounded.read_slots > 0 && unbounded.read_slots as u64 <= unbounded.slots);
    let (two_threads, _) = bake_with(2, None);
    assert!(
        reference == two_threads,
        "1 and 2 threads wrote different caches"
    );
    assert!(
        transport(1, None) == transport(2, None),
        "1 and 2 threads kept different transports"
    );
    for budget in [0, unbounded.bytes / 2] {
        let (bounded, report) = bake_with(2, Some(budget));
        assert!(
            report.bytes <= budget,
            "{report:?} over the budget {budget}"
        );
        assert!(report.regathered_groups > 0, "{report:?}");
        assert!(
            reference == bounded,
            "a transport budget of {budget} bytes changed the cache"
        );
    }
    let half = unbounded.bytes / 2;
    let path = dir.join(format!("t2-{:?}.wpc", Some(half)));
    let mut replay = TransportHandoff {
        reuse: Some(KeptTransport::read(&beside(&path)).expect("reads back")),
        ..TransportHandoff::default()
    };
    let (replayed, _) = bake_handing(1, None, &mut replay);
    assert!(replay.replayed, "refused: {:?}", replay.refused);
    assert!(
        reference == replayed,
        "replaying half the receivers' transport changed the cache"
    );
}

/// The staleness check hashes the settings the cache stores as text: every float must read
/// back as the one hashed (f32 settings such as a 3 % bounce tolerance print as long
/// decimals that a float parser which is not correctly rounded reads one ulp off).
#[test]
fn settings_hash_survives_the_caches_text() {
    let scene = cbox();
    let mut s = settings();
    for (tau, tolerance, operator_tau) in
        [(0.002, 0.03, 0.01), (0.1, 0.07, 0.003), (1e-4, 0.3, 0.2)]
    {
        s.tau = tau;
        s.bounces.tolerance = tolerance;
        s.bounces.operator_tau = operator_tau;
        let json = s.to_json();
        let text = serde_json::to_string(&json).expect("prints");
        let back: serde_json::Value = serde_json::from_str(&text).expect("parses");
        assert_eq!(
            bake_hash(&scene, &json),
            bake_hash(&scene, &back),
            "tau {tau}, tolerance {tolerance}, operator_tau {operator_tau}: {text}"
        );
    }
}

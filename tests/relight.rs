//! `wpbgi relight` (`bake::relight`): a relit cache against a fresh bake of the edited scene,
//! the refusals of edits that name nothing, and the cache's settings read back.

mod common;

use std::sync::atomic::AtomicBool;
use wpbgi::bake::bounce::kept::beside;
use wpbgi::bake::bounce::TransportHandoff;
use wpbgi::bake::relight::{relight, Relighting};
use wpbgi::bake::{bake_with_transport, BakeSettings, Quality};
use wpbgi::cache::store::BakedCache;
use wpbgi::image::error_against;
use wpbgi::scene::edit::Edit;
use wpbgi::scene::Scene;

/// A small bake with automatic bounces: what is compared is the relit cache against a bake of
/// the edited scene with these same settings, not against a reference.
fn settings() -> BakeSettings {
    BakeSettings {
        points: 6000,
        light_samples: 16,
        ..BakeSettings::preset(Quality::Draft)
    }
}

/// A fresh scratch folder for test `name`.
fn scratch(name: &str) -> common::Scratch {
    common::Scratch::new(&format!("relight-{name}"))
}

fn edits(list: &[&str]) -> Vec<Edit> {
    list.iter().map(|e| e.parse().expect("edit")).collect()
}

/// relMSE between the final renders (64², default settings) of `a` and `b`, both caches of
/// `scene`.
fn render_difference(scene: &Scene, a: &BakedCache, b: &BakedCache) -> f64 {
    let camera = scene.camera(None, 64, 64).expect("camera");
    let ra = common::final_render(scene, a, &camera);
    let rb = common::final_render(scene, b, &camera);
    error_against(&ra.beauty, &rb.beauty).expect("same size").1
}

/// Edits that multiply every emitter by one factor rescale the cache, and the result renders
/// as a fresh bake of the edited scene does. A grey factor changes no choice of the bake, so
/// only float rounding parts the two; a colour factor on cbox-glossy's one emitter also moves
/// the luminance the bounces compare and the coefficients the wavelet threshold keeps (it
/// compares the largest channel). Measured: relMSE 0 for ×2 (exact in binary), 5.1e-15 for
/// ×1.7, 2.7e-6 for the colour (9.8e-7 before the render's light points took 32-bit seeds,
/// its arctangent another rounding and its cuts far straddling nodes whole: which
/// coefficients sit at the threshold moved). The grey bounds are the maths of rounding: ×2
/// changes no bit, and ×1.7 rounds each float product once either way (half an ulp, 6e-8
/// relative), which a render carries through a few operations: a relative error of a few
/// 1e-7 per pixel, a relMSE below 1e-13. The colour's bound has no such argument: it is ten times the measured
/// figure, well inside the 1e-3.
#[test]
fn scaling_every_emitter_rescales_the_cache_as_a_fresh_bake_would_be() {
    let dir = scratch("rescale");
    for (name, edit, bound) in [
        ("cbox-rough", "light.emission*=2", 0.0),
        ("cbox-rough", "light.emission*=1.7", 1e-13),
        ("cbox-glossy", "light.emission*=1.25,1,0.75", 1e-5),
    ] {
        let original = Scene::load(&common::mitsuba_data(&format!("{name}.gltf"))).expect("scene");
        let path = |what: &str| dir.join(format!("{name}-{edit}-{what}.wpc"));
        let cache = common::bake_to_cache(&original, &settings(), &path("original"));
        // One emitter: the plan says a colour factor rescales too.
        let rescales = cache.plan["plan"]["relight"]["rescales"]
            .as_str()
            .unwrap_or_default();
        assert!(rescales.contains("grey or coloured"), "{rescales}");
        let edits = edits(&[edit]);
        let how = relit_to(&original, &cache, &edits, &path("relit"));
        assert!(
            matches!(how, Relighting::Rescaled { .. }),
            "{name}: {how:?}"
        );
        let edited = original.edited(&edits).expect("edited");
        let relit_cache =
            BakedCache::open_fresh(&edited, &path("relit")).expect("fresh for the edited scene");
        assert!(
            BakedCache::open_fresh(&original, &path("relit")).is_err(),
            "{name}: the relit cache is refused for the original scene"
        );
        let fresh = common::bake_to_cache(&edited, &settings(), &path("fresh"));
        let rel = render_difference(&edited, &relit_cache, &fresh);
        eprintln!("{name} {edit}: relMSE of the relit render against a fresh bake's {rel:.3e}");
        assert!(rel <= bound, "{name} {edit}: relMSE {rel:.3e} > {bound:e}");
    }
}

/// An edit of how light scatters bakes the edited scene again, says why, and writes what a
/// bake of the edited scene writes, byte for byte.
#[test]
fn an_edit_of_scattering_bakes_again_and_says_why() {
    let dir = scratch("rebake");
    let original = Scene::load(&common::mitsuba_data("cbox-rough.gltf")).expect("scene");
    let cache = common::bake_to_cache(&original, &settings(), &dir.join("original.wpc"));
    let edits = edits(&["white.reflectance=0.5", "gold-a0.2.alpha=0.02"]);
    let output = dir.join("relit.wpc");
    match &relit_to(&original, &cache, &edits, &output) {
        Relighting::Rebaked { why } => {
            assert!(why.contains("\"white\""), "{why}");
            // α 0.02 needs the finest maps, 64², where the cache's α 0.2 chose 16².
            assert!(
                why.contains(
                    "\"gold-a0.2\" now needs 64² directional maps where the cache has 16²"
                ),
                "{why}"
            );
        }
        other => panic!("expected a re-bake, got {other:?}"),
    }
    let edited = original.edited(&edits).expect("edited");
    assert!(
        std::fs::read(&output).expect("relit") == fresh_bake_bytes(&edited, &dir.join("fresh.wpc")),
        "the re-baked cache is the edited scene's bake"
    );
}

/// Bake `scene` keeping its transport beside the cache at `path` (what `wpbgi bake
/// --keep-transport` writes), and open the cache.
fn bake_keeping_transport(scene: &Scene, path: &std::path::Path) -> BakedCache {
    let mut handoff = TransportHandoff {
        keep: true,
        ..TransportHandoff::default()
    };
    let baked = bake_with_transport(
        scene,
        &settings(),
        &|_, _| {},
        &AtomicBool::new(false),
        &mut handoff,
    )
    .expect("bake");
    wpbgi::bake::store::save(path, scene, &baked).expect("save");
    let kept = handoff.kept.expect("the bounces hand out their transport");
    kept.write(&beside(path)).expect("write the transport");
    BakedCache::read(path, None).expect("read")
}

/// How `relight` of `cache` (a bake of `original`) with `edits` into `output` went.
fn relit_to(
    original: &Scene,
    cache: &BakedCache,
    edits: &[Edit],
    output: &std::path::Path,
) -> Relighting {
    relight(
        original,
        cache,
        edits,
        output,
        &|_, _| {},
        &AtomicBool::new(false),
    )
    .expect("relight")
    .how
}

/// The bytes of a fresh bake of `scene` with the tests' settings, written to `path`.
fn fresh_bake_bytes(scene: &Scene, path: &std::path::Path) -> Vec<u8> {
    let baked = wpbgi::bake::bake(scene, &settings(), &|_, _| {}).expect("bake");
    wpbgi::bake::store::save(path, scene, &baked).expect("save");
    std::fs::read(path).expect("fresh")
}

/// With the transport kept beside the cache, edits of a reflectance, a conductor's tint, a
/// dielectric's transmittance and a roughness within its operator's grid re-solve the bounces
/// from it instead of gathering again (every BSDF operator but an edited roughness's taken
/// from the file, and the edited diffuse surfels' irradiance, reflected again), and
/// the relit cache is a fresh bake of the edited scene byte for byte (the transport is
/// geometry; replaying it is the same arithmetic as recording it). A roughness edit that
/// changes a BSDF operator's grid, and a damaged or truncated transport file, are refused
/// with the reason, and the edited scene is baked again, byte for byte as before.
#[test]
fn a_kept_transport_re_solves_scattering_edits_as_a_fresh_bake_would() {
    let dir = scratch("transport");
    let original = Scene::load(&common::mitsuba_data("cbox-rough.gltf")).expect("scene");
    let cache = bake_keeping_transport(&original, &dir.join("original.wpc"));
    let transport = std::fs::read(beside(&dir.join("original.wpc"))).expect("transport");
    let damaged = {
        let mut bytes = transport.clone();
        let middle = bytes.len() / 2;
        bytes[middle] ^= 0x10;
        bytes
    };
    let truncated = transport[..transport.len() - 4096].to_vec();
    for (k, (edit, file, expected)) in [
        ("white.reflectance*=0.8", &transport, None),
        (
            "gold-a0.2.specular_reflectance=0.9,0.6,0.3",
            &transport,
            None,
        ),
        ("glass-a0.1.specular_transmittance=0.7", &transport, None),
        // α 0.24: the same grid, so the same transport, and the conductor's operator built
        // again (the glass's taken from the file).
        ("gold-a0.2.alpha*=1.2", &transport, None),
        // α 0.3: the operator's grid goes from 16² to 8² texels a hemisphere.
        (
            "gold-a0.2.alpha*=1.5",
            &transport,
            Some("recorded for other geometry, receivers or BSDF grids"),
        ),
        ("white.reflectance*=0.8", &damaged, Some("checksum fails")),
        ("white.reflectance*=0.8", &truncated, Some("checksum fails")),
    ]
    .into_iter()
    .enumerate()
    {
        std::fs::write(beside(&dir.join("original.wpc")), file).expect("transport");
        let edits = edits(&[edit]);
        let output = dir.join(format!("relit-{k}.wpc"));
        match (&relit_to(&original, &cache, &edits, &output), expected) {
            (
                Relighting::Resolved {
                    kept_direct,
                    kept_irradiance,
                    kept_operators,
                    ..
                },
                None,
            ) => {
                // Every operator is the kept one but a roughness edit's, built again.
                assert!(kept_operators.1 > 0, "{edit}: the scene has glossy BSDFs");
                let rebuilt = usize::from(edit.contains(".alpha"));
                assert_eq!(kept_operators.0 + rebuilt, kept_operators.1, "{edit}");
                assert!(
                    beside(&output).exists(),
                    "{edit}: the relit cache keeps the transport beside it"
                );
                // Every surfel but the edited material's keeps its direct light.
                let edited_material = &edits[0].target;
                let edited = cache
                    .surfels
                    .iter()
                    .filter(|s| {
                        let material = original.meshes[s.mesh as usize].material;
                        original.materials[material].name == *edited_material
                    })
                    .count();
                assert_eq!(kept_direct.0 + edited, kept_direct.1, "{edit}");
                assert!(edited > 0, "{edit}");
                // The white walls' irradiance is reflected again with their new reflectance;
                // the glossy materials' direct light is sampled again.
                let diffuse_edit = edited_material == "white";
                assert_eq!(
                    *kept_irradiance,
                    if diffuse_edit { edited } else { 0 },
                    "{edit}"
                );
            }
            (Relighting::Rebaked { why }, Some(reason)) => {
                assert!(
                    why.contains("was not used") && why.contains(reason),
                    "{edit}: {why}"
                )
            }
            (how, _) => panic!("{edit} ({k}): expected {expected:?}, got {how:?}"),
        }
        let edited = original.edited(&edits).expect("edited");
        assert!(
            std::fs::read(&output).expect("relit")
                == fresh_bake_bytes(&edited, &dir.join(format!("fresh-{k}.wpc"))),
            "{edit} ({k}): the relit cache is the edited scene's bake"
        );
    }
}

/// Edits chain: the relit cache keeps the transport beside it, and relighting it re-solves
/// again, every surfel whose material no edit has touched since the bake keeping its direct
/// light; the result is a fresh bake of the twice-edited scene, byte for byte.
#[test]
fn edits_chain_from_the_kept_transport() {
    let dir = scratch("chain");
    let original = Scene::load(&common::mitsuba_data("cbox-rough.gltf")).expect("scene");
    let cache = bake_keeping_transport(&original, &dir.join("original.wpc"));
    let first = edits(&["white.reflectance*=0.8"]);
    let once = original.edited(&first).expect("edited");
    let how = relit_to(&original, &cache, &first, &dir.join("once.wpc"));
    assert!(matches!(how, Relighting::Resolved { .. }), "{how:?}");
    let relit = BakedCache::open_fresh(&once, &dir.join("once.wpc")).expect("fresh");
    let second = edits(&["gold-a0.2.specular_reflectance=0.9,0.6,0.3"]);
    let twice = once.edited(&second).expect("edited");
    let surfels_of = |name: &str| {
        let material = |s: &&wpbgi::cache::store::SurfelRecord| {
            original.materials[original.meshes[s.mesh as usize].material].name == name
        };
        cache.surfels.iter().filter(material).count()
    };
    match relit_to(&once, &relit, &second, &dir.join("twice.wpc")) {
        Relighting::Resolved {
            kept_direct,
            kept_irradiance,
            ..
        } => {
            assert_eq!(
                kept_direct.0 + surfels_of("white") + surfels_of("gold-a0.2"),
                kept_direct.1
            );
            // The walls' irradiance is the bake's, reflected with the first edit's reflectance.
            assert_eq!(kept_irradiance, surfels_of("white"));
        }
        other => panic!("expected a re-solve, got {other:?}"),
    }
    assert!(
        std::fs::read(dir.join("twice.wpc")).expect("relit")
            == fresh_bake_bytes(&twice, &dir.join("fresh.wpc")),
        "the twice-relit cache is the twice-edited scene's bake"
    );
}

/// Edits that name nothing, or a parameter the target lacks, or a bad value, are refused in a
/// sentence that names them.
#[test]
fn edits_that_name_nothing_are_refused_naming_it() {
    let scene = Scene::load(&common::mitsuba_data("cbox-rough.gltf")).expect("scene");
    let refusal = |edit: &str| -> String {
        match edit.parse::<Edit>() {
            Err(e) => e.to_string(),
            Ok(e) => scene.edited(&[e]).expect_err(edit).to_string(),
        }
    };
    let cases = [
        (
            "nosuch.emission=1",
            &["\"nosuch\"", "materials: light, white"][..],
        ),
        (
            "white.alpha=0.1",
            &["diffuse material has no parameter \"alpha\"", "reflectance"],
        ),
        (
            "gold-a0.2.reflectance=1",
            &["roughconductor has no parameter \"reflectance\""],
        ),
        ("gold-a0.2.alpha=0", &["alpha must be positive"]),
        (
            "glass-a0.1.reflectance=1",
            &["roughdielectric has no parameter", "specular_transmittance"],
        ),
        ("gold-a0.2.alpha=0.1,0.2,0.3", &["alpha takes one number"]),
        ("white.reflectance=-1", &["not negative"]),
        ("white.reflectance=1,2", &["not one number or three"]),
        ("white.reflectance=nan", &["finite"]),
        ("reflectance=1", &["names no parameter"]),
        ("white.reflectance", &["expected NAME.PARAMETER=VALUE"]),
    ];
    for (edit, expected) in cases {
        let message = refusal(edit);
        assert!(
            message.contains(edit),
            "{edit}: the message names the edit: {message}"
        );
        for e in expected {
            assert!(message.contains(e), "{edit}: {message} (expected \"{e}\")");
        }
    }
}

/// A cache's settings read back are the settings it was baked with (the re-bake's).
#[test]
fn bake_settings_survive_the_cache_json() {
    let mut all: Vec<BakeSettings> = Quality::ALL
        .iter()
        .map(|&q| BakeSettings::preset(q))
        .collect();
    all.push(BakeSettings {
        split_level: Some(7),
        seed: u64::MAX,
        surfel_density: vec![("glass".into(), 2.5)],
        ..BakeSettings::default().direct_only()
    });
    for s in all {
        assert_eq!(BakeSettings::from_json(&s.to_json()), Ok(s.clone()));
    }
    let mut broken = BakeSettings::default().to_json();
    broken["bounces"]["view_tree"] = serde_json::json!(3);
    assert_eq!(
        BakeSettings::from_json(&broken),
        Err("\"view_tree\" is not true or false".to_string())
    );
}

/// The command: a relit cache that `render --set` with the same edits accepts and a render
/// of the original scene refuses, and an edit that names nothing refused in one sentence
/// with a non-zero exit.
#[test]
fn the_command_relights_and_refuses() {
    let dir = scratch("command");
    let scene_path = common::mitsuba_data("cbox-rough.gltf");
    let original = Scene::load(&scene_path).expect("scene");
    let cache = dir.join("original.wpc");
    common::bake_to_cache(&original, &settings(), &cache);
    let relit = dir.join("relit.wpc");
    let wpbgi = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_wpbgi"))
            .args(args)
            .output()
            .expect("wpbgi")
    };
    let (scene, cache, relit) = (
        scene_path.to_str().expect("path"),
        cache.to_str().expect("path"),
        relit.to_str().expect("path"),
    );
    let edit = "light.emission*=0.5";
    let ok = wpbgi(&[
        "relight", cache, "--scene", scene, "-o", relit, "--set", edit, "--json",
    ]);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&ok.stdout).expect("json");
    assert_eq!(report["how"], "rescaled");
    // A rescale runs no bounce.
    assert!(report["bounces"].is_null(), "{report}");
    // The stages' seconds are the run's, within its total.
    let stages = report["stage_seconds"].as_object().expect("stage_seconds");
    assert_eq!(
        stages.keys().collect::<Vec<_>>(),
        ["rescale and write"],
        "{report}"
    );
    let total = report["seconds"].as_f64().expect("seconds");
    let stage_sum: f64 = stages.values().map(|v| v.as_f64().expect("a number")).sum();
    assert!(
        stage_sum > 0.0 && stage_sum <= total,
        "stages {stage_sum} s of {total} s"
    );
    let image = dir.join("frame.exr");
    let image = image.to_str().expect("path");
    let render = |edits: &[&str]| {
        let mut args = vec![
            "render", scene, "--cache", relit, "--size", "16x16", "-o", image,
        ];
        for e in edits {
            args.extend(["--set", e]);
        }
        wpbgi(&args)
    };
    let edited = render(&[edit]);
    assert!(
        edited.status.success(),
        "{}",
        String::from_utf8_lossy(&edited.stderr)
    );
    let stale = render(&[]);
    assert_eq!(stale.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&stale.stderr).contains("stale"));
    let bad = wpbgi(&[
        "relight",
        cache,
        "--scene",
        scene,
        "-o",
        relit,
        "--set",
        "lamp.emission*=0.5",
    ]);
    assert_eq!(
        bad.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&bad.stderr)
    );
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("\"lamp\"") && err.lines().count() == 1,
        "{err}"
    );
}

/// Light and emission edits together: cbox-rough with a point light added beside its area
/// light. Both doubled rescale the cache, which renders as a fresh bake of the edited scene
/// does (measured: relMSE 0, ×2 being exact in binary); the point light alone doubled
/// changes the emitters by different factors and bakes again.
#[test]
fn every_light_doubled_rescales_and_one_alone_bakes_again() {
    let dir = scratch("lights");
    let mut original = Scene::load(&common::mitsuba_data("cbox-rough.gltf")).expect("scene");
    original.lights.push(wpbgi::scene::PunctualLight {
        name: "lamp".into(),
        kind: wpbgi::scene::LightKind::Point,
        position: glam::Vec3::new(0.3, 0.5, 0.2),
        direction: -glam::Vec3::Z,
        intensity: wpbgi::spectrum::Rgb::new(0.3, 0.25, 0.2),
    });
    let cache = common::bake_to_cache(&original, &settings(), &dir.join("original.wpc"));
    let run = |list: &[&str], output: &str| {
        let edits = edits(list);
        let how = relit_to(&original, &cache, &edits, &dir.join(output));
        (how, original.edited(&edits).expect("edited"))
    };
    let (how, edited) = run(&["light.emission*=2", "lamp.intensity*=2"], "both.wpc");
    assert_eq!(
        how,
        Relighting::Rescaled {
            factor: wpbgi::spectrum::Rgb::splat(2.0)
        }
    );
    let relit = BakedCache::open_fresh(&edited, &dir.join("both.wpc")).expect("fresh");
    let fresh = common::bake_to_cache(&edited, &settings(), &dir.join("fresh.wpc"));
    let rel = render_difference(&edited, &relit, &fresh);
    eprintln!("cbox-rough with a point light, every emitter ×2: relMSE {rel:.3e}");
    assert!(rel == 0.0, "relMSE {rel:.3e}");
    match run(&["lamp.intensity*=2"], "lamp.wpc").0 {
        Relighting::Rebaked { why } => assert!(why.contains("different factors"), "{why}"),
        other => panic!("expected a re-bake, got {other:?}"),
    }
    // Two emitter colours: a grey factor only, as the plan says, and a colour factor bakes
    // again.
    let rescales = cache.plan["plan"]["relight"]["rescales"]
        .as_str()
        .unwrap_or_default();
    assert!(rescales.contains("one grey factor"), "{rescales}");
    match run(
        &["light.emission*=1,1,2", "lamp.intensity*=1,1,2"],
        "blue.wpc",
    )
    .0
    {
        Relighting::Rebaked { why } => assert!(why.contains("recolour"), "{why}"),
        other => panic!("expected a re-bake, got {other:?}"),
    }
}

/// A bake handed a cache's projected-area coding takes it only where the geometry hash is its
/// own and the tree has as many nodes; otherwise it codes the area itself. (The relit caches
/// above are byte for byte the fresh bakes, which cannot tell the two apart: here the coding
/// handed in is deliberately not the one the bake would make, so taking it shows.)
#[test]
fn a_kept_projected_coding_is_taken_only_for_its_geometry() {
    use wpbgi::bake::bounce::KeptProjected;
    use wpbgi::surfels::coding::NodeCoding;
    let scene = Scene::load(&common::mitsuba_data("cbox-rough.gltf")).expect("scene");
    let mut settings = settings();
    settings.bounces.max = 0;
    let bake = |projected: Option<KeptProjected>| {
        let mut handoff = TransportHandoff {
            projected,
            ..TransportHandoff::default()
        };
        let baked = bake_with_transport(
            &scene,
            &settings,
            &|_, _| {},
            &AtomicBool::new(false),
            &mut handoff,
        )
        .expect("bake");
        baked.projected
    };
    let own = bake(None);
    assert!(own.nodes.iter().any(|n| n.g.is_some() || n.h.is_some()));
    let geometry = wpbgi::cache::store::geometry_hash(&scene, &settings.to_json());
    let empty = |nodes: usize| KeptProjected {
        geometry,
        nodes: vec![NodeCoding::default(); nodes],
    };
    let taken = bake(Some(empty(own.nodes.len())));
    assert!(taken.nodes.iter().all(|n| n.g.is_none() && n.h.is_none()));
    assert_eq!(taken.split_level, own.split_level);
    let other_geometry = KeptProjected {
        geometry: [0; 16],
        ..empty(own.nodes.len())
    };
    assert_eq!(
        bake(Some(other_geometry)),
        own,
        "another geometry's coding is not taken"
    );
    assert_eq!(
        bake(Some(empty(own.nodes.len() + 1))),
        own,
        "nor one of another tree"
    );
}

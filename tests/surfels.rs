//! Poisson-disk surfels: counts, areas, blue-noise spacing, thin walls and determinism.

mod common;

use glam::Vec3;
use wpbgi::scene::{Mesh, Scene};
use wpbgi::surfels::{sample_surfels, sample_surfels_with_density, Surfel};

/// A square of side `s` in the plane z = `z`, facing +z (or −z when `up` is false).
fn square(s: f32, offset: Vec3, up: bool) -> Mesh {
    let p = vec![
        offset,
        offset + Vec3::new(s, 0.0, 0.0),
        offset + Vec3::new(s, s, 0.0),
        offset + Vec3::new(0.0, s, 0.0),
    ];
    let triangles = if up {
        vec![[0, 1, 2], [0, 2, 3]]
    } else {
        vec![[0, 2, 1], [0, 3, 2]]
    };
    Mesh {
        name: "square".into(),
        positions: p,
        normals: None,
        uvs: None,
        triangles,
        material: 0,
    }
}

fn scene(meshes: Vec<Mesh>) -> Scene {
    common::grey_scene(meshes)
}

fn nearest_neighbour_distances(s: &[Surfel]) -> Vec<f32> {
    s.iter()
        .enumerate()
        .map(|(i, a)| {
            s.iter()
                .enumerate()
                .filter(|(j, b)| *j != i && a.n.dot(b.n) > 0.0)
                .map(|(_, b)| a.p.distance(b.p))
                .fold(f32::INFINITY, f32::min)
        })
        .collect()
}

#[test]
fn count_and_areas_are_exact() {
    let sc = scene(vec![
        square(1.0, Vec3::ZERO, true),
        square(2.0, Vec3::new(3.0, 0.0, 0.0), true),
    ]);
    let s = sample_surfels(&sc, 2000, 1);
    assert_eq!(s.len(), 2000);
    let total: f64 = s.iter().map(|x| x.area as f64).sum();
    assert!(
        (total - 5.0).abs() < 1e-4 * 5.0,
        "areas sum to {total}, surface is 5"
    );
    // Uniform density: the 4× larger square holds about 4× the surfels and 4× the area.
    let on_big: Vec<&Surfel> = s.iter().filter(|x| x.mesh == 1).collect();
    let frac = on_big.len() as f64 / s.len() as f64;
    assert!(
        (frac - 0.8).abs() < 0.02,
        "{frac} of the surfels on 80 % of the area"
    );
    let big_area: f64 = on_big.iter().map(|x| x.area as f64).sum();
    assert!(
        (big_area - 4.0).abs() < 0.05 * 4.0,
        "big square credited {big_area}"
    );
}

/// A mesh of density 4 gets 4× the surfels per unit area, each standing for a quarter of the
/// area, with the spacing of its own density; the areas still sum to each mesh's surface.
#[test]
fn density_weights_follow_the_mesh() {
    let sc = scene(vec![
        square(1.0, Vec3::ZERO, true),
        square(1.0, Vec3::new(3.0, 0.0, 0.0), true),
    ]);
    let n = 2000;
    let s = sample_surfels_with_density(&sc, n, 5, &[1.0, 4.0]);
    assert_eq!(s.len(), n);
    let on = |m: u32| s.iter().filter(move |x| x.mesh == m);
    let frac = on(1).count() as f64 / n as f64;
    // Candidates split 1 : 4 by weighted area (binomial, σ = √(0.16 / 10 000) = 0.004 of the
    // 10 000 candidates); elimination keeps the ratio to within its edge effects.
    assert!(
        (frac - 0.8).abs() < 0.02,
        "{frac} of the surfels on the dense square"
    );
    for m in 0..2 {
        let area: f64 = on(m).map(|x| x.area as f64).sum();
        assert!((area - 1.0).abs() < 0.02, "square {m} credited {area}");
    }
    // Each square is Poisson at its own radius: r_max of N_eff = n surfels over the weighted
    // area 1 + 4 = 5, and half that on the dense square.
    let r_max = (5.0 / (2.0 * 3f32.sqrt() * n as f32)).sqrt();
    for (m, r) in [(0u32, r_max), (1, r_max / 2.0)] {
        let own: Vec<Surfel> = on(m).copied().collect();
        let d = nearest_neighbour_distances(&own);
        let mean = d.iter().sum::<f32>() / d.len() as f32 / (2.0 * r);
        // As spacing_is_poisson_disk: about 0.76 of 2r at uniform density.
        assert!(
            (0.65..0.85).contains(&mean),
            "square {m}: mean spacing {mean}"
        );
    }
    // Density 1 everywhere is the uniform sampler, bit for bit.
    assert_eq!(
        sample_surfels_with_density(&sc, 500, 6, &[1.0, 1.0]),
        sample_surfels(&sc, 500, 6)
    );
}

/// Blue noise: after elimination no two surfels are much closer than the packing radius, unlike
/// independent uniform points (whose nearest pairs come arbitrarily close).
#[test]
fn spacing_is_poisson_disk() {
    let n = 2000;
    let sc = scene(vec![square(1.0, Vec3::ZERO, true)]);
    let s = sample_surfels(&sc, n, 2);
    let r_max = (1.0 / (2.0 * 3f32.sqrt() * n as f32)).sqrt();
    let d = nearest_neighbour_distances(&s);
    let min = d.iter().copied().fold(f32::INFINITY, f32::min) / (2.0 * r_max);
    let mean = d.iter().sum::<f32>() / d.len() as f32 / (2.0 * r_max);
    eprintln!("nearest-neighbour distance / 2r_max: min {min:.3}, mean {mean:.3}");
    // Measured: min 0.64, mean 0.76 (Yuksel reports about 0.75 for 5× candidates). For 2000
    // independent uniform points the expected minimum is about 0.02 and the mean 0.46 in these
    // units (0.5/√N over 2r_max), so these bounds separate the two by a wide margin.
    assert!(min > 0.5 && mean > 0.65, "min {min}, mean {mean}");
}

/// The two faces of a zero-thickness wall keep their own surfels and areas.
#[test]
fn thin_walls_keep_both_sides() {
    let sc = scene(vec![
        square(1.0, Vec3::ZERO, true),
        square(1.0, Vec3::ZERO, false),
    ]);
    let s = sample_surfels(&sc, 1000, 3);
    let up: Vec<&Surfel> = s.iter().filter(|x| x.n.z > 0.0).collect();
    let frac = up.len() as f64 / s.len() as f64;
    assert!((frac - 0.5).abs() < 0.03, "{frac} of the surfels face up");
    let area_up: f64 = up.iter().map(|x| x.area as f64).sum();
    assert!(
        (area_up - 1.0).abs() < 0.05,
        "upper face credited {area_up}"
    );
    let d = nearest_neighbour_distances(&s);
    let r_max = (2.0 / (2.0 * 3f32.sqrt() * 1000.0)).sqrt();
    assert!(
        d.iter().all(|&x| x > r_max),
        "each side is Poisson on its own"
    );
}

#[test]
fn independent_of_thread_count() {
    let sc = scene(vec![
        square(1.0, Vec3::ZERO, true),
        square(0.5, Vec3::new(0.0, 0.0, 1.0), false),
    ]);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| sample_surfels(&sc, 3000, 4))
    };
    assert_eq!(run(1), run(2));
}

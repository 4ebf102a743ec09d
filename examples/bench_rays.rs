//! Ray-tracing throughput on a procedural ~1M-triangle scene: closest-hit and occlusion, for
//! coherent (camera) and incoherent (diffuse bounce) rays, on one thread and on all.
//!
//! `cargo run --release --example bench_rays [-- --triangles N]`
//!
//! The scene: 121 closed spheres (subdivided octahedra, 8192 triangles each) over a 60 000-triangle
//! floor, about 1.05M triangles. Incoherent rays leave the first hits of the camera rays in
//! cosine-distributed directions, like a path tracer's second bounce; occlusion queries use the
//! same rays (any hit ends them). "obvhs alone" is obvhs's own traversal and (non-watertight)
//! triangle test on the same rays, to compare with the figures its authors publish.

#[path = "../tests/common/mod.rs"]
mod common;

use glam::{Vec2, Vec3, Vec3A};
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use rayon::prelude::*;
use std::time::Duration;
use std::time::Instant;
use wpbgi::accel::Accel;
use wpbgi::geometry::frame::Frame;
use wpbgi::geometry::warp::square_to_cosine_hemisphere;
use wpbgi::sampler::Sampler;
use wpbgi::scene::{Camera, Mesh, Scene};

fn sphere(center: Vec3, radius: f32, levels: u32) -> Mesh {
    let mut m = common::closed_sphere(levels);
    for p in &mut m.positions {
        *p = center + *p * radius;
    }
    m
}

fn floor(n: u32, half: f32) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (i as f32 / n as f32, j as f32 / n as f32);
            let y = 0.05 * ((x * 40.0).sin() + (z * 37.0).cos());
            positions.push(Vec3::new((2.0 * x - 1.0) * half, y, (2.0 * z - 1.0) * half));
        }
    }
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            triangles.push([v, v + n + 1, v + 1]);
            triangles.push([v + 1, v + n + 1, v + n + 2]);
        }
    }
    Mesh {
        name: "floor".into(),
        positions,
        normals: None,
        uvs: None,
        triangles,
        material: 0,
    }
}

fn scene() -> Scene {
    let mut meshes = vec![floor(173, 12.0)];
    for j in 0..11 {
        for i in 0..11 {
            let c = Vec3::new(
                i as f32 * 2.2 - 11.0,
                1.0 + 0.3 * ((i * j) % 3) as f32,
                j as f32 * 2.2 - 11.0,
            );
            meshes.push(sphere(c, 0.9, 5));
        }
    }
    common::grey_scene(meshes)
}

/// One ray query: true when the ray hit something.
type RayQuery<'a> = dyn Fn(Vec3, Vec3) -> bool + Sync + 'a;

struct RaySet {
    origins: Vec<Vec3>,
    dirs: Vec<Vec3>,
}

/// Mrays/s of `f` over every ray, on the current rayon pool, best of three runs.
fn measure(rays: &RaySet, f: &RayQuery<'_>) -> (f64, f64) {
    let mut best = f64::INFINITY;
    let mut hits = 0;
    for _ in 0..3 {
        let t = Instant::now();
        hits = rays
            .origins
            .par_iter()
            .zip(&rays.dirs)
            .with_min_len(1024)
            .filter(|(o, d)| f(**o, **d))
            .count();
        best = best.min(t.elapsed().as_secs_f64());
    }
    (
        rays.origins.len() as f64 / best / 1e6,
        hits as f64 / rays.origins.len() as f64,
    )
}

fn main() -> anyhow::Result<()> {
    let scene = scene();
    let t = Instant::now();
    let accel = Accel::build(&scene);
    let build = t.elapsed().as_secs_f64();
    let (lo, hi) = scene.bounds();
    let diag = (hi - lo).length();
    println!(
        "scene: {} triangles, BVH build {:.2} s on {} threads",
        accel.len(),
        build,
        rayon::current_num_threads()
    );

    // Coherent: a 1024² pinhole camera looking over the spheres.
    let cam = Camera::look_at(
        "bench",
        Vec3::new(0.0, 9.0, 17.0),
        Vec3::new(0.0, 0.0, -1.0),
        0.9,
        1024,
        1024,
    )
    .ok_or_else(|| anyhow::anyhow!("degenerate benchmark camera"))?;
    let mut coherent = RaySet {
        origins: Vec::new(),
        dirs: Vec::new(),
    };
    for y in 0..1024 {
        for x in 0..1024 {
            let (o, d) = cam.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            coherent.origins.push(o);
            coherent.dirs.push(d);
        }
    }
    // Incoherent: cosine-distributed bounces from the camera rays' hits.
    let mut incoherent = RaySet {
        origins: Vec::new(),
        dirs: Vec::new(),
    };
    for (i, (o, d)) in coherent.origins.iter().zip(&coherent.dirs).enumerate() {
        let Some(h) = accel.closest_hit(*o, *d, 0.0, f32::INFINITY) else {
            continue;
        };
        let m = &scene.meshes[h.mesh as usize];
        let tri = m.triangles[h.triangle as usize].map(|k| m.positions[k as usize]);
        let mut n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
        if n.dot(*d) > 0.0 {
            n = -n;
        }
        let p = *o + *d * h.t + n * (1e-4 * diag);
        let mut s = Sampler::new(1, i as u64, 0);
        incoherent.origins.push(p);
        incoherent
            .dirs
            .push(Frame::from_normal(n).to_world(square_to_cosine_hemisphere(s.next_2d())));
    }

    // obvhs on its own: same scene and rays, its Möller–Trumbore test (not watertight), its
    // unpadded boxes, unit directions: the figure its authors quote, for comparison.
    let tris: Vec<Triangle> = scene
        .meshes
        .iter()
        .flat_map(|m| {
            m.triangles.iter().map(|t| {
                let p = |i: u32| Vec3A::from(m.positions[i as usize]);
                Triangle {
                    v0: p(t[0]),
                    v1: p(t[1]),
                    v2: p(t[2]),
                }
            })
        })
        .collect();
    let native = build_cwbvh_from_tris(
        &tris,
        BvhBuildParams::medium_build(),
        &mut Duration::default(),
    );
    let native_closest = |o: Vec3, d: Vec3| {
        let ray = Ray::new(o.into(), d.normalize().into(), 0.0, f32::INFINITY);
        let mut hit = RayHit::none();
        native.ray_traverse(ray, &mut hit, |r, i| {
            tris[native.primitive_indices[i] as usize].intersect(r)
        })
    };

    let threads = rayon::current_num_threads();
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    println!(
        "{:<38} {:>14} {:>14} {:>9}",
        "rays",
        "Mrays/s 1 thr",
        format!("Mrays/s {threads} thr"),
        "hit rate"
    );
    for (name, rays) in [("coherent", &coherent), ("incoherent", &incoherent)] {
        let closest = |o: Vec3, d: Vec3| accel.closest_hit(o, d, 0.0, f32::INFINITY).is_some();
        let shadow = |o: Vec3, d: Vec3| accel.occluded(o, d, 0.0, f32::INFINITY);
        let queries: [(&str, &RayQuery<'_>); 3] = [
            ("closest hit", &closest),
            ("occlusion", &shadow),
            ("closest hit, obvhs alone", &native_closest),
        ];
        for (kind, f) in queries {
            let (single, _) = one.install(|| measure(rays, f));
            let (all, rate) = measure(rays, f);
            println!(
                "{:<38} {:>14.2} {:>14.2} {:>8.1}%",
                format!("{name} {kind}"),
                single,
                all,
                rate * 100.0
            );
        }
    }
    Ok(())
}

//! Where a cache's light is wrong, by where it comes from: the light arriving at one mesh's
//! surfels, split by the mesh it leaves, read from the cache where cosine-distributed rays
//! land (as `render --gather paths` reads it) against the path tracer's radiance along the
//! same rays (max_depth 64). A source whose ratio is off holds the cache's error; if every
//! source is right but the mesh's own cached light is not, the bake's gather there is.
//!
//! ```sh
//! cargo run --release --example light_by_source -- SCENE CACHE MESH [RAYS [STRIDE [BOX]]]
//! ```
//!
//! RAYS per surfel (default 1024), every STRIDE-th surfel of MESH (default 4), only those
//! inside BOX = `xmin,xmax,ymin,ymax,zmin,zmax` (world space; default everywhere). Emission
//! is not in the cache (the render lights it directly), so an emitter's row reads near zero.

use anyhow::{bail, Context, Result};
use glam::Vec3;
use rayon::prelude::*;
use std::path::Path;
use wpbgi::gather::Senders;
use wpbgi::geometry::frame::Frame;
use wpbgi::geometry::warp::square_to_cosine_hemisphere;
use wpbgi::reference::{radiance, RenderSettings};
use wpbgi::sampler::Sampler;
use wpbgi::scene::Scene;
use wpbgi::spectrum::luminance;
use wpbgi::trace::{intersect_geometry_within, Tracer};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        bail!("usage: light_by_source SCENE CACHE MESH [RAYS [STRIDE [xmin,xmax,ymin,ymax,zmin,zmax]]]");
    }
    let scene = Scene::load(Path::new(&args[0]))?;
    let cache = wpbgi::Cache::read(Path::new(&args[1]), None)?;
    let mesh = scene
        .meshes
        .iter()
        .position(|m| m.name == args[2])
        .with_context(|| format!("{} has no mesh named {}", args[0], args[2]))?
        as u32;
    let rays: u32 = args
        .get(3)
        .map_or(Ok(1024), |s| s.parse())
        .context("RAYS")?;
    let stride: usize = args.get(4).map_or(Ok(4), |s| s.parse()).context("STRIDE")?;
    let bounds: Vec<f32> = match args.get(5) {
        Some(s) => s
            .split(',')
            .map(str::parse)
            .collect::<Result<_, _>>()
            .context("BOX")?,
        None => vec![f32::MIN, f32::MAX, f32::MIN, f32::MAX, f32::MIN, f32::MAX],
    };
    if bounds.len() != 6 || stride == 0 || rays == 0 {
        bail!("BOX takes six numbers, RAYS and STRIDE at least 1");
    }
    let inside = |p: [f32; 3]| (0..3).all(|a| p[a] >= bounds[2 * a] && p[a] <= bounds[2 * a + 1]);
    let senders = Senders::from_cache(&cache)?;
    let settings = RenderSettings {
        max_depth: 64,
        ..Default::default()
    };
    let ctx = settings.context(&scene);
    let tracer = Tracer::new(&scene);
    let picked: Vec<usize> = (cache.surfels.iter().enumerate())
        .filter(|(_, s)| s.mesh == mesh && inside(s.p))
        .map(|(i, _)| i)
        .step_by(stride)
        .collect();
    let meshes = scene.meshes.len();
    // Per source mesh, area-weighted sums of the cache's and the path tracer's luminance.
    let per_surfel: Vec<Vec<[f64; 2]>> = picked
        .par_iter()
        .map(|&i| {
            let s = &cache.surfels[i];
            let n = Vec3::from(s.n);
            let p = Vec3::from(s.p) + n * 1e-4;
            let frame = Frame::from_normal(n);
            let mut sampler = Sampler::new(11, i as u64, 0);
            let mut sums = vec![[0.0f64; 2]; meshes];
            for _ in 0..rays {
                let w = frame.to_world(square_to_cosine_hemisphere(sampler.next_2d()));
                let Some(hit) = intersect_geometry_within(&tracer, p, w, f32::INFINITY) else {
                    continue;
                };
                let cached = senders
                    .lookup_at(hit.p, hit.hit.mesh, hit.ng, -w, mesh)
                    .map_or(Vec3::ZERO, |l| senders.radiance_of(l));
                let traced = radiance(&ctx, p, w, &mut sampler);
                let sum = &mut sums[hit.hit.mesh as usize];
                sum[0] += f64::from(luminance(cached) * s.area);
                sum[1] += f64::from(luminance(traced) * s.area);
            }
            sums
        })
        .collect();
    let mut sums = vec![[0.0f64; 2]; meshes];
    for surfel in per_surfel {
        for (total, s) in sums.iter_mut().zip(surfel) {
            total[0] += s[0];
            total[1] += s[1];
        }
    }
    let traced_total: f64 = sums.iter().map(|s| s[1]).sum();
    println!(
        "{} surfels of {}, {rays} rays each: the light arriving from each mesh, as shares of the path tracer's total",
        picked.len(),
        args[2]
    );
    for (k, s) in sums.iter().enumerate().filter(|(_, s)| s[1] > 0.0) {
        println!(
            "{:>16}: cache {:.4}, path tracer {:.4}, ratio {:.4}",
            scene.meshes[k].name,
            s[0] / traced_total,
            s[1] / traced_total,
            s[0] / s[1]
        );
    }
    Ok(())
}

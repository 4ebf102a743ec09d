//! Each object's mean luminance in an image against a reference's, the way
//! tests/indirect_light.rs holds them: the mesh that each pixel's centre ray hits first names
//! the pixel's region (the scene's default camera at the image's size).
//!
//! ```sh
//! cargo run --release --example region_means -- SCENE IMAGE.exr REFERENCE.exr
//! ```

use anyhow::{bail, Result};
use glam::Vec2;
use std::collections::BTreeMap;
use std::path::Path;
use wpbgi::image::read_exr;
use wpbgi::scene::Scene;
use wpbgi::spectrum::luminance;
use wpbgi::trace::{intersect, Tracer};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, image, reference] = args.as_slice() else {
        bail!("usage: region_means SCENE IMAGE.exr REFERENCE.exr");
    };
    let scene = Scene::load(Path::new(scene))?;
    let (image, reference) = (read_exr(Path::new(image))?, read_exr(Path::new(reference))?);
    if (image.width, image.height) != (reference.width, reference.height) {
        bail!("the image and the reference differ in size");
    }
    let camera = scene.default_camera(image.width, image.height)?;
    let tracer = Tracer::new(&scene);
    // Per region: the image's and the reference's luminance sums, and the pixel count.
    let mut regions: BTreeMap<String, (f64, f64, usize)> = BTreeMap::new();
    for y in 0..camera.height {
        for x in 0..camera.width {
            let (o, d) = camera.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let name = intersect(&tracer, o, d).map_or(String::from("(nothing)"), |h| {
                scene.meshes[h.mesh as usize].name.clone()
            });
            let k = (y * camera.width + x) as usize;
            let region = regions.entry(name).or_default();
            region.0 += f64::from(luminance(image.pixels[k]));
            region.1 += f64::from(luminance(reference.pixels[k]));
            region.2 += 1;
        }
    }
    for (name, (ours, theirs, count)) in regions {
        let n = count as f64;
        let ratio = if theirs > 0.0 { ours / theirs } else { 1.0 };
        println!(
            "{name:>16} {count:7} px  mean {:.5}, reference {:.5}, ratio {ratio:.4}",
            ours / n,
            theirs / n
        );
    }
    Ok(())
}

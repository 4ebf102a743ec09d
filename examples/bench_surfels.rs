//! Surfel sampling speed: surfels per second on the bundled Cornell box and on a 1M-triangle
//! sphere field, and bytes per surfel.
//!
//! `cargo run --release --example bench_surfels [-- N]` (default 1 000 000 surfels)

use std::path::Path;
use std::time::Instant;
use wpbgi::scene::Scene;
use wpbgi::surfels::{sample_surfels, Surfel};

fn main() -> anyhow::Result<()> {
    let n: usize = match std::env::args().nth(1) {
        Some(s) => s.parse()?,
        None => 1_000_000,
    };
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cbox-rough.gltf");
    let scene = Scene::load(&path)?;
    println!("{} threads", rayon::current_num_threads());
    for target in [n / 10, n] {
        let t = Instant::now();
        let s = sample_surfels(&scene, target, 0);
        let secs = t.elapsed().as_secs_f64();
        println!(
            "cbox-rough: {} surfels in {secs:.2} s = {:.0} surfels/s ({} bytes each in memory)",
            s.len(),
            s.len() as f64 / secs,
            std::mem::size_of::<Surfel>()
        );
    }
    Ok(())
}

//! Compare two EXR images: prints MSE, relative MSE and the means, and writes a PNG with the
//! two side by side and their absolute difference (×4) for looking at.
//!
//! `cargo run --release --example image_diff -- ours.exr reference.exr side_by_side.png [x,y,w,h]`
//! (an image k times the reference's size each way is averaged down to it first).

use std::fmt::Write as _;
use std::io::Write as _;
use wpbgi::image::{error_against, read_exr, write_png, Image};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: image_diff OURS.exr REFERENCE.exr [OUT.png]");
        std::process::exit(2);
    }
    let mut a = read_exr(args[1].as_ref())?;
    let mut b = read_exr(args[2].as_ref())?;
    // A render at a whole multiple of the reference's size is averaged down to it by the
    // reference's box pixel filter, as `bench_render modes` does.
    if a.width > b.width && a.width.is_multiple_of(b.width) {
        a = a
            .box_downsample(a.width / b.width)
            .ok_or("the images' sizes are not a whole multiple apart")?;
    }
    // Optional fifth argument x,y,w,h: compare that window, enlarged 4×.
    if let Some(win) = args.get(4) {
        let v: Vec<u32> = win.split(',').filter_map(|x| x.parse().ok()).collect();
        if v.len() == 4 {
            a = crop4(&a, v[0], v[1], v[2], v[3]);
            b = crop4(&b, v[0], v[1], v[2], v[3]);
        }
    }
    let (mse, rel) = error_against(&a, &b).ok_or("the images differ in size")?;
    // The report is written at once, and a reader that stops early (`| head`) ends it
    // quietly.
    let mut report = String::new();
    writeln!(report, "MSE {mse:.4e}  relMSE {rel:.4e}")?;
    writeln!(report, "mean ours {:?}  reference {:?}", a.mean(), b.mean())?;
    let worst = (0..a.pixels.len())
        .max_by(|&i, &j| {
            let e = |k: usize| (a.pixels[k] - b.pixels[k]).abs().max_element();
            e(i).total_cmp(&e(j))
        })
        .unwrap_or(0);
    writeln!(
        report,
        "worst pixel ({}, {}): ours {:?} reference {:?}",
        worst as u32 % a.width,
        worst as u32 / a.width,
        a.pixels[worst],
        b.pixels[worst]
    )?;
    // The pixels that add most to the relative MSE.
    let rel_of = |k: usize| {
        let (x, r) = (a.pixels[k], b.pixels[k]);
        ((x - r) * (x - r) / (r * r + glam::Vec3::splat(0.01))).element_sum() / 3.0
    };
    let mut order: Vec<usize> = (0..a.pixels.len()).collect();
    order.sort_by(|&i, &j| rel_of(j).total_cmp(&rel_of(i)));
    let total: f32 = order.iter().map(|&k| rel_of(k)).sum();
    for &k in order.iter().take(8) {
        writeln!(
            report,
            "  ({}, {}): {:.1} % of relMSE, ours {:?} reference {:?}",
            k as u32 % a.width,
            k as u32 / a.width,
            100.0 * rel_of(k) / total,
            a.pixels[k],
            b.pixels[k]
        )?;
    }
    match std::io::stdout().lock().write_all(report.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => return Err(e.into()),
        _ => {}
    }
    if let Some(out) = args.get(3) {
        let mut s = Image::new(3 * a.width, a.height);
        for y in 0..a.height {
            for x in 0..a.width {
                let (p, q) = (a.get(x, y), b.get(x, y));
                let row = (y * 3 * a.width) as usize;
                s.pixels[row + x as usize] = p;
                s.pixels[row + (a.width + x) as usize] = q;
                s.pixels[row + (2 * a.width + x) as usize] = (p - q).abs() * 4.0;
            }
        }
        write_png(out.as_ref(), &s)?;
    }
    Ok(())
}

/// The window (x, y, w, h) of `img`, each pixel repeated 4 × 4.
fn crop4(img: &Image, x: u32, y: u32, w: u32, h: u32) -> Image {
    let mut out = Image::new(4 * w, 4 * h);
    for j in 0..4 * h {
        for i in 0..4 * w {
            let (sx, sy) = (
                (x + i / 4).min(img.width - 1),
                (y + j / 4).min(img.height - 1),
            );
            out.pixels[(j * 4 * w + i) as usize] = img.get(sx, sy);
        }
    }
    out
}

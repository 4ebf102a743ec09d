//! The error-against-time plot of a [`Report`]: relative MSE against total seconds, log-log,
//! one curve per method (the cache's presets, the path tracer's and the denoised path
//! tracer's samples per pixel), as SVG and as PNG pixels (drawn with plotters; the PNG's text with
//! the DejaVu Sans subset in `assets/fonts`, so it looks the same on a machine without fonts).

use super::report::{Method, Report, Run};
use plotters::coord::Shift;
use plotters::prelude::*;

const SIZE: (u32, u32) = (900, 560);
const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans-subset.ttf");

fn register_font() -> Result<(), String> {
    static REGISTERED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    });
    ok.then_some(())
        .ok_or_else(|| "the plot's font does not load".to_string())
}

/// The plot as an SVG document.
pub(super) fn svg(report: &Report) -> Result<String, String> {
    register_font()?;
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, SIZE).into_drawing_area();
        draw(&root, report)?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(out)
}

/// The plot as 8-bit RGB pixels: (width, height, pixels).
pub(super) fn png_pixels(report: &Report) -> Result<(u32, u32, Vec<u8>), String> {
    register_font()?;
    let mut rgb = vec![255u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        draw(&root, report)?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok((SIZE.0, SIZE.1, rgb))
}

/// One method's curve: its name, colour, and points (seconds, relative MSE, label).
type Curve = (&'static str, RGBColor, Vec<(f64, f64, String)>);

/// A positive value for a log axis (an error of exactly 0 sits at the floor).
fn positive(x: f64) -> f64 {
    if x.is_finite() {
        x.max(1e-12)
    } else {
        1e-12
    }
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, report: &Report) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let point = |r: &Run| (positive(r.total_seconds()), positive(r.rel_mse));
    type Of = fn(&Method) -> bool;
    let curves: Vec<Curve> = [
        (
            "wpbgi (bake + render)",
            RGBColor(31, 119, 180),
            (|m| matches!(m, Method::Cache { .. })) as Of,
        ),
        ("path tracer", RGBColor(214, 39, 40), |m| {
            matches!(m, Method::PathTracer { .. })
        }),
        ("path tracer + OIDN", RGBColor(44, 160, 44), |m| {
            matches!(m, Method::Denoised { .. })
        }),
    ]
    .into_iter()
    .map(|(name, colour, of)| {
        let mut points: Vec<(f64, f64, String)> = report
            .runs
            .iter()
            .filter(|r| of(&r.method))
            .map(|r| {
                let (x, y) = point(r);
                let label = match &r.method {
                    Method::Cache { preset, .. } => preset.name().to_string(),
                    Method::PathTracer { spp } | Method::Denoised { spp } => format!("{spp}"),
                };
                (x, y, label)
            })
            .collect();
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        (name, colour, points)
    })
    .filter(|c| !c.2.is_empty())
    .collect();
    let all = curves.iter().flat_map(|c| c.2.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y, _) in all {
        (x0, x1, y0, y1) = (x0.min(*x), x1.max(*x), y0.min(*y), y1.max(*y));
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (0.1, 10.0, 1e-4, 1.0);
    }
    // Whole decades, at least one, so that the log axes have labelled ticks.
    let decades = |lo: f64, hi: f64| {
        let lo = 10f64.powf((lo / 1.5).log10().floor());
        let hi = 10f64.powf((hi * 1.5).log10().ceil());
        (lo, hi.max(lo * 10.0))
    };
    let ((x0, x1), (y0, y1)) = (decades(x0, x1), decades(y0, y1));
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!(
                "Error against time: {}",
                report
                    .scene
                    .file_name()
                    .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
            ),
            ("sans-serif", 22),
        )
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(80)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("total seconds (bake + render)")
        .y_desc("relative MSE against the reference")
        .x_label_formatter(&|v| format!("{v}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .light_line_style(RGBColor(235, 235, 235))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    for (name, colour, points) in &curves {
        let colour = *colour;
        chart
            .draw_series(LineSeries::new(
                points.iter().map(|p| (p.0, p.1)),
                colour.stroke_width(2),
            ))
            .map_err(err)?
            .label(*name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(points.iter().map(|p| {
                EmptyElement::at((p.0, p.1))
                    + Circle::new((0, 0), 4, colour.filled())
                    + Text::new(p.2.clone(), (6, -16), ("sans-serif", 13))
            }))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    Ok(())
}

//! SVG figures of the report (plotters' SVG backend; text is left to the
//! SVG viewer's fonts, none is shipped):
//!
//! * like the paper's Fig. 5, one per scheme: the estimated trajectory
//!   against ground truth in the plane, processed frames and keyframes
//!   marked;
//! * like Fig. 3: the test path coloured by the true residual and by a
//!   regressor's predicted residual, side by side.

use gpodo_frontends::FrontendRun;
use gpodo_frontends::prediction::ResidualPrediction;
use gpodo_frontends::traverse::Traverse;
use plotters::prelude::*;

/// Plot size (pixels).
const SIZE: (u32, u32) = (720, 720);

/// At most this many points of a line are drawn (keeps the files small).
const MAX_LINE_POINTS: usize = 2500;

/// Every `k`-th point, `k` such that at most [`MAX_LINE_POINTS`] remain,
/// and the last one.
fn thin(points: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    let stride = points.len().div_ceil(MAX_LINE_POINTS).max(1);
    let last = points.last().copied();
    let mut out: Vec<(f64, f64)> = points.into_iter().step_by(stride).collect();
    if let Some(p) = last
        && out.last() != Some(&p)
    {
        out.push(p);
    }
    out
}

fn io(e: impl std::fmt::Display) -> std::io::Error {
    std::io::Error::other(e.to_string())
}

/// The plane bounds of a set of points with a margin, as a square.
fn bounds(
    points: impl Iterator<Item = (f64, f64)>,
) -> (std::ops::Range<f64>, std::ops::Range<f64>) {
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for (x, y) in points {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !x0.is_finite() {
        return (0.0..1.0, 0.0..1.0);
    }
    let span = (x1 - x0).max(y1 - y0).max(1e-3) * 1.08;
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    (
        cx - span / 2.0..cx + span / 2.0,
        cy - span / 2.0..cy + span / 2.0,
    )
}

/// Fig. 5: the trajectory of one scheme against ground truth.
///
/// # Errors
/// A drawing error (as `io::Error`).
pub fn trajectory_svg(
    traverse: &Traverse,
    run: &FrontendRun,
    title: &str,
) -> std::io::Result<String> {
    let truth: Vec<(f64, f64)> = traverse
        .ground_truth()
        .iter()
        .map(|p| (p.translation.vector.x, p.translation.vector.y))
        .collect();
    let estimate: Vec<(f64, f64)> = run
        .trajectory
        .iter()
        .map(|p| (p.translation.vector.x, p.translation.vector.y))
        .collect();
    let at = |t: f64| {
        let k = traverse
            .sample_at_or_before(t)
            .min(estimate.len().saturating_sub(1));
        estimate.get(k).copied()
    };
    let processed: Vec<(f64, f64)> = run
        .processed
        .iter()
        .filter(|f| !f.keyframe)
        .filter_map(|f| at(f.time_secs))
        .collect();
    let keyframes: Vec<(f64, f64)> = run
        .processed
        .iter()
        .filter(|f| f.keyframe)
        .filter_map(|f| at(f.time_secs))
        .collect();
    let (xr, yr) = bounds(truth.iter().chain(&estimate).copied());
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(io)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(48)
            .build_cartesian_2d(xr, yr)
            .map_err(io)?;
        chart
            .configure_mesh()
            .x_desc("x [m]")
            .y_desc("y [m]")
            .light_line_style(WHITE)
            .draw()
            .map_err(io)?;
        chart
            .draw_series(LineSeries::new(thin(truth), BLACK.stroke_width(2)))
            .map_err(io)?
            .label("ground truth")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(2)));
        let blue = RGBColor(31, 119, 180);
        chart
            .draw_series(LineSeries::new(thin(estimate), blue.stroke_width(1)))
            .map_err(io)?
            .label("estimate")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 16, y)], blue.stroke_width(2))
            });
        let frame_colour = RGBColor(44, 160, 44);
        chart
            .draw_series(
                processed
                    .iter()
                    .map(|&p| Circle::new(p, 2, frame_colour.filled())),
            )
            .map_err(io)?
            .label(format!("processed frames ({})", run.frames))
            .legend(move |(x, y)| Circle::new((x + 8, y), 3, frame_colour.filled()));
        let kf_colour = RGBColor(214, 39, 40);
        chart
            .draw_series(
                keyframes
                    .iter()
                    .map(|&p| TriangleMarker::new(p, 5, kf_colour.filled())),
            )
            .map_err(io)?
            .label(format!("keyframes ({})", run.keyframes))
            .legend(move |(x, y)| TriangleMarker::new((x + 8, y), 5, kf_colour.filled()));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(io)?;
        root.present().map_err(io)?;
    }
    Ok(svg)
}

/// A colour for `value` in `[0, max]`: white-yellow-red, as Fig. 3's bar.
fn heat(value: f64, max: f64) -> RGBColor {
    let s = (value / max.max(1e-12)).clamp(0.0, 1.0);
    let g = (255.0 * (1.0 - s)) as u8;
    let b = (200.0 * (1.0 - s).powi(2)) as u8;
    RGBColor(230 - (60.0 * s) as u8, g, b)
}

/// Fig. 3: the test path coloured by the true residual norm of each window
/// (left) and by the predicted one (right), on the same scale.
///
/// # Errors
/// A drawing error (as `io::Error`).
pub fn residual_map_svg(
    traverse: &Traverse,
    predictions: &[ResidualPrediction],
    regressor: &str,
) -> std::io::Result<String> {
    let windows = traverse.windows();
    let points: Vec<(f64, f64)> = windows
        .iter()
        .map(|w| {
            let p = traverse.ground_truth()[w.steps.start].translation.vector;
            (p.x, p.y)
        })
        .collect();
    let truth: Vec<f64> = windows.iter().map(|w| w.true_residual.norm()).collect();
    let predicted: Vec<f64> = predictions.iter().map(|p| p.mean.norm()).collect();
    let mut sorted = truth.clone();
    sorted.sort_by(f64::total_cmp);
    let scale = sorted
        .get((sorted.len() as f64 * 0.95) as usize)
        .copied()
        .unwrap_or(0.01)
        .max(1e-6);
    let (xr, yr) = bounds(points.iter().copied());
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (2 * SIZE.0, SIZE.1)).into_drawing_area();
        root.fill(&WHITE).map_err(io)?;
        let panels = root.split_evenly((1, 2));
        let titles = [
            format!("true residual ‖y‖ (colour scale 0–{:.1} mm/s)", 1e3 * scale),
            format!("predicted ‖μ‖, {regressor}"),
        ];
        for ((panel, title), values) in panels.iter().zip(&titles).zip([&truth, &predicted]) {
            let mut chart = ChartBuilder::on(panel)
                .caption(title, ("sans-serif", 16))
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(48)
                .build_cartesian_2d(xr.clone(), yr.clone())
                .map_err(io)?;
            chart
                .configure_mesh()
                .x_desc("x [m]")
                .y_desc("y [m]")
                .light_line_style(WHITE)
                .draw()
                .map_err(io)?;
            chart
                .draw_series(LineSeries::new(points.iter().copied(), BLACK.mix(0.3)))
                .map_err(io)?;
            chart
                .draw_series(
                    points
                        .iter()
                        .zip(values.iter())
                        .map(|(&p, &v)| Circle::new(p, 4, heat(v, scale).filled())),
                )
                .map_err(io)?;
        }
        root.present().map_err(io)?;
    }
    Ok(svg)
}

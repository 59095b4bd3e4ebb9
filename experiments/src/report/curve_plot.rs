//! The frames-versus-error figure of a sweep: every curve's mean RMSE with
//! its 95 % bootstrap band, against mean frames processed (left) and mean
//! compute (right), in one SVG, every axis logarithmic; the RMSE axis
//! stops at three times the median point (the tables give the collapsed
//! points).

use plotters::prelude::*;

use crate::report::curves::PointSummary;

/// One curve as drawn: its name and its points sorted by the x value.
pub type DrawnCurve<'a> = (&'a str, &'a [PointSummary]);

fn io(e: impl std::fmt::Display) -> std::io::Error {
    std::io::Error::other(e.to_string())
}

/// A colour per curve (cycled).
pub fn colour(i: usize) -> RGBColor {
    const PALETTE: [RGBColor; 10] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
    ];
    PALETTE[i % PALETTE.len()]
}

/// The marker of curve `i` at pixel offset `at`: a circle, a triangle
/// or a cross, so that curves sharing a colour (past ten) still differ.
fn marker<DB: DrawingBackend>(i: usize, at: (i32, i32), c: RGBColor) -> DynElement<'static, DB, (i32, i32)> {
    match (i / 10) % 3 {
        0 => Circle::new(at, 4, c.filled()).into_dyn(),
        1 => TriangleMarker::new(at, 5, c.filled()).into_dyn(),
        _ => Cross::new(at, 4, c.stroke_width(2)).into_dyn(),
    }
}

/// The figure.
///
/// # Errors
/// A drawing error (as `io::Error`).
pub fn curves_svg(curves: &[DrawnCurve<'_>]) -> std::io::Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1400, 640)).into_drawing_area();
        root.fill(&WHITE).map_err(io)?;
        let panels = root.split_evenly((1, 2));
        let x_of: [fn(&PointSummary) -> f64; 2] = [|p| p.frames, |p| p.compute];
        let names = ["frames processed", "compute proxy [s]"];
        let finite = |v: f64| v.is_finite().then_some(v);
        // Collapsed points (tracking lost for good) would squeeze the range
        // that matters: the axis stops at three times the median point.
        let mut estimates: Vec<f64> = curves
            .iter()
            .flat_map(|(_, ps)| ps.iter())
            .filter_map(|p| finite(p.rmse.high).or(finite(p.rmse.estimate)))
            .collect();
        estimates.sort_by(f64::total_cmp);
        let highest = estimates.last().copied().unwrap_or(1e-3).max(1e-3);
        let median = estimates
            .get(estimates.len() / 2)
            .copied()
            .unwrap_or(highest);
        let y_max = highest.min(3.0 * median) * 1.1;
        let lowest = curves
            .iter()
            .flat_map(|(_, ps)| ps.iter())
            .flat_map(|p| [p.rmse.low, p.rmse.estimate])
            .filter(|v| v.is_finite() && *v > 0.0)
            .fold(y_max, f64::min);
        let y_min = (lowest / 1.1).min(y_max / 2.0);
        for (panel, (x, name)) in panels.iter().zip(x_of.iter().zip(names)) {
            let xs: Vec<f64> = curves
                .iter()
                .flat_map(|(_, ps)| ps.iter().map(x))
                .filter(|v| v.is_finite() && *v > 0.0)
                .collect();
            let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = xs.iter().copied().fold(0.0, f64::max);
            if !(lo.is_finite() && hi > lo) {
                continue;
            }
            let mut chart = ChartBuilder::on(panel)
                .caption(format!("RMSE against {name}"), ("sans-serif", 18))
                .margin(16)
                .x_label_area_size(40)
                .y_label_area_size(56)
                .build_cartesian_2d(
                    (lo / 1.2..hi * 1.2).log_scale(),
                    (y_min..y_max).log_scale(),
                )
                .map_err(io)?;
            chart
                .configure_mesh()
                .x_desc(name)
                .y_desc("RMSE [m] (log; mean, 95 % bootstrap band over seeds)")
                .light_line_style(WHITE)
                .draw()
                .map_err(io)?;
            for (i, (label, points)) in curves.iter().enumerate() {
                let c = colour(i);
                let mut sorted: Vec<&PointSummary> = points.iter().filter(|p| x(p) > 0.0).collect();
                sorted.sort_by(|a, b| x(a).total_cmp(&x(b)));
                let band: Vec<(f64, f64)> = sorted
                    .iter()
                    .filter(|p| p.rmse.low.is_finite())
                    .map(|p| (x(p), p.rmse.high.min(y_max)))
                    .chain(
                        sorted
                            .iter()
                            .rev()
                            .filter(|p| p.rmse.low.is_finite())
                            .map(|p| (x(p), p.rmse.low.max(y_min))),
                    )
                    .collect();
                if band.len() >= 4 {
                    chart
                        .draw_series(std::iter::once(Polygon::new(band, c.mix(0.15).filled())))
                        .map_err(io)?;
                }
                let line: Vec<(f64, f64)> =
                    sorted.iter().map(|p| (x(p), p.rmse.estimate)).collect();
                chart
                    .draw_series(LineSeries::new(line.clone(), c.stroke_width(2)))
                    .map_err(io)?
                    .label(label.to_string())
                    .legend(move |(x, y)| {
                        EmptyElement::at((x, y))
                            + PathElement::new(vec![(0, 0), (18, 0)], c.stroke_width(2))
                            + marker(i, (9, 0), c)
                    });
                chart
                    .draw_series(line.into_iter().map(|p| EmptyElement::at(p) + marker(i, (0, 0), c)))
                    .map_err(io)?;
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 11))
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(io)?;
        }
        root.present().map_err(io)?;
    }
    Ok(svg)
}

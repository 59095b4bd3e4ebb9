//! The frames-versus-error figure of a sweep, as small multiples: one panel
//! per gated curve, with the fixed-rate curve of its back end (its
//! control) in grey behind it, each the mean RMSE over seeds with its 95 %
//! bootstrap band; every panel on the same log axes, so panels compare.
//! The RMSE axis stops at three times the median point (the tables give
//! the collapsed points).

use plotters::prelude::*;

use crate::report::curves::PointSummary;

/// One curve as drawn: its name and its points.
pub type DrawnCurve<'a> = (&'a str, &'a [PointSummary]);

/// One panel: a gated curve and, when its back end has one, its fixed-rate
/// control.
pub type Panel<'a> = (DrawnCurve<'a>, Option<DrawnCurve<'a>>);

/// A plotters error as an I/O error.
pub(crate) fn io(e: impl std::fmt::Display) -> std::io::Error {
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
        RGBColor(0, 95, 95),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
    ];
    PALETTE[i % PALETTE.len()]
}

/// Draws `line` in `colour` with a dot at each point, labelled `label` in
/// the chart's legend (the figures' one way to draw a curve).
///
/// # Errors
/// When plotters cannot draw.
pub fn draw_labelled_line<'a, X, Y>(
    chart: &mut ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, Y>>,
    line: Vec<(f64, f64)>,
    colour: RGBColor,
    label: String,
) -> std::io::Result<()>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    chart
        .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))
        .map_err(io)?
        .label(label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2)));
    chart
        .draw_series(line.into_iter().map(|p| Circle::new(p, 3, colour.filled())))
        .map_err(io)?;
    Ok(())
}

/// The axis ranges every panel shares: (frames, RMSE).
fn ranges(panels: &[Panel<'_>]) -> Option<((f64, f64), (f64, f64))> {
    let points = || {
        panels
            .iter()
            .flat_map(|(c, f)| std::iter::once(c).chain(f.iter()))
            .flat_map(|(_, ps)| ps.iter())
    };
    let frames: Vec<f64> = points()
        .map(|p| p.frames)
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let lo = frames.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = frames.iter().copied().fold(0.0, f64::max);
    let mut estimates: Vec<f64> = points()
        .map(|p| p.rmse.estimate)
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    estimates.sort_by(f64::total_cmp);
    let highest = *estimates.last()?;
    let median = estimates[estimates.len() / 2];
    // Collapsed points (tracking lost for good) would squeeze the range
    // that matters.
    let y_max = highest.min(3.0 * median) * 1.15;
    let lowest = points()
        .flat_map(|p| [p.rmse.low, p.rmse.estimate])
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold(y_max, f64::min);
    let y_min = (lowest / 1.1).min(y_max / 2.0);
    (lo.is_finite() && hi > lo).then_some(((lo / 1.2, hi * 1.2), (y_min, y_max)))
}

/// The figure: a grid of panels, three per row.
///
/// # Errors
/// A drawing error (as `io::Error`).
pub fn curves_svg(panels: &[Panel<'_>]) -> std::io::Result<String> {
    let mut svg = String::new();
    let Some(((x_lo, x_hi), (y_lo, y_hi))) = ranges(panels) else {
        return Ok(svg);
    };
    let columns = 3;
    let rows = panels.len().div_ceil(columns).max(1);
    {
        let root = SVGBackend::with_string(&mut svg, (1500, 380 * rows as u32)).into_drawing_area();
        root.fill(&WHITE).map_err(io)?;
        let areas = root.split_evenly((rows, columns));
        for (i, (panel, (curve, control))) in areas.iter().zip(panels).enumerate() {
            let mut chart = ChartBuilder::on(panel)
                .caption(curve.0, ("sans-serif", 15))
                .margin(10)
                .x_label_area_size(36)
                .y_label_area_size(52)
                .build_cartesian_2d((x_lo..x_hi).log_scale(), (y_lo..y_hi).log_scale())
                .map_err(io)?;
            chart
                .configure_mesh()
                .x_desc("frames processed (log)")
                .y_desc("RMSE [m] (log)")
                .x_label_formatter(&|v| format!("{v:.0}"))
                .y_label_formatter(&|v| format!("{v:.2}"))
                .light_line_style(WHITE)
                .draw()
                .map_err(io)?;
            let grey = RGBColor(120, 120, 120);
            let drawn = control
                .iter()
                .map(|c| (c, grey, "fixed rate, same back end"))
                .chain(std::iter::once((curve, colour(i), "policy")));
            for ((_, points), c, role) in drawn {
                let mut sorted: Vec<&PointSummary> =
                    points.iter().filter(|p| p.frames > 0.0).collect();
                sorted.sort_by(|a, b| a.frames.total_cmp(&b.frames));
                let clamp = |v: f64| v.clamp(y_lo, y_hi);
                let band: Vec<(f64, f64)> = sorted
                    .iter()
                    .filter(|p| p.rmse.low.is_finite())
                    .map(|p| (p.frames, clamp(p.rmse.high)))
                    .chain(
                        sorted
                            .iter()
                            .rev()
                            .filter(|p| p.rmse.low.is_finite())
                            .map(|p| (p.frames, clamp(p.rmse.low))),
                    )
                    .collect();
                if band.len() >= 4 {
                    chart
                        .draw_series(std::iter::once(Polygon::new(band, c.mix(0.15).filled())))
                        .map_err(io)?;
                }
                let line: Vec<(f64, f64)> = sorted
                    .iter()
                    .map(|p| (p.frames, clamp(p.rmse.estimate)))
                    .collect();
                draw_labelled_line(&mut chart, line, c, role.to_string())?;
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

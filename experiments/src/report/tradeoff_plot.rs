//! `plots/tradeoff.svg`: frames processed against trajectory RMSE for every
//! scheme of Table II (mean over seeds, ±std bar), on log axes so that a
//! collapsed scheme does not squeeze the rest; one colour and marker per
//! policy family with a legend instead of point labels; every back end's
//! fixed rates joined by a thin line, and a vertical segment from each
//! gated scheme to that line at its frame count: its distance from its
//! fixed-rate control at equal frames.

use plotters::prelude::*;

use crate::execute::records::RunRecord;
use crate::report::controls::interpolate_log_frames;
use crate::report::curve_plot::colour;

/// One scheme as drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct TradeoffPoint {
    /// The policy family (`fixed rate`, `authors' schedule`, …).
    pub family: String,
    /// The scheme's back end (fixed rates of the same back end are its
    /// control).
    pub back_end: String,
    /// Whether it is a fixed-rate scheme.
    pub fixed_rate: bool,
    /// Mean frames processed.
    pub frames: f64,
    /// Mean RMSE (m) and its standard deviation over seeds.
    pub rmse: f64,
    /// Standard deviation of the RMSE (m).
    pub std: f64,
}

/// The marker of family `i`: a circle, a triangle or a cross (with the
/// colour, nine families stay apart).
fn marker<DB: DrawingBackend>(i: usize, c: RGBColor) -> DynElement<'static, DB, (i32, i32)> {
    match i % 3 {
        0 => Circle::new((0, 0), 5, c.filled()).into_dyn(),
        1 => TriangleMarker::new((0, 0), 6, c.filled()).into_dyn(),
        _ => Cross::new((0, 0), 5, c.stroke_width(2)).into_dyn(),
    }
}

fn io(e: impl std::fmt::Display) -> std::io::Error {
    std::io::Error::other(e.to_string())
}

/// The figure.
///
/// # Errors
/// A drawing error (as `io::Error`).
pub fn tradeoff_svg(points: &[TradeoffPoint]) -> std::io::Result<String> {
    let shown: Vec<&TradeoffPoint> = points
        .iter()
        .filter(|p| p.frames > 0.0 && p.rmse > 0.0 && p.rmse.is_finite())
        .collect();
    let (f_lo, f_hi) = shown.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), p| {
        (lo.min(p.frames), hi.max(p.frames))
    });
    let (r_lo, r_hi) = shown.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), p| {
        (lo.min(p.rmse - p.std).min(p.rmse), hi.max(p.rmse + p.std))
    });
    let r_lo = r_lo.max(shown.iter().map(|p| p.rmse).fold(f64::INFINITY, f64::min) / 2.0);
    let mut families: Vec<&str> = Vec::new();
    for p in &shown {
        if !families.contains(&p.family.as_str()) {
            families.push(&p.family);
        }
    }
    let mut svg = String::new();
    if shown.is_empty() || !(f_hi > 0.0 && r_hi > 0.0) {
        return Ok(svg);
    }
    {
        let root = SVGBackend::with_string(&mut svg, (1000, 700)).into_drawing_area();
        root.fill(&WHITE).map_err(io)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "frames processed against trajectory RMSE (mean, ±std over seeds)",
                ("sans-serif", 18),
            )
            .margin(16)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d(
                (f_lo / 1.3..f_hi * 1.3).log_scale(),
                (r_lo / 1.2..r_hi * 1.2).log_scale(),
            )
            .map_err(io)?;
        chart
            .configure_mesh()
            .x_desc("frames processed (log)")
            .y_desc("RMSE [m] (log)")
            .light_line_style(WHITE)
            .draw()
            .map_err(io)?;
        // Each back end's fixed rates, joined.
        let mut back_ends: Vec<&str> = Vec::new();
        for p in shown.iter().filter(|p| p.fixed_rate) {
            if !back_ends.contains(&p.back_end.as_str()) {
                back_ends.push(&p.back_end);
            }
        }
        let grey = RGBColor(150, 150, 150);
        let mut controls: Vec<(&str, Vec<(f64, f64)>)> = Vec::new();
        for b in back_ends {
            let mut line: Vec<(f64, f64)> = shown
                .iter()
                .filter(|p| p.fixed_rate && p.back_end == b)
                .map(|p| (p.frames, p.rmse))
                .collect();
            line.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(line.clone(), grey.stroke_width(1)))
                .map_err(io)?;
            controls.push((b, line));
        }
        // Each gated scheme to its control at equal frames.
        for p in shown.iter().filter(|p| !p.fixed_rate) {
            let Some((_, line)) = controls.iter().find(|(b, _)| *b == p.back_end) else {
                continue;
            };
            if let Some(at) = interpolate_log_frames(line, p.frames) {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(p.frames, at), (p.frames, p.rmse)],
                        BLACK.mix(0.5).stroke_width(1),
                    )))
                    .map_err(io)?;
            }
        }
        for (fi, family) in families.iter().enumerate() {
            let c = colour(fi);
            let mine: Vec<&&TradeoffPoint> = shown.iter().filter(|p| p.family == *family).collect();
            chart
                .draw_series(mine.iter().map(|p| {
                    let lo = (p.rmse - p.std).max(r_lo / 1.2);
                    PathElement::new(vec![(p.frames, lo), (p.frames, p.rmse + p.std)], c.mix(0.4))
                }))
                .map_err(io)?;
            chart
                .draw_series(
                    mine.iter()
                        .map(|p| EmptyElement::at((p.frames, p.rmse)) + marker(fi, c)),
                )
                .map_err(io)?
                .label(family.to_string())
                .legend(move |(x, y)| EmptyElement::at((x + 8, y)) + marker(fi, c));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 12))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(io)?;
        root.present().map_err(io)?;
    }
    Ok(svg)
}

/// A scheme's policy family, as the trade-off figure colours it.
fn family(selector: &gpodo_frontends::SelectorSpec) -> String {
    use gpodo_frontends::SelectorSpec as S;
    match selector {
        S::FixedRate { .. } => "fixed rate".into(),
        S::ResidualSchedule(_) => "authors' schedule".into(),
        S::UncertaintyBudget(_) => "drift budget".into(),
        S::MaxGap { inner, .. } => family(inner),
        S::Hysteresis { .. } => "hysteresis".into(),
        S::Oracle(p) if p.search.is_some() => "hindsight search".into(),
        S::Oracle(_) => "surrogate planner".into(),
        S::FrontLoaded(_) => "front-loaded".into(),
    }
}

/// The frames-versus-RMSE figure of Table II's rows, for a sweep of one
/// setting (its seeds pooled); `None` for several settings, whose
/// figures are the curves per setting.
pub(crate) fn records_tradeoff_svg(records: &[RunRecord]) -> Option<String> {
    let groups = crate::report::curves::by_setting(records);
    let [(_, runs)] = groups.as_slice() else {
        return None;
    };
    let config = &runs.first()?.config;
    let mut points = Vec::new();
    for spec in &config.schemes {
        let values: Vec<(f64, f64)> = runs
            .iter()
            .flat_map(|r| {
                r.metrics
                    .schemes
                    .iter()
                    .filter(|m| m.label == spec.label)
                    .map(|m| (m.frames as f64, m.rmse_m))
            })
            .collect();
        if values.is_empty() {
            continue;
        }
        let n = values.len() as f64;
        let frames = values.iter().map(|v| v.0).sum::<f64>() / n;
        let rmse = values.iter().map(|v| v.1).sum::<f64>() / n;
        let var = values.iter().map(|v| (v.1 - rmse).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
        points.push(TradeoffPoint {
            family: family(&spec.selector),
            back_end: spec.back_end(config),
            fixed_rate: matches!(
                spec.selector,
                gpodo_frontends::SelectorSpec::FixedRate { .. }
            ),
            frames,
            rmse,
            std: var.sqrt(),
        });
    }
    tradeoff_svg(&points).ok()
}

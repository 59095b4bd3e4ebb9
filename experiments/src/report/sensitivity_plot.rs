//! `plots/sensitivity.svg`: gating's effect Δ (policy − fixed rate at
//! equal frames) with its 95 % interval, one row per setting, one panel
//! per frame budget, one colour and marker per policy, the zero line
//! drawn: a forest plot, read at a glance as "left of zero: gating
//! better". The axis spans ±[`MAX_SHOWN_M`] at most; a value beyond is
//! drawn at the edge with its number, and an effect reached on fewer than
//! five seeds (which no verdict counts) is drawn pale.

use plotters::prelude::*;

use crate::report::curve_plot::colour;
use crate::report::curves::BUDGETS;
use crate::report::sensitivity::{Effect, Side};

/// The marker of policy `i`: a circle or a triangle.
fn marker<DB: DrawingBackend>(i: usize, c: RGBAColor) -> DynElement<'static, DB, (i32, i32)> {
    if i.is_multiple_of(2) {
        Circle::new((0, 0), 5, c.filled()).into_dyn()
    } else {
        TriangleMarker::new((0, 0), 6, c.filled()).into_dyn()
    }
}

/// The widest Δ the axis shows (m).
pub const MAX_SHOWN_M: f64 = 0.15;

fn io(e: impl std::fmt::Display) -> std::io::Error {
    std::io::Error::other(e.to_string())
}

/// The figure of `effects` (as [`crate::report::sensitivity::effects`]
/// orders them).
///
/// # Errors
/// A drawing error (as `io::Error`).
pub fn sensitivity_svg(effects: &[Effect]) -> std::io::Result<String> {
    let mut settings: Vec<String> = Vec::new();
    let mut policies: Vec<String> = Vec::new();
    for e in effects {
        if !settings.contains(&e.setting()) {
            settings.push(e.setting());
        }
        if !policies.contains(&e.policy) {
            policies.push(e.policy.clone());
        }
    }
    let n = settings.len();
    // A spare row at the bottom holds the legend.
    let height = 150 + 34 * n as u32;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1400, height)).into_drawing_area();
        root.fill(&WHITE).map_err(io)?;
        let panels = root.split_evenly((1, BUDGETS.len()));
        for (panel, budget) in panels.iter().zip(BUDGETS) {
            let here: Vec<&Effect> = effects.iter().filter(|e| e.budget == budget).collect();
            let bound = here
                .iter()
                .filter_map(|e| e.difference)
                .flat_map(|d| [d.low, d.high, d.estimate])
                .filter(|v| v.is_finite())
                .fold(0.005_f64, |m, v| m.max(v.abs()))
                .min(MAX_SHOWN_M)
                * 1.1;
            let shown = |v: f64| v.clamp(-bound / 1.1, bound / 1.1);
            let labels = settings.clone();
            let mut chart = ChartBuilder::on(panel)
                .caption(
                    format!("{budget:.0} frames: Δ RMSE, policy − fixed rate"),
                    ("sans-serif", 18),
                )
                .margin(14)
                .x_label_area_size(40)
                .y_label_area_size(260)
                .build_cartesian_2d(-bound..bound, -1.5..(n as f64 - 0.5))
                .map_err(io)?;
            chart
                .configure_mesh()
                .x_desc("Δ RMSE [m] (mean over seeds, 95 % bootstrap interval); < 0: gating better")
                .y_labels(4 * (n + 1))
                .y_label_formatter(&move |y| {
                    let i = y.round();
                    if (y - i).abs() > 1e-6 || i < 0.0 {
                        return String::new();
                    }
                    // Top row first.
                    labels
                        .get(n.saturating_sub(1 + i as usize))
                        .cloned()
                        .unwrap_or_default()
                })
                .light_line_style(WHITE)
                .draw()
                .map_err(io)?;
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(0.0, -1.5), (0.0, n as f64 - 0.5)],
                    BLACK.stroke_width(1),
                )))
                .map_err(io)?;
            let k = policies.len().max(1) as f64;
            for (pi, policy) in policies.iter().enumerate() {
                let c = colour(pi);
                let offset = (pi as f64 - (k - 1.0) / 2.0) * 0.25;
                let row = |e: &Effect| {
                    let i = settings.iter().position(|s| *s == e.setting()).unwrap_or(0);
                    (n - 1 - i) as f64 + offset
                };
                // (row, estimate, low, high, counted by a verdict)
                let mine: Vec<(f64, f64, f64, f64, bool)> = here
                    .iter()
                    .filter(|e| &e.policy == policy)
                    .filter_map(|e| {
                        let counted = Side::of_effect(e) != Side::TooFewSeeds;
                        e.difference
                            .filter(|d| d.low.is_finite() && d.high.is_finite())
                            .map(|d| (row(e), d.estimate, d.low, d.high, counted))
                    })
                    .collect();
                let tone = |counted: bool| if counted { c.to_rgba() } else { c.mix(0.3) };
                chart
                    .draw_series(mine.iter().map(|&(y, _, lo, hi, counted)| {
                        PathElement::new(
                            vec![(shown(lo), y), (shown(hi), y)],
                            tone(counted).stroke_width(2),
                        )
                    }))
                    .map_err(io)?;
                chart
                    .draw_series(mine.iter().map(|&(y, x, _, _, counted)| {
                        EmptyElement::at((shown(x), y)) + marker(pi, tone(counted))
                    }))
                    .map_err(io)?
                    .label(policy.clone())
                    .legend(move |(x, y)| EmptyElement::at((x + 8, y)) + marker(pi, c.to_rgba()));
                // A value beyond the axis: its number beside the edge.
                chart
                    .draw_series(mine.iter().filter(|m| m.1.abs() > bound / 1.1).map(
                        |&(y, x, _, _, _)| {
                            Text::new(
                                format!("{x:+.2}"),
                                (shown(x) * 0.82, y + 0.35),
                                ("sans-serif", 11).into_font(),
                            )
                        },
                    ))
                    .map_err(io)?;
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 12))
                .position(SeriesLabelPosition::LowerRight)
                .draw()
                .map_err(io)?;
        }
        root.present().map_err(io)?;
    }
    Ok(svg)
}

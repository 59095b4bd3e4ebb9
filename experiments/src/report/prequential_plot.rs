//! The prequential figure of `gpodo bench` (`plots/prequential.svg`): each
//! contender's RMSE pooled over blocks 2…k against the training rows seen
//! at the end of block k, the refitted baseline in black.

use plotters::prelude::*;

use crate::execute::prequential::Prequential;
use crate::report::curve_plot::{colour, draw_labelled_line, io};

/// The figure as SVG text.
///
/// # Errors
/// When plotters cannot draw.
pub fn prequential_svg(p: &Prequential) -> std::io::Result<String> {
    let scores: Vec<_> = std::iter::once(&p.refitted)
        .chain(&p.baselines)
        .chain(&p.learners)
        .collect();
    let values = scores
        .iter()
        .flat_map(|s| s.cumulative_rmse.iter().copied())
        .filter(|v| v.is_finite());
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    let blocks = scores
        .iter()
        .map(|s| s.cumulative_rmse.len())
        .max()
        .unwrap_or(0);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 500)).into_drawing_area();
        root.fill(&WHITE).map_err(io)?;
        if blocks == 0 || !lo.is_finite() {
            root.present().map_err(io)?;
        } else {
            draw(&root, p, &scores, blocks, (lo, hi))?;
        }
    }
    Ok(svg)
}

/// The chart on `root`: one line per score, over `blocks` blocks, RMSE in
/// `(lo, hi)`.
fn draw(
    root: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    p: &Prequential,
    scores: &[&crate::execute::prequential::PrequentialScore],
    blocks: usize,
    (lo, hi): (f64, f64),
) -> std::io::Result<()> {
    // The k-th point (from 0) closes block k + 2, after k + 2 blocks of rows.
    let rows = p.scored + p.block_rows;
    let x = |k: usize| ((k + 2) * p.block_rows).min(rows) as f64;
    {
        let pad = 0.05 * (hi - lo).max(1e-12);
        let mut chart = ChartBuilder::on(root)
            .caption(
                "Prequential RMSE, pooled over blocks 2…k",
                ("sans-serif", 16),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(x(0)..x(blocks - 1).max(x(0) + 1.0), (lo - pad)..(hi + pad))
            .map_err(io)?;
        chart
            .configure_mesh()
            .x_desc("training rows seen")
            .y_desc("RMSE")
            .y_label_formatter(&|v| format!("{v:.4}"))
            .light_line_style(WHITE)
            .draw()
            .map_err(io)?;
        for (i, score) in scores.iter().enumerate() {
            let c = if i == 0 { BLACK } else { colour(i - 1) };
            let line: Vec<(f64, f64)> = score
                .cumulative_rmse
                .iter()
                .enumerate()
                .map(|(k, v)| (x(k), *v))
                .collect();
            draw_labelled_line(&mut chart, line, c, score.label.clone())?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 11))
            .position(SeriesLabelPosition::LowerRight)
            .draw()
            .map_err(io)?;
        root.present().map_err(io)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::execute::prequential::PrequentialScore;

    fn score(label: &str, cumulative_rmse: Vec<f64>) -> PrequentialScore {
        PrequentialScore {
            label: label.into(),
            rmse: *cumulative_rmse.last().unwrap_or(&0.0),
            nlpd: 0.0,
            update_latency: None,
            cumulative_rmse,
        }
    }

    #[test]
    fn every_contender_is_drawn_and_named() {
        let p = Prequential {
            blocks: 3,
            block_rows: 10,
            scored: 20,
            refitted: score("refitted", vec![0.5, 0.4]),
            refits: Vec::new(),
            baselines: vec![score("running mean", vec![0.6, 0.45])],
            learners: vec![score("ILGR", vec![0.7, 0.5])],
        };
        let svg = prequential_svg(&p).unwrap();
        for label in ["refitted", "running mean", "ILGR", "training rows seen"] {
            assert!(svg.contains(label), "{label}");
        }
        // Three lines of two points each.
        assert_eq!(svg.matches("<circle").count(), 6);
    }
}

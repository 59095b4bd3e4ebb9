//! The controls of Table II on one test run: what gating contributes (a
//! gated scheme against the fixed-rate schemes of the same back end, at
//! equal frames) and what the regressor contributes (a scheme against the
//! same selector fed by the parametric model alone). A scheme's back end is
//! its tracking prior and its residual source; a row is compared only with
//! rows that share both, or that share everything but the residual source.

use std::fmt::Write as _;

use gpodo_frontends::SelectorSpec;
use gpodo_frontends::scheme::SchemeResult;
use gpodo_regressors::RegressorSpec;

use crate::execute::results::ExperimentResults;
use crate::report::table::{Align, Table};

/// A fixed-rate point of a back end: (frames, RMSE).
type Point = (f64, f64);

/// The RMSE of the fixed-rate curve `points` at `frames`, linear in the
/// logarithm of the frame count between the two points around it; `None`
/// outside the points' range (or with fewer than two points unless one
/// matches exactly).
pub fn interpolate_log_frames(points: &[Point], frames: f64) -> Option<f64> {
    interpolate_sorted(points, frames, f64::ln)
}

/// `y` at `x` on the points `(x, y)` sorted by `x` (positive, with finite
/// `y`), linear in `scale(x)` between the two points around it; `None`
/// outside their range (or with fewer than two points unless one matches
/// exactly).
pub fn interpolate_sorted(points: &[Point], x: f64, scale: fn(f64) -> f64) -> Option<f64> {
    let mut sorted: Vec<Point> = points
        .iter()
        .copied()
        .filter(|(f, r)| *f > 0.0 && r.is_finite())
        .collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let Some(&(_, r)) = sorted.iter().find(|(f, _)| *f == x) {
        return Some(r);
    }
    sorted.windows(2).find_map(|w| {
        let ((f0, r0), (f1, r1)) = (w[0], w[1]);
        (f0 < x && x < f1).then(|| {
            let t = (scale(x) - scale(f0)) / (scale(f1) - scale(f0));
            r0 + t * (r1 - r0)
        })
    })
}

/// The section, empty when no row has a control.
pub fn controls_section(s: &mut String, r: &ExperimentResults) {
    let spec = |label: &str| r.config.schemes.iter().find(|x| x.label == label);
    // A fixed rate at a phase is an A/A control (the sweep report's floor),
    // neither a point of the fixed-rate curve nor a gated scheme.
    let is_phased = |x: &SchemeResult| {
        spec(&x.label).is_some_and(
            |p| matches!(p.selector, SelectorSpec::FixedRate { phase_secs, .. } if phase_secs > 0.0),
        )
    };
    let is_fixed = |x: &SchemeResult| {
        spec(&x.label).is_some_and(
            |p| matches!(p.selector, SelectorSpec::FixedRate { phase_secs, .. } if phase_secs == 0.0),
        )
    };
    let is_oracle =
        |x: &SchemeResult| spec(&x.label).is_some_and(|p| p.selector.oracle().is_some());
    let zero_labels: Vec<String> = r
        .config
        .regressors
        .iter()
        .filter(|x| matches!(x, RegressorSpec::Zero { .. }))
        .map(RegressorSpec::label)
        .collect();
    let mut gating = Table::new(&[
        "Scheme",
        "back end",
        "#Frames",
        "RMSE [m]",
        "fixed rate, equal frames [m]",
        "Δ RMSE [m]",
        "fixed-rate rows",
    ])
    .align(&[1, 6], Align::Left);
    let mut regressor = Table::new(&[
        "Scheme",
        "control (zero residuals)",
        "#Frames",
        "control #Frames",
        "RMSE [m]",
        "control RMSE [m]",
        "Δ RMSE [m]",
    ])
    .align(&[1], Align::Left);
    for traverse in r.traverses.iter() {
        let rows: Vec<&SchemeResult> = r
            .schemes
            .iter()
            .filter(|x| x.traverse == traverse.name())
            .collect();
        let run = if r.traverses.len() > 1 {
            format!(" (`{}`)", traverse.name())
        } else {
            String::new()
        };
        for x in rows
            .iter()
            .filter(|x| !is_fixed(x) && !is_phased(x) && !is_oracle(x))
        {
            let fixed: Vec<&&SchemeResult> = rows
                .iter()
                .filter(|y| {
                    is_fixed(y) && y.motion_prior == x.motion_prior && y.residuals == x.residuals
                })
                .collect();
            if fixed.is_empty() {
                continue;
            }
            let points: Vec<Point> = fixed
                .iter()
                .map(|y| (y.run.frames as f64, y.run.metrics.rmse_m))
                .collect();
            let at = interpolate_log_frames(&points, x.run.frames as f64);
            gating.push(vec![
                format!("{}{run}", x.label),
                format!("{}, {:?} prior", x.residuals, x.motion_prior).to_lowercase(),
                x.run.frames.to_string(),
                format!("{:.3}", x.run.metrics.rmse_m),
                at.map_or("outside their range".into(), |v| format!("{v:.3}")),
                at.map_or("–".into(), |v| {
                    format!("{:+.3}", x.run.metrics.rmse_m - v)
                }),
                fixed
                    .iter()
                    .map(|y| format!("{} ({} frames)", y.label, y.run.frames))
                    .collect::<Vec<_>>()
                    .join("; "),
            ]);
        }
        for x in rows.iter().filter(|x| !zero_labels.contains(&x.residuals)) {
            let Some(px) = spec(&x.label) else { continue };
            if is_fixed(x) || is_phased(x) || is_oracle(x) {
                continue;
            }
            let control = rows.iter().find(|y| {
                zero_labels.contains(&y.residuals)
                    && y.motion_prior == x.motion_prior
                    && spec(&y.label).is_some_and(|py| py.selector == px.selector)
            });
            let Some(y) = control else { continue };
            regressor.push(vec![
                format!("{}{run}", x.label),
                y.label.clone(),
                x.run.frames.to_string(),
                y.run.frames.to_string(),
                format!("{:.3}", x.run.metrics.rmse_m),
                format!("{:.3}", y.run.metrics.rmse_m),
                format!("{:+.3}", x.run.metrics.rmse_m - y.run.metrics.rmse_m),
            ]);
        }
    }
    if gating.is_empty() && regressor.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "## Controls — what gating and what the regressor contribute\n\nA scheme's back end is its tracking prior and its residual source (which also corrects the odometry in the pose graph). Gating's effect: each gated scheme against the fixed-rate schemes of the same back end, their RMSE interpolated at the gated scheme's frame count (linear in log frames; Δ < 0: gating is better at equal frames). The regressor's effect: each scheme against the same selector and prior fed by the parametric model alone (zero residuals). One seed: schemes grouped into `curve:`s and run over `seeds:` give these comparisons with intervals over seeds, in the sweep report's frames-versus-error curves.\n"
    );
    if !gating.is_empty() {
        let _ = writeln!(s, "Gating against fixed rate:\n\n{}", gating.markdown());
    }
    if !regressor.is_empty() {
        let _ = writeln!(
            s,
            "Regressor against zero residuals:\n\n{}",
            regressor.markdown()
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_is_linear_in_log_frames_and_refuses_to_extrapolate() {
        let points = [(100.0, 0.3), (1000.0, 0.1), (400.0, 0.2)];
        let mid = 10f64.powf(2.5); // halfway between 100 and 1000 in log
        let at = interpolate_log_frames(&[points[0], points[1]], mid).unwrap_or(f64::NAN);
        assert!((at - 0.2).abs() < 1e-12, "{at}");
        assert_eq!(interpolate_log_frames(&points, 400.0), Some(0.2));
        let between = interpolate_log_frames(&points, 200.0).unwrap_or(f64::NAN);
        let t = (200f64.ln() - 100f64.ln()) / (400f64.ln() - 100f64.ln());
        assert!((between - (0.3 - 0.1 * t)).abs() < 1e-12);
        assert_eq!(interpolate_log_frames(&points, 50.0), None);
        assert_eq!(interpolate_log_frames(&points, 2000.0), None);
        assert_eq!(interpolate_log_frames(&points[..1], 150.0), None);
    }
}

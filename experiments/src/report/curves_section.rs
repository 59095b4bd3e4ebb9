//! The "Frames-versus-error curves" section of a sweep report: the points
//! of every curve over seeds, table (a) (frames to come within 10 % of the
//! same back end's 2.5 fps RMSE), table (b) (RMSE at the paper's budgets,
//! paired with fixed rate at equal frames), the per-seed pairs as CSV, and
//! the figure.

use std::fmt::Write as _;

use crate::execute::records::RunRecord;
use crate::report::bootstrap::{Interval, RESAMPLES};
use crate::report::curve_plot::{Panel, curves_svg};
use crate::report::curves::{
    BUDGETS, Curve, Curves, FramesToReach, PointSummary, WITHIN, by_setting, frames_to_reach,
    summarise,
};
use crate::report::floor::{Floor, floors, mde_cell, nearest};
use crate::report::oracle_table::oracle_table;
use crate::report::pairing::{at_budget, at_equal_compute, push_pairs};
use crate::report::table::{Align, Table};
use crate::report::twin_table::twin_table;
use crate::report::verdict::verdict;

/// What the section adds to a sweep report.
#[derive(Debug, Clone, PartialEq)]
pub struct CurvesSection {
    /// The Markdown.
    pub markdown: String,
    /// Tables to write under `tables/` (file name, table with CSV twin).
    pub tables: Vec<(String, Table)>,
    /// Figures to write under `plots/` (file name, SVG).
    pub figures: Vec<(String, String)>,
}

fn interval(i: &Interval, digits: usize) -> String {
    if i.low.is_finite() && i.high.is_finite() {
        format!(
            "{:.*} [{:.*}, {:.*}]",
            digits, i.estimate, digits, i.low, digits, i.high
        )
    } else {
        format!("{:.*}", digits, i.estimate)
    }
}

/// The Markdown cell and CSV cells of a table (a) outcome.
fn reach_cells(found: FramesToReach) -> (String, Vec<String>) {
    match found {
        FramesToReach::Crosses(i) => (
            if i.defined < 1.0 {
                format!(
                    "{} (reached in {:.0} % of resamples)",
                    interval(&i, 0),
                    100.0 * i.defined
                )
            } else {
                interval(&i, 0)
            },
            vec![
                "crosses".to_string(),
                i.estimate.to_string(),
                i.low.to_string(),
                i.high.to_string(),
                i.defined.to_string(),
            ],
        ),
        FramesToReach::AtMost(f) => (
            format!("≤ {f:.0} (its fewest)"),
            vec![
                "at_most".into(),
                f.to_string(),
                String::new(),
                String::new(),
                String::new(),
            ],
        ),
        FramesToReach::Never { best_ratio, frames } => (
            format!("never (best {best_ratio:.2}× at {frames:.0} frames)"),
            vec![
                "never".into(),
                frames.to_string(),
                String::new(),
                String::new(),
                best_ratio.to_string(),
            ],
        ),
    }
}

/// The section over `records`, `None` when no scheme names a curve.
/// `seed` seeds every bootstrap.
pub fn curves_section(records: &[RunRecord], seed: u64) -> Option<CurvesSection> {
    let groups = by_setting(records);
    let many = groups.len() > 1;
    let mut out = CurvesSection {
        markdown: String::new(),
        tables: Vec::new(),
        figures: Vec::new(),
    };
    for (g, (setting, runs)) in groups.iter().enumerate() {
        let Some(curves) = Curves::of(runs) else {
            continue;
        };
        let suffix = if many { format!("_{g}") } else { String::new() };
        let label = if many {
            format!(" (`{setting}`)")
        } else {
            String::new()
        };
        write_intro(&mut out.markdown, &label, &curves, &suffix);
        let summaries: Vec<Vec<PointSummary>> =
            curves.curves.iter().map(|c| summarise(c, seed)).collect();
        let points = points_table(&curves, &summaries);
        let reach = reach_table(&curves, seed);
        let mut paired = Table::new(&["curve"]).with_csv(&[
            "curve",
            "against",
            "budget_frames",
            "seed",
            "rmse_m",
            "against_rmse_m",
            "difference_m",
        ]);
        let floors = floors(runs, seed);
        let margin = runs.first().and_then(|r| r.config.equivalence_margin_m);
        let budget = budget_table(&curves, seed, &mut paired, &floors, margin);
        let twin = twin_table(&curves, seed, &mut paired, margin);
        let oracles = oracle_table(&curves, seed, margin);
        let s = &mut out.markdown;
        let _ = writeln!(s, "Points of every curve:\n\n{}", points.markdown());
        let _ = writeln!(
            s,
            "(a) Frames each curve needs to come within {:.0} % of the 2.5 fps RMSE of its own back end, and of the experiment's first scheme (the paper's baseline): the mean over seeds of the per-seed RMSE ratio, its first crossing, linear in log frames between knob values; \"never\" gives the best mean ratio reached:\n\n{}",
            100.0 * (WITHIN - 1.0),
            reach.markdown()
        );
        let _ = writeln!(
            s,
            "(b) RMSE at the paper's budgets (each seed's curve interpolated in log frames, never extrapolated), paired per seed with the fixed-rate curve of the same back end at the same frames (Δ < 0: the policy is better than fixed rate at equal frames). MDE: the minimum detectable effect of the nearest A/A pair of the same back end (the floor section); a Δ within it cannot be told from frame choice that does nothing. The verdict: lower or higher when the interval excludes zero, equivalent when it crosses zero within the experiment's `equivalence_margin_m`, otherwise not resolved. Δ at equal compute pairs the policy, at the fixed rate's compute-model cost at the budget, with the fixed rate at the budget. Per-seed pairs: `tables/curves_paired{suffix}.csv`.\n\n{}",
            budget.markdown()
        );
        if !twin.is_empty() {
            let _ = writeln!(
                s,
                "(c) What the regressor contributes: each curve against the same policy with the same knob values on zero residuals (the parametric model alone) and the same prior, paired per seed at the same frames (Δ < 0: the regressor helps).\n\n{}",
                twin.markdown()
            );
        }
        if !oracles.is_empty() {
            let _ = writeln!(
                s,
                "(d) Each oracle on the measure it minimises (the drift since the last look, were every look exact; `frontends/src/oracle`), against the fixed rate of its back end at equal frames, paired per seed as in (b) (Δ < 0: the oracle drifts less between looks). The equivalence margin of the verdict is the experiment's, in metres.\n\n{}",
                oracles.markdown()
            );
        }
        out.tables
            .push((format!("curves_oracles{suffix}.csv"), oracles));
        out.tables
            .push((format!("curves_points{suffix}.csv"), points));
        out.tables
            .push((format!("curves_regressor_effect{suffix}.csv"), twin));
        out.tables
            .push((format!("curves_frames_to_reach{suffix}.csv"), reach));
        out.tables
            .push((format!("curves_at_budget{suffix}.csv"), budget));
        out.tables
            .push((format!("curves_paired{suffix}.csv"), paired));
        if let Err(e) = draw_figure(&mut out, &curves, &summaries, &suffix) {
            let _ = writeln!(out.markdown, "(The figure could not be drawn: {e}.)\n");
        }
    }
    (!out.markdown.is_empty()).then_some(out)
}

/// The section's heading and what its numbers are.
fn write_intro(s: &mut String, label: &str, curves: &Curves, suffix: &str) {
    let _ = writeln!(
        s,
        "## Frames-versus-error curves{}\n\nEach curve is one policy with one knob varied; every point is a scheme run on all {} seeds ({:?}), all schemes sharing each seed's data and tracker streams. Mean over seeds with a 95 % percentile-bootstrap interval ({RESAMPLES} resamples of seeds). Figure: `plots/curves{suffix}.svg` (one panel per policy, its back end's fixed rates in grey).\n",
        label,
        curves.seeds.len(),
        curves.seeds
    );
}

/// Every point of every curve: frames, compute and RMSE over seeds.
fn points_table(curves: &Curves, summaries: &[Vec<PointSummary>]) -> Table {
    let mut points = Table::new(&[
        "curve",
        "scheme",
        "frames",
        "compute [s]",
        "RMSE [m] (95 % CI)",
        "drift since look, p95 [mm]",
        "RPE 1 m [mm]",
        "compute [ms/m]",
    ])
    .align(&[1], Align::Left)
    .with_csv(&[
        "curve",
        "back_end",
        "scheme",
        "frames_mean",
        "compute_mean_s",
        "rmse_mean_m",
        "rmse_low_m",
        "rmse_high_m",
        "drift_since_look_p95_mean_m",
        "rpe_1m_mean_m",
        "cpu_ms_per_m_mean",
    ]);
    for (c, summary) in curves.curves.iter().zip(summaries) {
        for p in summary {
            points.push(vec![
                c.name.clone(),
                p.label.clone(),
                format!("{:.0}", p.frames),
                format!("{:.1}", p.compute),
                interval(&p.rmse, 3),
                format!("{:.1}", 1e3 * p.drift_since_look_p95_m),
                format!("{:.1}", 1e3 * p.rpe_1m_m),
                format!("{:.0}", p.cpu_ms_per_m),
            ]);
            points.push_csv(vec![
                c.name.clone(),
                c.back_end.clone(),
                p.label.clone(),
                p.frames.to_string(),
                p.compute.to_string(),
                p.rmse.estimate.to_string(),
                p.rmse.low.to_string(),
                p.rmse.high.to_string(),
                p.drift_since_look_p95_m.to_string(),
                p.rpe_1m_m.to_string(),
                p.cpu_ms_per_m.to_string(),
            ]);
        }
    }
    points
}

/// Table (a): the frames each curve needs to come within 10 % of its own
/// back end's 2.5 fps RMSE, and of the experiment's first scheme.
fn reach_table(curves: &Curves, seed: u64) -> Table {
    let baseline = curves.baseline.as_ref();
    let baseline_name = baseline.map_or("the first scheme".to_string(), |(l, _)| format!("`{l}`"));
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let mut reach = Table::new(&[
        "curve".to_string(),
        "back end".to_string(),
        "2.5 fps RMSE of the back end [m]".to_string(),
        "frames to within 10 % of it (95 % CI)".to_string(),
        format!(
            "frames to within 10 % of {baseline_name} ({:.3} m)",
            baseline.map_or(f64::NAN, |(_, r)| mean(r))
        ),
    ])
    .align(&[1], Align::Left)
    .with_csv(&[
        "curve",
        "back_end",
        "reference",
        "reference_rmse_m",
        "outcome",
        "frames",
        "frames_low",
        "frames_high",
        "share_of_resamples_reaching_or_best_ratio",
    ]);
    for c in &curves.curves {
        let own = c
            .reference
            .as_ref()
            .map(|r| (r, reach_cells(frames_to_reach(c, r, seed))));
        let paper = baseline.map(|(_, r)| reach_cells(frames_to_reach(c, r, seed)));
        reach.push(vec![
            c.name.clone(),
            c.back_end.clone(),
            own.as_ref()
                .map_or("–".into(), |(r, _)| format!("{:.3}", mean(r))),
            own.as_ref()
                .map_or("–".into(), |(_, (cell, _))| cell.clone()),
            paper.as_ref().map_or("–".into(), |(cell, _)| cell.clone()),
        ]);
        let mut rows = Vec::new();
        if let Some((r, (_, csv))) = &own {
            rows.push(("back end 2.5 fps".to_string(), mean(r), csv.clone()));
        }
        if let (Some((label, r)), Some((_, csv))) = (baseline, &paper) {
            rows.push((label.clone(), mean(r), csv.clone()));
        }
        for (reference, rmse, csv) in rows {
            let mut row = vec![
                c.name.clone(),
                c.back_end.clone(),
                reference,
                rmse.to_string(),
            ];
            row.extend(csv);
            reach.push_csv(row);
        }
    }
    reach
}

/// Table (b): RMSE at the paper's budgets, paired per seed with the fixed
/// rate of the same back end; each seed's pair goes into `paired`.
fn budget_table(
    curves: &Curves,
    seed: u64,
    paired: &mut Table,
    floors: &[Floor],
    margin: Option<f64>,
) -> Table {
    let mut budget = Table::new(&[
        "curve",
        "frames",
        "seeds in range",
        "RMSE [m] (95 % CI)",
        "fixed rate, same back end [m]",
        "Δ RMSE [m] (95 % CI)",
        "MDE [m]",
        "gating vs fixed rate",
        "Δ at equal compute [m] (95 % CI)",
    ])
    .align(&[6, 7], Align::Left)
    .with_csv(&[
        "curve",
        "budget_frames",
        "seeds",
        "rmse_mean_m",
        "rmse_low_m",
        "rmse_high_m",
        "fixed_mean_m",
        "difference_mean_m",
        "difference_low_m",
        "difference_high_m",
        "mde_m",
        "equal_compute_difference_mean_m",
        "equal_compute_difference_low_m",
        "equal_compute_difference_high_m",
    ]);
    for c in &curves.curves {
        let fixed = if c.fixed_rate {
            None
        } else {
            curves.fixed_rate_of(&c.back_end)
        };
        if !c.fixed_rate && fixed.is_none() {
            continue;
        }
        for b in BUDGETS {
            let r = at_budget(c, fixed, &curves.seeds, b, seed);
            let Some(mean) = r.rmse_mean else { continue };
            let fixed_mean = r.fixed.iter().sum::<f64>() / r.fixed.len() as f64;
            let equal_compute =
                fixed.and_then(|f| at_equal_compute(c, f, &curves.seeds, b, seed).difference);
            budget.push(vec![
                c.name.clone(),
                format!("{b:.0}"),
                format!("{}/{}", r.seeds.len(), curves.seeds.len()),
                interval(&mean, 3),
                format!("{fixed_mean:.3}"),
                r.difference
                    .as_ref()
                    .map_or("– (is the fixed rate)".into(), |d| {
                        format!("{:+.3} [{:+.3}, {:+.3}]", d.estimate, d.low, d.high)
                    }),
                mde_cell(floors, &c.back_end, b),
                r.difference
                    .as_ref()
                    .map_or("–".into(), |d| verdict(d, r.seeds.len(), margin)),
                equal_compute.map_or("–".into(), |d| {
                    format!("{:+.3} [{:+.3}, {:+.3}]", d.estimate, d.low, d.high)
                }),
            ]);
            let zero = Interval {
                estimate: 0.0,
                low: 0.0,
                high: 0.0,
                defined: 1.0,
            };
            let d = r.difference.unwrap_or(zero);
            let e = equal_compute.unwrap_or(zero);
            let mde = nearest(floors, &c.back_end, b).map_or(f64::NAN, Floor::mde_m);
            budget.push_csv(vec![
                c.name.clone(),
                b.to_string(),
                r.seeds.len().to_string(),
                mean.estimate.to_string(),
                mean.low.to_string(),
                mean.high.to_string(),
                fixed_mean.to_string(),
                d.estimate.to_string(),
                d.low.to_string(),
                d.high.to_string(),
                mde.to_string(),
                e.estimate.to_string(),
                e.low.to_string(),
                e.high.to_string(),
            ]);
            push_pairs(
                paired,
                &c.name,
                fixed.map_or("", |f| f.name.as_str()),
                b,
                &r,
            );
        }
    }
    budget
}

/// The figure: one panel per policy, its back end's fixed rate in grey.
fn draw_figure(
    out: &mut CurvesSection,
    curves: &Curves,
    summaries: &[Vec<PointSummary>],
    suffix: &str,
) -> Result<(), String> {
    let drawn = |c: &Curve| -> Option<(&str, &[PointSummary])> {
        let i = curves.curves.iter().position(|x| x.name == c.name)?;
        Some((curves.curves[i].name.as_str(), summaries[i].as_slice()))
    };
    let panels: Vec<Panel<'_>> = curves
        .curves
        .iter()
        .filter(|c| !c.fixed_rate)
        .filter_map(|c| {
            let control = curves.fixed_rate_of(&c.back_end).and_then(&drawn);
            Some((drawn(c)?, control))
        })
        .collect();
    let svg = curves_svg(&panels).map_err(|e| e.to_string())?;
    out.figures.push((format!("curves{suffix}.svg"), svg));
    Ok(())
}

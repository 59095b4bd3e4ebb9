//! "The verdict" section of a sweep report: the experiment's committed
//! rules ([`VerdictRules`], its `verdict:` block) applied to every regime
//! (each setting of a sweep). For each policy and comparison (a measure
//! at a frame budget) the policy's curve is paired per route with the
//! fixed-rate curve of its own back end at equal frames, and the outcome
//! is one of better, worse, equivalent within ε, or cannot decide, beside
//! the minimum detectable effect of the nearest A/A pair on the same
//! measure.
//!
//! The tests: for RMSE, drift and compute, the mean paired Δ with its
//! percentile-bootstrap interval and p-value
//! ([`bootstrap_with_p`]); for losses, a count, the exact sign test and
//! the order-statistic interval of the median ([`crate::report::exact`]).
//! The primary comparison is tested at α for each policy; the secondary
//! ones of every policy of a regime form one family, corrected by Holm's
//! step-down rule.

use std::fmt::Write as _;

use crate::config::{Comparison, Measure, VerdictRules};
use crate::execute::records::{RunRecord, SchemeMetrics};
use crate::report::bootstrap::{Interval, bootstrap_with_p, mean_at};
use crate::report::curves::{Curve, Curves, by_setting};
use crate::report::exact::{median_interval, sign_test};
use crate::report::floor::pair_on_first_traverse;
use crate::report::pairing::at_budget;
use crate::report::table::{Align, Table};
use crate::report::verdict::MIN_SEEDS_FOR_VERDICT;

/// The outcome of one comparison.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// The (corrected) test rejects Δ = 0 and Δ < 0.
    Better,
    /// The (corrected) test rejects Δ = 0 and Δ > 0.
    Worse,
    /// Not rejected, and the 95 % interval lies within ±ε.
    Equivalent,
    /// Neither.
    CannotDecide,
    /// Fewer than [`MIN_SEEDS_FOR_VERDICT`] routes reach the budget on
    /// both curves.
    TooFewRoutes,
}

impl Outcome {
    /// The outcome in words; a difference the test finds but whose
    /// interval lies within ±ε says so.
    fn words(self, margin: f64, within: bool) -> String {
        let negligible = if within {
            format!(" (within ±{})", short(margin))
        } else {
            String::new()
        };
        match self {
            Self::Better => format!("better{negligible}"),
            Self::Worse => format!("worse{negligible}"),
            Self::Equivalent => format!("equivalent (±{})", short(margin)),
            Self::CannotDecide => "cannot decide".into(),
            Self::TooFewRoutes => "too few routes".into(),
        }
    }
}

/// One policy on one comparison in one regime.
#[derive(Debug, Clone, PartialEq)]
pub struct Judgement {
    /// The regime (the sweep setting; empty for a single one).
    pub regime: String,
    /// The policy's curve.
    pub policy: String,
    /// Its fixed-rate curve.
    pub against: String,
    /// The comparison.
    pub comparison: Comparison,
    /// Whether it is the primary one.
    pub primary: bool,
    /// Routes on which both curves reach the budget.
    pub routes: usize,
    /// Δ (policy − fixed rate): the mean, or the median for a count,
    /// with its 95 % interval (exact for a count: its coverage in
    /// `defined`).
    pub delta: Option<Interval>,
    /// The test's p-value.
    pub p: f64,
    /// After Holm's correction (the primary's is its own).
    pub p_adjusted: f64,
    /// The MDE of the nearest A/A pair of the same back end on this
    /// measure, and that pair's frames.
    pub mde: Option<(f64, f64)>,
    /// ε.
    pub margin: f64,
    /// The outcome.
    pub outcome: Outcome,
}

/// A number in a measure's unit, short.
fn short(v: f64) -> String {
    if v.abs() >= 10.0 {
        format!("{v:.0}")
    } else if v.abs() >= 0.1 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}

/// A scheme's value on `measure`.
fn value(m: &SchemeMetrics, measure: Measure) -> f64 {
    match measure {
        Measure::Rmse => m.rmse_m,
        Measure::Losses => m.tracking_losses as f64,
        Measure::DriftSinceLook => m.rover.drift_since_look_p95_m,
        Measure::CpuPerMetre => m.rover.cpu_ms_per_m,
    }
}

/// `curve` with its values on `measure` in place of RMSE.
fn on_measure(curve: &Curve, measure: Measure) -> Curve {
    match measure {
        Measure::Rmse => curve.clone(),
        Measure::Losses => curve.with_losses(),
        Measure::DriftSinceLook => curve.with_measure(|r| r.drift_since_look_p95_m),
        Measure::CpuPerMetre => curve.with_measure(|r| r.cpu_ms_per_m),
    }
}

/// Δ's estimate, interval and p-value over paired differences: the
/// bootstrap of the mean, or for a count the median's exact interval and
/// the sign test.
fn infer(differences: &[f64], measure: Measure, seed: u64) -> Option<(Interval, f64)> {
    if measure.is_count() {
        let (median, low, high, coverage) = median_interval(differences, 0.95)?;
        let interval = Interval {
            estimate: median,
            low,
            high,
            defined: coverage,
        };
        Some((interval, sign_test(differences)))
    } else {
        bootstrap_with_p(differences.len(), seed, |ix| Some(mean_at(differences, ix)))
    }
}

/// The A/A floors of `runs` on `measure`: (back end, mean frames, MDE).
fn floors_on(runs: &[&RunRecord], measure: Measure, seed: u64) -> Vec<(String, f64, f64)> {
    let Some(first) = runs.first() else {
        return Vec::new();
    };
    let config = &first.config;
    let mut out = Vec::new();
    for (u, s) in config.phase_pairs() {
        let (unshifted, shifted) = (&config.schemes[u].label, &config.schemes[s].label);
        let mut frames = Vec::new();
        let mut differences = Vec::new();
        for r in runs {
            if let Some((a, b)) = pair_on_first_traverse(r, unshifted, shifted) {
                frames.push(a.frames as f64);
                differences.push(value(b, measure) - value(a, measure));
            }
        }
        if let Some((interval, _)) = infer(&differences, measure, seed) {
            let mde = 0.5 * (interval.high - interval.low);
            let mean_frames = frames.iter().sum::<f64>() / frames.len() as f64;
            if mde.is_finite() {
                out.push((config.schemes[u].back_end(config), mean_frames, mde));
            }
        }
    }
    out
}

/// Holm's step-down adjustment of `p` (in place, NaN left out).
fn holm(p: &mut [f64]) {
    let mut order: Vec<usize> = (0..p.len()).filter(|&i| p[i].is_finite()).collect();
    order.sort_by(|&a, &b| p[a].total_cmp(&p[b]));
    let m = order.len();
    let mut running: f64 = 0.0;
    for (rank, &i) in order.iter().enumerate() {
        running = running.max(((m - rank) as f64 * p[i]).min(1.0));
        p[i] = running;
    }
}

/// Every judgement of one regime under `rules`.
pub fn judge(regime: &str, runs: &[&RunRecord], rules: &VerdictRules, seed: u64) -> Vec<Judgement> {
    let Some(curves) = Curves::of(runs) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for (primary, comparison) in rules.comparisons() {
        let measure = comparison.measure;
        let floors = floors_on(runs, measure, seed);
        let margin = rules.margins.of(measure);
        for policy in &rules.policies {
            let Some(curve) = curves.curves.iter().find(|c| &c.name == policy) else {
                continue;
            };
            let Some(fixed) = curves.fixed_rate_of(&curve.back_end) else {
                continue;
            };
            let pairs = at_budget(
                &on_measure(curve, measure),
                Some(&on_measure(fixed, measure)),
                &curves.seeds,
                comparison.frames,
                seed,
            );
            let differences: Vec<f64> = pairs
                .rmse
                .iter()
                .zip(&pairs.fixed)
                .map(|(a, b)| a - b)
                .collect();
            let inferred = (differences.len() >= MIN_SEEDS_FOR_VERDICT)
                .then(|| infer(&differences, measure, seed))
                .flatten();
            let mde = floors
                .iter()
                .filter(|f| f.0 == curve.back_end)
                .min_by(|a, b| {
                    let d = |f: &(String, f64, f64)| (f.1.ln() - comparison.frames.ln()).abs();
                    d(a).total_cmp(&d(b))
                })
                .map(|f| (f.2, f.1));
            let p = inferred.map_or(f64::NAN, |i| i.1);
            out.push(Judgement {
                regime: regime.to_string(),
                policy: policy.clone(),
                against: fixed.name.clone(),
                comparison,
                primary,
                routes: differences.len(),
                delta: inferred.map(|i| i.0),
                p,
                p_adjusted: p,
                mde,
                margin,
                outcome: Outcome::TooFewRoutes,
            });
        }
    }
    let secondary: Vec<usize> = (0..out.len()).filter(|&i| !out[i].primary).collect();
    let mut adjusted: Vec<f64> = secondary.iter().map(|&i| out[i].p).collect();
    holm(&mut adjusted);
    for (&i, p) in secondary.iter().zip(adjusted) {
        out[i].p_adjusted = p;
    }
    for j in &mut out {
        j.outcome = match j.delta {
            None => Outcome::TooFewRoutes,
            Some(d) if j.p_adjusted < rules.alpha => {
                if d.estimate < 0.0 {
                    Outcome::Better
                } else {
                    Outcome::Worse
                }
            }
            Some(d) if -j.margin < d.low && d.high < j.margin => Outcome::Equivalent,
            Some(_) => Outcome::CannotDecide,
        };
    }
    out
}

/// The section over `records` (every setting with rules), with its table;
/// `None` when no run commits rules.
pub fn verdict_section(records: &[RunRecord], seed: u64) -> Option<(String, Table)> {
    let groups = by_setting(records);
    let many = groups.len() > 1;
    let mut judgements = Vec::new();
    let mut rules_seen = None;
    for (setting, runs) in &groups {
        let Some(rules) = runs.first().and_then(|r| r.config.verdict.as_ref()) else {
            continue;
        };
        let regime = if many { setting.clone() } else { String::new() };
        judgements.extend(judge(&regime, runs, rules, seed));
        rules_seen.get_or_insert_with(|| rules.clone());
    }
    let rules = rules_seen?;
    let mut table = Table::new(&[
        "regime",
        "policy",
        "comparison",
        "routes",
        "Δ (95 % CI)",
        "p (Holm)",
        "MDE (A/A)",
        "outcome",
    ])
    .align(&[0, 1, 2, 7], Align::Left)
    .with_csv(&[
        "regime",
        "policy",
        "against",
        "measure",
        "budget_frames",
        "primary",
        "routes",
        "delta",
        "delta_low",
        "delta_high",
        "p",
        "p_adjusted",
        "mde",
        "mde_frames",
        "margin",
        "outcome",
    ]);
    for j in &judgements {
        let c = &j.comparison;
        let k = c.measure.display_scale();
        let delta = j.delta.map_or("–".into(), |d| {
            format!(
                "{} [{}, {}]",
                short(k * d.estimate),
                short(k * d.low),
                short(k * d.high)
            )
        });
        let within = j
            .delta
            .is_some_and(|d| -j.margin < d.low && d.high < j.margin);
        let p = if j.p.is_finite() {
            let cell = |p: f64| {
                if p == 0.0 {
                    "< 0.001".to_string()
                } else {
                    format!("{p:.3}")
                }
            };
            if j.primary {
                cell(j.p)
            } else {
                format!("{} ({})", cell(j.p), cell(j.p_adjusted))
            }
        } else {
            "–".into()
        };
        table.push(vec![
            if j.regime.is_empty() {
                "–".into()
            } else {
                j.regime.clone()
            },
            j.policy.clone(),
            format!(
                "{}{} at {:.0} frames",
                if j.primary { "**primary**: " } else { "" },
                c.measure.name(),
                c.frames
            ),
            j.routes.to_string(),
            delta,
            p,
            j.mde.map_or("–".into(), |(m, f)| {
                format!("±{} ({f:.0} fr.)", short(k * m))
            }),
            j.outcome.words(k * j.margin, within),
        ]);
        let num = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
        table.push_csv(vec![
            j.regime.clone(),
            j.policy.clone(),
            j.against.clone(),
            c.measure.key().into(),
            c.frames.to_string(),
            j.primary.to_string(),
            j.routes.to_string(),
            num(j.delta.map(|d| d.estimate)),
            num(j.delta.map(|d| d.low)),
            num(j.delta.map(|d| d.high)),
            j.p.to_string(),
            j.p_adjusted.to_string(),
            num(j.mde.map(|m| m.0)),
            num(j.mde.map(|m| m.1)),
            j.margin.to_string(),
            format!("{:?}", j.outcome),
        ]);
    }
    let margins = &rules.margins;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "## The verdict\n\nThe experiment's rules, committed before its runs (`verdict:`): each policy against the fixed-rate curve of its own back end at equal frames, paired per route (each route's curve interpolated in log frames, never extrapolated); Δ = policy − fixed rate, lower is better on every measure. The primary comparison is tested at α = {} for each policy; the secondary ones of every policy of a regime are one family, their p-values (in brackets) corrected by Holm's step-down rule. RMSE, drift and compute: the mean Δ with its 95 % percentile-bootstrap interval over routes and p-value (twice the share of resamples beyond zero); losses, a count: the median Δ with its exact order-statistic interval and the exact sign test. Better or worse when the test rejects Δ = 0; else equivalent when the interval lies within ±ε (RMSE {} m, losses {} per route, drift since the last look {} mm, compute {} ms/m); else cannot decide; too few routes below five reaching the budget on both curves (six for losses: on five no exact 95 % interval of a median exists). MDE: the interval half-width of the nearest A/A pair of the same back end on the same measure. Table: `tables/verdict.csv`.\n\n{}",
        rules.alpha,
        margins.rmse_m,
        margins.losses,
        1000.0 * margins.drift_since_look_m,
        margins.cpu_ms_per_m,
        table.markdown()
    );
    Some((s, table))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holm_matches_its_hand_computed_steps() {
        // Sorted 0.01, 0.02, 0.04, 0.5 over m = 4: 0.04, 0.06, 0.08, 0.5;
        // the running maximum keeps them monotone. NaN stays out.
        let mut p = vec![0.04, 0.5, 0.01, f64::NAN, 0.02];
        holm(&mut p);
        let expected = [0.08, 0.5, 0.04, f64::NAN, 0.06];
        for (got, want) in p.iter().zip(expected) {
            assert!(
                (got - want).abs() < 1e-12 || (got.is_nan() && want.is_nan()),
                "{p:?}"
            );
        }
        // The running maximum: 2 × 0.01 = 0.02 outranks 1 × 0.012.
        let mut q = vec![0.012, 0.01];
        holm(&mut q);
        assert_eq!(q, vec![0.02, 0.02]);
    }
}

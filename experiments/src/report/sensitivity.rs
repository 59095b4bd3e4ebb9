//! The sensitivity of gating's effect to parameters nobody measured: a
//! sweep run one parameter at a time around a base (`one_at_a_time:`),
//! each setting over the same seeds. For every setting and every gated
//! curve: Δ = RMSE(policy) − RMSE(fixed rate of the same back end) at the
//! budgets of [`BUDGETS`], each seed's curves interpolated in log frames
//! (never extrapolated), with the 95 % bootstrap interval over seeds; and
//! per policy one verdict by a rule fixed before any result is read:
//!
//! * it **wins** across the plausible range when, at every budget, every
//!   setting's interval lies below zero;
//! * it **loses** when every interval lies above zero;
//! * otherwise **the simulation cannot decide**, naming the settings whose
//!   intervals lie below zero, above zero, or across it.
//!
//! A setting whose curves reach a budget on fewer than
//! [`MIN_SEEDS_FOR_VERDICT`] seeds (the floor of every verdict in the
//! curves tables) is named and counts for neither side.

use std::fmt::Write as _;

use crate::execute::records::RunRecord;
use crate::report::bootstrap::Interval;
use crate::report::curves::{BUDGETS, Curves, by_setting};
use crate::report::floor::{Floor, floors, nearest};
use crate::report::pairing::at_budget;
use crate::report::table::{Align, Table};
use crate::report::verdict::MIN_SEEDS_FOR_VERDICT;

/// Where an interval lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// Entirely below zero: gating better at equal frames.
    Below,
    /// Entirely above zero: gating worse.
    Above,
    /// Across zero, within ±ε of the experiment's
    /// `equivalence_margin_m`.
    Equivalent,
    /// Across zero.
    Across,
    /// Fewer than [`MIN_SEEDS_FOR_VERDICT`] seeds reach the budget.
    TooFewSeeds,
}

impl Side {
    /// Of an effect's interval over `seeds` seeds in range, with the
    /// equivalence margin ε (m), if the experiment commits one.
    pub fn of(d: Option<&Interval>, seeds: usize, margin: Option<f64>) -> Self {
        match d {
            _ if seeds < MIN_SEEDS_FOR_VERDICT => Self::TooFewSeeds,
            Some(d) if d.high < 0.0 => Self::Below,
            Some(d) if d.low > 0.0 => Self::Above,
            Some(d) if margin.is_some_and(|e| -e < d.low && d.high < e) => Self::Equivalent,
            Some(d) if d.low.is_finite() && d.high.is_finite() => Self::Across,
            _ => Self::TooFewSeeds,
        }
    }

    /// Of `e`.
    pub fn of_effect(e: &Effect) -> Self {
        Self::of(e.difference.as_ref(), e.seeds.0, e.margin)
    }

    fn words(self) -> &'static str {
        match self {
            Self::Below => "below zero (gating better)",
            Self::Above => "above zero (gating worse)",
            Self::Equivalent => "within ±ε (equivalent)",
            Self::Across => "across zero",
            Self::TooFewSeeds => "too few seeds in range",
        }
    }
}

/// One setting, one policy, one budget.
#[derive(Debug, Clone, PartialEq)]
pub struct Effect {
    /// The parameter varied (`defaults` for the base).
    pub parameter: String,
    /// Its value (`–` for the base).
    pub value: String,
    /// The policy's curve.
    pub policy: String,
    /// Frames.
    pub budget: f64,
    /// Seeds whose curves reach the budget, and all seeds.
    pub seeds: (usize, usize),
    /// Mean RMSE of the policy and of the fixed rate at the budget (m).
    pub rmse: Option<(f64, f64)>,
    /// Δ with its interval.
    pub difference: Option<Interval>,
    /// The experiment's equivalence margin ε (m), if any.
    pub margin: Option<f64>,
    /// The minimum detectable effect of the setting's nearest A/A pair of
    /// the same back end (m), if the experiment has one.
    pub mde_m: Option<f64>,
}

impl Effect {
    /// The setting as the report names it.
    pub fn setting(&self) -> String {
        if self.parameter == "defaults" {
            "defaults".into()
        } else {
            format!("{} = {}", self.parameter, self.value)
        }
    }
}

/// The effects of every gated curve under every setting, in setting order
/// (the base first). `None` unless the records are a one-at-a-time sweep
/// (a base setting and at least one other) with curves.
pub fn effects(records: &[RunRecord], seed: u64) -> Option<Vec<Effect>> {
    let groups = by_setting(records);
    if groups.len() < 2 || !groups.iter().any(|(key, _)| key.is_empty()) {
        return None;
    }
    let mut out = Vec::new();
    let base_first = groups
        .iter()
        .filter(|(k, _)| k.is_empty())
        .chain(groups.iter().filter(|(k, _)| !k.is_empty()));
    for (key, runs) in base_first {
        let Some(curves) = Curves::of(runs) else {
            continue;
        };
        let (parameter, value) = match key.split_once('=') {
            Some((p, v)) => (p.to_string(), v.to_string()),
            None => ("defaults".to_string(), "–".to_string()),
        };
        let floors = floors(runs, seed);
        let margin = runs.first().and_then(|r| r.config.equivalence_margin_m);
        for c in curves.curves.iter().filter(|c| !c.fixed_rate) {
            let Some(fixed) = curves.fixed_rate_of(&c.back_end) else {
                continue;
            };
            for b in BUDGETS {
                let r = at_budget(c, Some(fixed), &curves.seeds, b, seed);
                let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
                out.push(Effect {
                    parameter: parameter.clone(),
                    value: value.clone(),
                    policy: c.name.clone(),
                    budget: b,
                    seeds: (r.seeds.len(), curves.seeds.len()),
                    rmse: (!r.rmse.is_empty()).then(|| (mean(&r.rmse), mean(&r.fixed))),
                    difference: r.difference,
                    margin,
                    mde_m: nearest(&floors, &c.back_end, b).map(Floor::mde_m),
                });
            }
        }
    }
    (!out.is_empty()).then_some(out)
}

/// The verdict on `policy` by the rule of the module documentation.
pub fn verdict(effects: &[Effect], policy: &str) -> String {
    let mine: Vec<&Effect> = effects.iter().filter(|e| e.policy == policy).collect();
    let sides: Vec<(Side, &Effect)> = mine.iter().map(|e| (Side::of_effect(e), *e)).collect();
    let counted: Vec<&(Side, &Effect)> = sides
        .iter()
        .filter(|(s, _)| *s != Side::TooFewSeeds)
        .collect();
    let named = |side: Side| -> Vec<String> {
        sides
            .iter()
            .filter(|(s, _)| *s == side)
            .map(|(_, e)| format!("{} at {:.0} frames", e.setting(), e.budget))
            .collect()
    };
    let too_few = named(Side::TooFewSeeds);
    let caveat = if too_few.is_empty() {
        String::new()
    } else {
        format!(
            " (reached on fewer than {MIN_SEEDS_FOR_VERDICT} seeds, so not counted: {})",
            too_few.join("; ")
        )
    };
    let span = |items: &[&(Side, &Effect)]| {
        let d: Vec<&Interval> = items
            .iter()
            .filter_map(|(_, e)| e.difference.as_ref())
            .collect();
        let lo = d.iter().map(|i| i.estimate).fold(f64::INFINITY, f64::min);
        let hi = d
            .iter()
            .map(|i| i.estimate)
            .fold(f64::NEG_INFINITY, f64::max);
        let low = d.iter().map(|i| i.low).fold(f64::INFINITY, f64::min);
        let high = d.iter().map(|i| i.high).fold(f64::NEG_INFINITY, f64::max);
        format!("Δ {lo:+.3} to {hi:+.3} m, every 95 % interval within [{low:+.3}, {high:+.3}] m")
    };
    if counted.is_empty() {
        return format!("the simulation cannot decide: no setting reaches the budgets{caveat}");
    }
    if counted.iter().all(|(s, _)| *s == Side::Below) {
        return format!(
            "gating wins across the plausible range: {}{caveat}",
            span(&counted)
        );
    }
    if counted.iter().all(|(s, _)| *s == Side::Equivalent) {
        return format!(
            "gating is equivalent to the fixed rate across the plausible range (every interval across zero within ±{:.3} m): {}{caveat}",
            mine.first().and_then(|e| e.margin).unwrap_or(f64::NAN),
            span(&counted)
        );
    }
    if counted.iter().all(|(s, _)| *s == Side::Above) {
        return format!(
            "gating loses across the plausible range: {}{caveat}",
            span(&counted)
        );
    }
    let list = |side: Side| {
        let v = named(side);
        if v.is_empty() {
            "none".to_string()
        } else {
            v.join("; ")
        }
    };
    let (below, above) = (named(Side::Below), named(Side::Above));
    let head = if !below.is_empty() && !above.is_empty() {
        "the simulation cannot decide: the sign flips between settings"
    } else {
        "the simulation cannot decide: an interval crosses zero"
    };
    let equivalent = if mine.iter().any(|e| e.margin.is_some()) {
        format!(". Equivalent (within ±ε): {}", list(Side::Equivalent))
    } else {
        String::new()
    };
    format!(
        "{head}. Below zero (gating better): {}. Above zero (gating worse): {}{equivalent}. Across zero: {}{caveat}",
        list(Side::Below),
        list(Side::Above),
        list(Side::Across)
    )
}

/// The section: the table of effects, the verdict per policy, and the
/// table for `tables/sensitivity.csv`. `None` as for [`effects`].
pub fn sensitivity_section(
    records: &[RunRecord],
    seed: u64,
) -> Option<(String, Table, Vec<Effect>)> {
    let effects = effects(records, seed)?;
    let mut table = Table::new(&[
        "setting",
        "policy",
        "frames",
        "seeds in range",
        "policy RMSE [m]",
        "fixed rate [m]",
        "Δ RMSE [m] (95 % CI)",
        "MDE [m]",
        "interval",
    ])
    .align(&[0, 1, 8], Align::Left)
    .with_csv(&[
        "parameter",
        "value",
        "policy",
        "budget_frames",
        "seeds",
        "policy_rmse_m",
        "fixed_rmse_m",
        "difference_m",
        "difference_low_m",
        "difference_high_m",
        "mde_m",
    ]);
    for e in &effects {
        let (p, f) = e.rmse.map_or(("–".into(), "–".into()), |(p, f)| {
            (format!("{p:.3}"), format!("{f:.3}"))
        });
        table.push(vec![
            e.setting(),
            e.policy.clone(),
            format!("{:.0}", e.budget),
            format!("{}/{}", e.seeds.0, e.seeds.1),
            p,
            f,
            e.difference.as_ref().map_or("–".into(), |d| {
                format!("{:+.3} [{:+.3}, {:+.3}]", d.estimate, d.low, d.high)
            }),
            e.mde_m.map_or("–".into(), |m| format!("±{m:.3}")),
            Side::of_effect(e).words().into(),
        ]);
        let d = e.difference;
        table.push_csv(vec![
            e.parameter.clone(),
            e.value.clone(),
            e.policy.clone(),
            e.budget.to_string(),
            e.seeds.0.to_string(),
            e.rmse.map_or(String::new(), |r| r.0.to_string()),
            e.rmse.map_or(String::new(), |r| r.1.to_string()),
            d.map_or(String::new(), |d| d.estimate.to_string()),
            d.map_or(String::new(), |d| d.low.to_string()),
            d.map_or(String::new(), |d| d.high.to_string()),
            e.mde_m.map_or(String::new(), |m| m.to_string()),
        ]);
    }
    let mut policies: Vec<&str> = Vec::new();
    for e in &effects {
        if !policies.contains(&e.policy.as_str()) {
            policies.push(&e.policy);
        }
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "## Sensitivity — does gating win at equal frames across the plausible range?\n\nOne parameter at a time around the defaults, every setting on the same seeds. Δ = RMSE(policy) − RMSE(fixed rate of the same back end), both interpolated in log frames at the budget on each seed (never extrapolated), mean over seeds with a 95 % percentile-bootstrap interval. The verdict follows a rule fixed before the runs: a policy wins if at every budget every setting's interval lies below zero, loses if every one lies above, is equivalent if every one crosses zero within ±ε (the experiment's `equivalence_margin_m`, when it commits one), and otherwise the simulation cannot decide; MDE: the minimum detectable effect of the setting's nearest A/A pair of the same back end; a setting reached on fewer than five seeds counts for neither side. Figure: `plots/sensitivity.svg`; table: `tables/sensitivity.csv`.\n"
    );
    let _ = writeln!(s, "Verdict:\n");
    for p in &policies {
        let _ = writeln!(s, "* **{p}**: {}.", verdict(&effects, p));
    }
    let _ = writeln!(s, "\n{}", table.markdown());
    Some((s, table, effects))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn effect(setting: (&str, &str), budget: f64, d: Option<(f64, f64, f64)>) -> Effect {
        Effect {
            parameter: setting.0.into(),
            value: setting.1.into(),
            policy: "p".into(),
            budget,
            seeds: (20, 20),
            rmse: Some((0.1, 0.1)),
            difference: d.map(|(estimate, low, high)| Interval {
                estimate,
                low,
                high,
                defined: 1.0,
            }),
            margin: None,
            mde_m: None,
        }
    }

    #[test]
    fn equivalence_needs_a_committed_margin_and_every_interval_within_it() {
        let base = ("defaults", "–");
        let shared = ("map_error_share", "1.0");
        let with_margin = |mut e: Effect, margin: f64| {
            e.margin = Some(margin);
            e
        };
        let near_zero = [
            with_margin(effect(base, 500.0, Some((0.001, -0.004, 0.006))), 0.01),
            with_margin(effect(shared, 1000.0, Some((-0.002, -0.008, 0.003))), 0.01),
        ];
        let v = verdict(&near_zero, "p");
        assert!(
            v.starts_with("gating is equivalent to the fixed rate"),
            "{v}"
        );
        assert!(v.contains("±0.010 m"), "{v}");
        // The same intervals without a margin: not decided.
        let unmarked = [
            effect(base, 500.0, Some((0.001, -0.004, 0.006))),
            effect(shared, 1000.0, Some((-0.002, -0.008, 0.003))),
        ];
        assert!(verdict(&unmarked, "p").contains("an interval crosses zero"));
        // One interval wider than the margin: not decided, and named.
        let wide = [
            with_margin(effect(base, 500.0, Some((0.001, -0.004, 0.006))), 0.005),
            with_margin(effect(shared, 1000.0, Some((-0.002, -0.008, 0.003))), 0.005),
        ];
        let v = verdict(&wide, "p");
        assert!(v.contains("an interval crosses zero"), "{v}");
        assert!(v.contains("Equivalent (within ±ε): none"), "{v}");
        // An interval below zero stays "below", margin or not.
        let below = with_margin(effect(base, 500.0, Some((-0.002, -0.003, -0.001))), 0.01);
        assert_eq!(Side::of_effect(&below), Side::Below);
    }

    #[test]
    fn the_verdict_follows_the_rule() {
        let base = ("defaults", "–");
        let shared = ("map_error_share", "1.0");
        let wins = [
            effect(base, 500.0, Some((-0.02, -0.03, -0.01))),
            effect(shared, 1000.0, Some((-0.01, -0.02, -0.001))),
        ];
        let v = verdict(&wins, "p");
        assert!(
            v.starts_with("gating wins across the plausible range: Δ -0.020 to -0.010 m"),
            "{v}"
        );
        let loses = [effect(base, 500.0, Some((0.02, 0.01, 0.03)))];
        assert!(verdict(&loses, "p").starts_with("gating loses"));
        let flips = [
            effect(base, 500.0, Some((-0.02, -0.03, -0.01))),
            effect(shared, 500.0, Some((0.02, 0.01, 0.03))),
        ];
        let v = verdict(&flips, "p");
        assert!(v.contains("the sign flips"), "{v}");
        assert!(
            v.contains("Above zero (gating worse): map_error_share = 1.0 at 500 frames"),
            "{v}"
        );
        let across = [
            effect(base, 500.0, Some((-0.02, -0.03, -0.01))),
            effect(shared, 500.0, Some((0.0, -0.01, 0.01))),
            effect(("camera", "838"), 1000.0, None),
        ];
        let v = verdict(&across, "p");
        assert!(v.contains("an interval crosses zero"), "{v}");
        assert!(
            v.contains("not counted: camera = 838 at 1000 frames"),
            "{v}"
        );
    }
}

//! The comparison's floor: what a paired Δ RMSE over seeds can resolve.
//! Its A/A control is a fixed rate against itself at a phase
//! ([`ExperimentConfig::phase_pairs`](crate::config::ExperimentConfig::phase_pairs)):
//! as many frames of the same stream on the same route, terrain, odometry
//! and regressor, none in common. Whatever separates the two is what any
//! Δ at equal frames carries when frame choice does nothing.
//!
//! For each pair over the seeds of one setting: Δ = RMSE(shifted) −
//! RMSE(unshifted) with its 95 % percentile-bootstrap interval; the
//! **minimum detectable effect** (MDE), the interval's half-width, the
//! smallest Δ the comparison can tell from nothing at this many routes;
//! the routes a 5 mm MDE would need (the half-width shrinks as 1/√routes);
//! and how alike the two schedules err along each route (the correlation
//! of their position errors and their shared second moment, recorded per
//! run).

use std::fmt::Write as _;

use crate::execute::records::{RunRecord, SchemeMetrics};
use crate::report::aggregate::Stat;
use crate::report::bootstrap::{Interval, RESAMPLES, bootstrap, mean_at};
use crate::report::curves::by_setting;
use crate::report::table::{Align, Table};

/// The MDE the routes-needed column aims at (m).
pub const TARGET_MDE_M: f64 = 0.005;

/// One A/A pair over the seeds of a setting.
#[derive(Debug, Clone, PartialEq)]
pub struct Floor {
    /// The back end both schemes share.
    pub back_end: String,
    /// The fixed rate's label.
    pub unshifted: String,
    /// The same rate at a phase.
    pub shifted: String,
    /// Mean frames of the unshifted scheme.
    pub frames: f64,
    /// Mean RMSE of the unshifted scheme (m).
    pub rmse_m: f64,
    /// Seeds on which both ran.
    pub seeds: usize,
    /// Mean Δ = shifted − unshifted (m) and its interval.
    pub delta: Interval,
    /// Standard deviation of Δ over the seeds (m).
    pub sd_m: f64,
    /// Mean correlation and shared share of the two position errors over
    /// the seeds, when the records carry them.
    pub agreement: Option<(f64, f64)>,
}

impl Floor {
    /// The minimum detectable effect (m): the half-width of Δ's interval.
    pub fn mde_m(&self) -> f64 {
        0.5 * (self.delta.high - self.delta.low)
    }

    /// The routes a `mde_m` would need, from this MDE at these seeds.
    pub fn routes_for(&self, mde_m: f64) -> f64 {
        (self.seeds as f64 * (self.mde_m() / mde_m).powi(2)).ceil()
    }
}

/// The metrics of the schemes `unshifted` and `shifted` of one run on its
/// first traverse, when both ran there.
pub fn pair_on_first_traverse<'a>(
    r: &'a RunRecord,
    unshifted: &str,
    shifted: &str,
) -> Option<(&'a SchemeMetrics, &'a SchemeMetrics)> {
    let traverse = r.metrics.schemes.first()?.traverse.as_str();
    let find = |label: &str| {
        r.metrics
            .schemes
            .iter()
            .find(|m| m.label == label && m.traverse == traverse)
    };
    Some((find(unshifted)?, find(shifted)?))
}

/// Every A/A pair of `records` (runs of one setting, one per seed).
pub fn floors(records: &[&RunRecord], seed: u64) -> Vec<Floor> {
    let Some(first) = records.first() else {
        return Vec::new();
    };
    let config = &first.config;
    let mut out = Vec::new();
    for (u, s) in config.phase_pairs() {
        let (unshifted, shifted) = (&config.schemes[u].label, &config.schemes[s].label);
        let mut pairs = Vec::new();
        let mut agreement = Vec::new();
        for r in records {
            let Some(traverse) = r.metrics.schemes.first().map(|m| m.traverse.as_str()) else {
                continue;
            };
            if let Some((a, b)) = pair_on_first_traverse(r, unshifted, shifted) {
                pairs.push((a.frames as f64, a.rmse_m, b.rmse_m - a.rmse_m));
            }
            if let Some(e) = r.metrics.shared_errors.iter().find(|e| {
                &e.unshifted == unshifted && &e.shifted == shifted && e.traverse == traverse
            }) {
                agreement.push((e.agreement.correlation, e.agreement.shared_share));
            }
        }
        let n = pairs.len();
        let deltas: Vec<f64> = pairs.iter().map(|p| p.2).collect();
        let Some(delta) = bootstrap(n, seed, |ix| Some(mean_at(&deltas, ix))) else {
            continue;
        };
        let mean_of = |values: Vec<f64>| Stat::of(&values).map_or(f64::NAN, |s| s.mean);
        out.push(Floor {
            back_end: config.schemes[u].back_end(config),
            unshifted: unshifted.clone(),
            shifted: shifted.clone(),
            frames: mean_of(pairs.iter().map(|p| p.0).collect()),
            rmse_m: mean_of(pairs.iter().map(|p| p.1).collect()),
            seeds: n,
            delta,
            sd_m: Stat::of(&deltas).map_or(f64::NAN, |s| s.std),
            agreement: (agreement.len() == n).then(|| {
                (
                    mean_of(agreement.iter().map(|a| a.0).collect()),
                    mean_of(agreement.iter().map(|a| a.1).collect()),
                )
            }),
        });
    }
    out
}

/// The floor of `back_end` nearest `frames` (in log frames), if any.
pub fn nearest<'a>(floors: &'a [Floor], back_end: &str, frames: f64) -> Option<&'a Floor> {
    floors
        .iter()
        .filter(|f| f.back_end == back_end && f.mde_m().is_finite())
        .min_by(|a, b| {
            let d = |f: &Floor| (f.frames.ln() - frames.ln()).abs();
            d(a).total_cmp(&d(b))
        })
}

/// The MDE cell of a Δ: the nearest floor's MDE and the frames it was
/// measured at, or a dash.
pub fn mde_cell(floors: &[Floor], back_end: &str, frames: f64) -> String {
    nearest(floors, back_end, frames).map_or("–".into(), |f| {
        format!("±{:.3} (A/A at {:.0} frames)", f.mde_m(), f.frames)
    })
}

/// The section over `records` (every setting), `None` without A/A pairs.
pub fn floor_section(records: &[RunRecord], seed: u64) -> Option<(String, Table)> {
    let groups = by_setting(records);
    let many = groups.len() > 1;
    let mut table = Table::new(&[
        "setting",
        "A/A pair",
        "back end",
        "frames",
        "RMSE [m]",
        "Δ [m] (95 % CI)",
        "σ of Δ per route [m]",
        "MDE [m]",
        "routes for a 5 mm MDE",
        "error correlation",
        "shared share",
    ])
    .align(&[0, 1, 2], Align::Left)
    .with_csv(&[
        "setting",
        "unshifted",
        "shifted",
        "back_end",
        "seeds",
        "frames_mean",
        "rmse_mean_m",
        "delta_mean_m",
        "delta_low_m",
        "delta_high_m",
        "delta_sd_m",
        "mde_m",
        "routes_for_5mm",
        "error_correlation_mean",
        "shared_share_mean",
    ]);
    for (setting, runs) in &groups {
        for f in floors(runs, seed) {
            let (corr, share) = f.agreement.unwrap_or((f64::NAN, f64::NAN));
            let cell = |v: f64| {
                if v.is_finite() {
                    format!("{v:.2}")
                } else {
                    "–".into()
                }
            };
            table.push(vec![
                if many { setting.clone() } else { "–".into() },
                format!("{} / {}", f.unshifted, f.shifted),
                f.back_end.clone(),
                format!("{:.0}", f.frames),
                format!("{:.3}", f.rmse_m),
                format!(
                    "{:+.4} [{:+.4}, {:+.4}]",
                    f.delta.estimate, f.delta.low, f.delta.high
                ),
                format!("{:.4}", f.sd_m),
                format!("±{:.4}", f.mde_m()),
                format!("{:.0}", f.routes_for(TARGET_MDE_M)),
                cell(corr),
                cell(share),
            ]);
            table.push_csv(vec![
                setting.clone(),
                f.unshifted.clone(),
                f.shifted.clone(),
                f.back_end.clone(),
                f.seeds.to_string(),
                f.frames.to_string(),
                f.rmse_m.to_string(),
                f.delta.estimate.to_string(),
                f.delta.low.to_string(),
                f.delta.high.to_string(),
                f.sd_m.to_string(),
                f.mde_m().to_string(),
                f.routes_for(TARGET_MDE_M).to_string(),
                corr.to_string(),
                share.to_string(),
            ]);
        }
    }
    if table.is_empty() {
        return None;
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "## The comparison's floor (A/A)\n\nEach fixed rate against itself at a phase: as many frames of the same stream, none in common, on the same routes, odometry and regressor. Δ = RMSE(shifted) − RMSE(unshifted), mean over seeds with a 95 % percentile-bootstrap interval ({RESAMPLES} resamples). Its half-width is the minimum detectable effect (MDE): a Δ between schemes of this back end and frame count must exceed it to be told from frame choice that does nothing. The routes for a 5 mm MDE scale the seeds by (MDE / 5 mm)². Error correlation: Pearson's over every sample and axis of the two position errors along each route; shared share: 2 Σ e_a·e_b / Σ (|e_a|² + |e_b|²), the part of the error's second moment the two schedules have in common; both averaged over routes. Table: `tables/floor.csv`.\n\n{}",
        table.markdown()
    );
    Some((s, table))
}

//! Table (d) of the curves section: each oracle curve against the fixed
//! rate of its back end at equal frames, on the measure the oracle
//! minimises ([`gpodo_frontends::oracle::OracleObjective`]): the
//! root-mean-square or the largest drift since the last look. The oracle
//! plans for exact looks, so on the real tracker it may lose on its own
//! measure too; the table says whether it does.

use gpodo_frontends::oracle::OracleObjective;
use gpodo_frontends::rover_measures::RoverMeasures;

use crate::report::curves::{BUDGETS, Curves};
use crate::report::pairing::at_budget;
use crate::report::table::{Align, Table};
use crate::report::verdict::verdict;

/// The measure a run reports for an objective, and its name.
fn measure(objective: OracleObjective) -> (fn(&RoverMeasures) -> f64, &'static str) {
    match objective {
        OracleObjective::SquaredDrift => (
            |m| m.drift_since_look_rms_m,
            "RMS drift since the last look",
        ),
        OracleObjective::MaxDrift => (
            |m| m.drift_since_look_max_m,
            "largest drift since the last look",
        ),
    }
}

/// Table (d) over `curves`; empty when no curve is an oracle's.
pub fn oracle_table(curves: &Curves, seed: u64, margin: Option<f64>) -> Table {
    let mut table = Table::new(&[
        "curve",
        "measure it minimises",
        "frames",
        "seeds in range",
        "oracle [mm]",
        "fixed rate, same back end [mm]",
        "Δ [mm] (95 % CI)",
        "oracle vs fixed rate",
    ])
    .align(&[1, 7], Align::Left)
    .with_csv(&[
        "curve",
        "measure",
        "budget_frames",
        "seeds",
        "oracle_mean_m",
        "fixed_mean_m",
        "difference_mean_m",
        "difference_low_m",
        "difference_high_m",
    ]);
    for c in &curves.curves {
        let objectives: Vec<OracleObjective> = c
            .selectors
            .iter()
            .filter_map(|s| s.oracle().map(|p| p.objective))
            .collect();
        let Some(&objective) = objectives.first() else {
            continue;
        };
        if objectives.len() != c.selectors.len() || objectives.iter().any(|o| *o != objective) {
            continue;
        }
        let Some(fixed) = curves.fixed_rate_of(&c.back_end) else {
            continue;
        };
        let (f, name) = measure(objective);
        let (oracle, fixed) = (c.with_measure(f), fixed.with_measure(f));
        for b in BUDGETS {
            let r = at_budget(&oracle, Some(&fixed), &curves.seeds, b, seed);
            let (Some(m), Some(d)) = (r.rmse_mean, r.difference) else {
                continue;
            };
            let fixed_mean = r.fixed.iter().sum::<f64>() / r.fixed.len() as f64;
            table.push(vec![
                c.name.clone(),
                name.into(),
                format!("{b:.0}"),
                format!("{}/{}", r.seeds.len(), curves.seeds.len()),
                format!("{:.1}", 1e3 * m.estimate),
                format!("{:.1}", 1e3 * fixed_mean),
                format!(
                    "{:+.1} [{:+.1}, {:+.1}]",
                    1e3 * d.estimate,
                    1e3 * d.low,
                    1e3 * d.high
                ),
                verdict(&d, r.seeds.len(), margin),
            ]);
            table.push_csv(vec![
                c.name.clone(),
                name.into(),
                b.to_string(),
                r.seeds.len().to_string(),
                m.estimate.to_string(),
                fixed_mean.to_string(),
                d.estimate.to_string(),
                d.low.to_string(),
                d.high.to_string(),
            ]);
        }
    }
    table
}

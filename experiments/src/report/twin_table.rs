//! Table (c) of the curves section: what the regressor contributes, each
//! curve against the same policy with the same knob values on zero
//! residuals (the parametric model alone) and the same prior, paired per
//! seed at equal frames.

use crate::report::curves::{BUDGETS, Curves};
use crate::report::pairing::at_budget;
use crate::report::pairing::push_pairs;
use crate::report::table::{Align, Table};
use crate::report::verdict::verdict;

/// Table (c): each curve against its zero-residual twin at equal frames;
/// each seed's pair goes into `paired`.
pub fn twin_table(curves: &Curves, seed: u64, paired: &mut Table, margin: Option<f64>) -> Table {
    let mut twin = Table::new(&[
        "curve",
        "zero-residual twin",
        "frames",
        "seeds in range",
        "RMSE [m]",
        "twin RMSE [m]",
        "Δ RMSE [m] (95 % CI)",
        "regressor vs zero residuals",
    ])
    .align(&[1, 7], Align::Left)
    .with_csv(&[
        "curve",
        "twin",
        "budget_frames",
        "seeds",
        "rmse_mean_m",
        "twin_mean_m",
        "difference_mean_m",
        "difference_low_m",
        "difference_high_m",
    ]);
    for c in &curves.curves {
        let Some(z) = curves.zero_twin_of(c) else {
            continue;
        };
        for b in BUDGETS {
            let r = at_budget(c, Some(z), &curves.seeds, b, seed);
            let (Some(m), Some(d)) = (r.rmse_mean, r.difference) else {
                continue;
            };
            let twin_mean = r.fixed.iter().sum::<f64>() / r.fixed.len() as f64;
            twin.push(vec![
                c.name.clone(),
                z.name.clone(),
                format!("{b:.0}"),
                format!("{}/{}", r.seeds.len(), curves.seeds.len()),
                format!("{:.3}", m.estimate),
                format!("{twin_mean:.3}"),
                format!("{:+.3} [{:+.3}, {:+.3}]", d.estimate, d.low, d.high),
                verdict(&d, r.seeds.len(), margin),
            ]);
            twin.push_csv(vec![
                c.name.clone(),
                z.name.clone(),
                b.to_string(),
                r.seeds.len().to_string(),
                m.estimate.to_string(),
                twin_mean.to_string(),
                d.estimate.to_string(),
                d.low.to_string(),
                d.high.to_string(),
            ]);
            push_pairs(paired, &c.name, &z.name, b, &r);
        }
    }
    twin
}

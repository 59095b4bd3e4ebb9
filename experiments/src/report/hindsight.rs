//! The "Hindsight search" section of a single run's report: for each
//! oracle refined over the real tracker, where it started, what it found,
//! and what it bounds (only the scheme it starts from, at that scheme's
//! frame count, on this seed).

use std::fmt::Write as _;

use crate::execute::results::ExperimentResults;
use crate::report::table::{Align, Table};

/// What each hindsight search did and what it bounds; empty without one.
pub fn hindsight_section(s: &mut String, r: &ExperimentResults) {
    let rows: Vec<_> = r
        .schemes
        .iter()
        .filter_map(|x| {
            let search = x.oracle.as_ref()?.search.as_ref()?;
            let spec = r.config.schemes.iter().find(|p| p.label == x.label)?;
            let matched = spec.selector.oracle()?.same_as.clone();
            Some((x, search, matched))
        })
        .collect();
    if rows.is_empty() {
        return;
    }
    let mut t = Table::new(&[
        "Scheme",
        "started from",
        "start RMSE [m] (matched scheme's frames; surrogate plan)",
        "RMSE found [m] (its draws; fresh draws)",
        "front-end runs",
        "moves accepted",
        "bounds",
    ])
    .align(&[1, 6], Align::Left);
    for (x, search, matched) in rows {
        t.push(vec![
            x.label.clone(),
            search.started_from.clone(),
            search
                .start_rmse_m
                .iter()
                .map(|v| format!("{v:.3}"))
                .collect::<Vec<_>>()
                .join("; "),
            match search.fresh_draws_rmse_m {
                Some(fresh) => format!("{:.3}; {fresh:.3}", search.rmse_m),
                None => format!("{:.3}", search.rmse_m),
            },
            search.evaluations.to_string(),
            search.accepted.to_string(),
            matched.map_or("no causal scheme (no `same_as`)".into(), |m| {
                format!("`{m}` at its {} frames, this seed", x.run.frames)
            }),
        ]);
    }
    let _ = writeln!(
        s,
        "## Hindsight search\n\nA local search over the real tracker (it sees the ground truth and this seed's tracker outcomes): from the better of the matched scheme's own frames and a surrogate dynamic programme's plan, each move a full front-end run, kept only when the RMSE falls. So on the tracker draws it searched it is never worse than the scheme it starts from, at that scheme's frame count, on this seed; part of that gain is luck with those draws, so the schedule found is re-run on an independent set of draws, and that run is its row in Table II. It is not the optimum and bounds no other policy.\n\n{}",
        t.markdown()
    );
}

//! The verdict end to end: a sweep whose file commits its rules records
//! them with every run, and its report's verdict table holds, for each
//! comparison, the paired Δ recomputed here from the recorded runs (each
//! route's curves interpolated in log frames), the exact sign test for
//! the count, Holm's correction over the secondary comparisons, and the
//! outcome the rules give.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::process::Command;

const GPODO: &str = env!("CARGO_BIN_EXE_gpodo");

/// Six short routes; a fixed-rate curve, a gated curve and an A/A pair on
/// the parametric back end.
const SWEEP: &str = "name: verdict
dataset: { kind: simulated, preset: exoter-prl, seed: 1, training_runs: 1, training_run_secs: 60, test_max_secs: 120 }
regressors:
  - kind: zero
schemes:
  - { curve: fixed, label: fixed 0.25, selector: { kind: fixed_rate, fps: 0.25 } }
  - { curve: fixed, label: fixed 0.5, selector: { kind: fixed_rate, fps: 0.5 } }
  - { curve: fixed, label: fixed 1, selector: { kind: fixed_rate, fps: 1.0 } }
  - { curve: gated, label: gated 1e-2, selector: { kind: uncertainty_budget, budget_m2: 1.0e-2 } }
  - { curve: gated, label: gated 1e-3, selector: { kind: uncertainty_budget, budget_m2: 1.0e-3 } }
  - { curve: gated, label: gated 1e-4, selector: { kind: uncertainty_budget, budget_m2: 1.0e-4 } }
  - { curve: gated, label: gated 1e-5, selector: { kind: uncertainty_budget, budget_m2: 1.0e-5 } }
  - { curve: gated, label: gated 1e-6, selector: { kind: uncertainty_budget, budget_m2: 1.0e-6 } }
  - { label: fixed 0.5 at 1 s, selector: { kind: fixed_rate, fps: 0.5, phase_secs: 1.0 } }
verdict:
  policies: [gated]
  primary: { measure: rmse, frames: 60 }
  secondary:
    - { measure: losses, frames: 60 }
    - { measure: drift_since_look, frames: 60 }
    - { measure: cpu_per_metre, frames: 60 }
  margins: { rmse_m: 0.01, losses: 0.5, drift_since_look_m: 0.002, cpu_ms_per_m: 17.0 }
seeds: [1, 2, 3, 4, 5, 6]
";

/// `y` at `x` on `points`, linear in ln x between the two around it.
fn at_log(points: &[(f64, f64)], x: f64) -> Option<f64> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let Some(&(_, y)) = p.iter().find(|q| q.0 == x) {
        return Some(y);
    }
    p.windows(2).find_map(|w| {
        (w[0].0 < x && x < w[1].0).then(|| {
            let t = (x.ln() - w[0].0.ln()) / (w[1].0.ln() - w[0].0.ln());
            w[0].1 + t * (w[1].1 - w[0].1)
        })
    })
}

/// The two-sided exact sign test, from binomial coefficients.
fn sign_p(d: &[f64]) -> f64 {
    let pos = d.iter().filter(|&&v| v > 0.0).count() as u64;
    let neg = d.iter().filter(|&&v| v < 0.0).count() as u64;
    let n = pos + neg;
    if n == 0 {
        return 1.0;
    }
    let choose = |k: u64| (0..k).fold(1.0, |a, i| a * (n - i) as f64 / (i + 1) as f64);
    let tail: f64 = (0..=pos.min(neg)).map(choose).sum::<f64>() / 2f64.powi(n as i32);
    (2.0 * tail).min(1.0)
}

#[test]
fn the_verdict_table_follows_the_committed_rules() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("verdict.yaml"), SWEEP).unwrap();
    let out = Command::new(GPODO)
        .args(["-q", "run", "verdict.yaml", "--out", "r"])
        .current_dir(d)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // Per route and measure: (policy, fixed rate) at 60 frames.
    let measures = ["rmse", "losses", "drift_since_look", "cpu_per_metre"];
    let mut differences: Vec<Vec<f64>> = vec![Vec::new(); measures.len()];
    for line in std::fs::read_to_string(d.join("r/runs.jsonl"))
        .unwrap()
        .lines()
    {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        assert!(v["config"]["verdict"].is_object(), "the rules are recorded");
        let schemes = v["metrics"]["schemes"].as_array().unwrap();
        let curve = |labels: &[&str], m: usize| -> Vec<(f64, f64)> {
            labels
                .iter()
                .map(|l| {
                    let s = schemes.iter().find(|s| s["label"] == *l).unwrap();
                    let y = match m {
                        0 => s["rmse_m"].as_f64().unwrap(),
                        1 => s["tracking_losses"].as_f64().unwrap(),
                        2 => s["rover"]["drift_since_look_p95_m"].as_f64().unwrap(),
                        _ => s["rover"]["cpu_ms_per_m"].as_f64().unwrap(),
                    };
                    (s["frames"].as_f64().unwrap(), y)
                })
                .collect()
        };
        for (m, diffs) in differences.iter_mut().enumerate() {
            let gated = at_log(
                &curve(
                    &[
                        "gated 1e-2",
                        "gated 1e-3",
                        "gated 1e-4",
                        "gated 1e-5",
                        "gated 1e-6",
                    ],
                    m,
                ),
                60.0,
            );
            let fixed = at_log(&curve(&["fixed 0.25", "fixed 0.5", "fixed 1"], m), 60.0);
            if let (Some(g), Some(f)) = (gated, fixed) {
                diffs.push(g - f);
            }
        }
    }

    let csv = std::fs::read_to_string(d.join("r/tables/verdict.csv")).unwrap();
    let mut reader = csv::Reader::from_reader(csv.as_bytes());
    let rows: Vec<csv::StringRecord> = reader.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 4, "{csv}");
    let field = |r: &csv::StringRecord, i: usize| r.get(i).unwrap().to_string();
    let num = |r: &csv::StringRecord, i: usize| field(r, i).parse::<f64>().unwrap();
    // Columns: regime, policy, against, measure, budget, primary, routes,
    // delta, low, high, p, p_adjusted, mde, mde_frames, margin, outcome.
    let mut secondary_p = Vec::new();
    for (row, (m, diffs)) in rows.iter().zip(measures.iter().zip(&differences)) {
        assert_eq!(field(row, 3), *m);
        assert_eq!(field(row, 2), "fixed");
        assert_eq!(num(row, 6) as usize, diffs.len(), "{m}");
        assert!(diffs.len() >= 5, "{m}: {diffs:?}");
        let estimate = if *m == "losses" {
            let mut s = diffs.clone();
            s.sort_by(f64::total_cmp);
            let n = s.len();
            if n % 2 == 1 {
                s[n / 2]
            } else {
                0.5 * (s[n / 2 - 1] + s[n / 2])
            }
        } else {
            diffs.iter().sum::<f64>() / diffs.len() as f64
        };
        assert!(
            (num(row, 7) - estimate).abs() < 1e-9,
            "{m}: {row:?} {estimate}"
        );
        if *m == "losses" {
            assert!((num(row, 10) - sign_p(diffs)).abs() < 1e-12, "{row:?}");
        }
        let (low, high, p_adj, margin) = (num(row, 8), num(row, 9), num(row, 11), num(row, 14));
        assert!(
            low <= estimate + 1e-12 && estimate <= high + 1e-12,
            "{row:?}"
        );
        let expected = if p_adj < 0.05 {
            if estimate < 0.0 { "Better" } else { "Worse" }
        } else if -margin < low && high < margin {
            "Equivalent"
        } else {
            "CannotDecide"
        };
        assert_eq!(field(row, 15), expected, "{row:?}");
        if field(row, 5) == "false" {
            secondary_p.push((num(row, 10), p_adj));
        } else {
            assert_eq!(num(row, 10), p_adj, "the primary is not corrected");
        }
        // The A/A pair's MDE stands beside every comparison.
        assert!(num(row, 12).is_finite() && num(row, 12) >= 0.0, "{row:?}");
    }
    // Holm over the three secondary comparisons.
    let mut sorted = secondary_p.clone();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut running: f64 = 0.0;
    for (rank, (p, adjusted)) in sorted.iter().enumerate() {
        running = running.max(((3 - rank) as f64 * p).min(1.0));
        assert!((adjusted - running).abs() < 1e-12, "{secondary_p:?}");
    }
    let summary = std::fs::read_to_string(d.join("r/report.md")).unwrap();
    assert!(summary.contains("## The verdict"), "{summary}");
}

//! The comparison's floor end to end: a sweep with a fixed rate and the
//! same rate at a phase records, per run, how alike the two err, and its
//! report's floor table gives the mean Δ of the recorded RMSEs, the MDE
//! as the half-width of Δ's interval and the routes a 5 mm MDE needs.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::process::Command;

const GPODO: &str = env!("CARGO_BIN_EXE_gpodo");

/// Six short routes; a fixed rate at two phases on the parametric back
/// end, and a gated scheme.
const SWEEP: &str = "name: aa
dataset: { kind: simulated, preset: exoter-prl, seed: 1, training_runs: 1, training_run_secs: 60, test_max_secs: 120 }
regressors:
  - kind: zero
schemes:
  - label: fixed
    selector: { kind: fixed_rate, fps: 0.5 }
  - label: fixed at phase 1 s
    selector: { kind: fixed_rate, fps: 0.5, phase_secs: 1.0 }
  - label: gated
    selector: { kind: uncertainty_budget, budget_m2: 1.0e-4 }
equivalence_margin_m: 0.01
seeds: [1, 2, 3, 4, 5, 6]
";

#[test]
fn the_floor_table_matches_the_recorded_runs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("aa.yaml"), SWEEP).unwrap();
    let out = Command::new(GPODO)
        .args(["-q", "run", "aa.yaml", "--out", "r"])
        .current_dir(d)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // Δ per route from the records, and the recorded agreement.
    let mut deltas = Vec::new();
    for line in std::fs::read_to_string(d.join("r/runs.jsonl"))
        .unwrap()
        .lines()
    {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        let schemes = v["metrics"]["schemes"].as_array().unwrap();
        let rmse = |label: &str| {
            schemes.iter().find(|s| s["label"] == label).unwrap()["rmse_m"]
                .as_f64()
                .unwrap()
        };
        let frames = |label: &str| {
            schemes.iter().find(|s| s["label"] == label).unwrap()["frames"]
                .as_u64()
                .unwrap()
        };
        // As many frames, to one.
        assert!(frames("fixed").abs_diff(frames("fixed at phase 1 s")) <= 1);
        deltas.push(rmse("fixed at phase 1 s") - rmse("fixed"));
        let shared = v["metrics"]["shared_errors"].as_array().unwrap();
        assert_eq!(shared.len(), 1, "{shared:?}");
        assert_eq!(shared[0]["unshifted"], "fixed");
        let agreement = &shared[0]["agreement"];
        let (r, s) = (
            agreement["correlation"].as_f64().unwrap(),
            agreement["shared_share"].as_f64().unwrap(),
        );
        assert!(
            (-1.0..=1.0).contains(&r) && (-1.0..=1.0).contains(&s),
            "{r} {s}"
        );
        // Two estimates of one route from the same odometry err alike.
        assert!(s > 0.0, "{s}");
        // Every scheme carries the rover measures.
        for scheme in schemes {
            let rover = &scheme["rover"];
            assert!(
                rover["drift_since_look_max_m"].as_f64().unwrap()
                    >= rover["drift_since_look_p95_m"].as_f64().unwrap()
            );
            assert!(rover["rpe_1m_m"].as_f64().unwrap() > 0.0);
            assert!(rover["cpu_ms_per_m"].as_f64().unwrap() > 0.0);
        }
    }
    assert_eq!(deltas.len(), 6);
    let mean = deltas.iter().sum::<f64>() / 6.0;
    let sd = (deltas.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 5.0).sqrt();

    let mut csv = csv::Reader::from_path(d.join("r/tables/floor.csv")).unwrap();
    let header = csv.headers().unwrap().clone();
    let rows: Vec<csv::StringRecord> = csv.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 1, "one A/A pair: {rows:?}");
    let col = |name: &str| -> f64 {
        let i = header.iter().position(|h| h == name).unwrap();
        rows[0][i].parse().unwrap()
    };
    assert_eq!(&rows[0][3], "parametric only, odometry prior");
    assert!((col("delta_mean_m") - mean).abs() < 1e-12);
    assert!((col("delta_sd_m") - sd).abs() < 1e-12);
    let (low, high) = (col("delta_low_m"), col("delta_high_m"));
    assert!(low <= mean && mean <= high);
    assert!((col("mde_m") - 0.5 * (high - low)).abs() < 1e-15);
    let routes = (6.0 * (col("mde_m") / 0.005).powi(2)).ceil();
    assert_eq!(col("routes_for_5mm"), routes);
    let summary = std::fs::read_to_string(d.join("r/report.md")).unwrap();
    assert!(
        summary.contains("## The comparison's floor (A/A)"),
        "{summary}"
    );
}

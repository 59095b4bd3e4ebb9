//! The `gpodo` binary end to end: simulate → CSV logs → experiment on those
//! logs gives exactly the numbers of the experiment on the simulator itself;
//! a run writes its report and metrics; a bad config names file and line.

// Tests panic on failure by design.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;
use std::process::Command;

const GPODO: &str = env!("CARGO_BIN_EXE_gpodo");

fn gpodo(args: &[&str], cwd: &Path) -> std::process::Output {
    Command::new(GPODO)
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap()
}

fn write(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap();
}

fn metrics(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn experiment_on_written_logs_matches_the_simulated_experiment() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sim = gpodo(
        &[
            "-q",
            "simulate",
            "--seed",
            "3",
            "--out",
            "logs",
            "--training-runs",
            "1",
            "--training-run-secs",
            "120",
        ],
        d,
    );
    assert!(
        sim.status.success(),
        "{}",
        String::from_utf8_lossy(&sim.stderr)
    );
    assert!(d.join("logs/train_01.csv").exists() && d.join("logs/test.camera.csv").exists());

    // The CLI's test traverse is the preset's whole 42 m traverse; the config
    // below simulates the same seed and lengths in memory.
    write(
        &d.join("simulated.yaml"),
        "name: sim\ndataset: {kind: simulated, preset: exoter-prl, seed: 3, training_runs: 1, training_run_secs: 120}\nregressors:\n  - kind: zero\n",
    );
    write(
        &d.join("logs.yaml"),
        "name: logs\ndataset: {kind: logs, train: [logs/train_01.csv], test: [logs/test.csv]}\nregressors:\n  - kind: zero\n",
    );
    for file in ["simulated.yaml", "logs.yaml"] {
        let out = gpodo(&["-q", "run", file], d);
        assert!(
            out.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let a = metrics(&d.join("results/sim/metrics.json"));
    let b = metrics(&d.join("results/logs/metrics.json"));
    // Everything but the fit's wall-clock time must be identical.
    assert_eq!(
        a["regressors"][0]["evaluation"], b["regressors"][0]["evaluation"],
        "CSV round trip changed the results"
    );
    assert_eq!(a["dead_reckoning"], b["dead_reckoning"]);
    let report = std::fs::read_to_string(d.join("results/sim/report.md")).unwrap();
    assert!(
        report.contains("Table I") && report.contains("parametric only"),
        "{report}"
    );
    let rmse = a["regressors"][0]["evaluation"]["pooled"]["rmse"]
        .as_f64()
        .unwrap();
    assert!(
        rmse > 1e-4 && rmse < 0.05,
        "implausible baseline RMSE {rmse}"
    );
    assert!(d.join("results/sim/residuals_test.csv").exists());
}

#[test]
fn residual_table_experiment_reads_back_the_residual_csv() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut csv = String::from("a,b,y1,y2\n");
    for i in 0..20 {
        let x = i as f64 * 0.1;
        csv.push_str(&format!("{x},{},{},{}\n", x * x, 0.01 * x, -0.02));
    }
    write(&d.join("table.csv"), &csv);
    write(
        &d.join("t.yaml"),
        "name: table\ndataset: {kind: residual_table, path: table.csv, targets: [y1, y2], train_fraction: 0.75}\nregressors:\n  - kind: zero\n",
    );
    let out = gpodo(&["-q", "run", "t.yaml", "--out", "out"], d);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let m = metrics(&d.join("out/metrics.json"));
    assert_eq!(m["dataset"]["n_train"], 15);
    assert_eq!(m["dataset"]["n_test"], 5);
    // Zero predictor: MAE of y2 is exactly 0.02.
    let mae = m["regressors"][0]["evaluation"]["per_output"][1]["mae"]
        .as_f64()
        .unwrap();
    assert!((mae - 0.02).abs() < 1e-15, "{mae}");
}

#[test]
fn malformed_config_is_reported_with_file_and_line_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        &d.join("bad.yaml"),
        "name: bad\ndataset: {kind: simulated, preset: exoter-prl, seed: 1}\nregressors:\n  - kind: zero\n    varience: 1.0\n",
    );
    let out = gpodo(&["run", "bad.yaml"], d);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.yaml") && err.contains("varience"),
        "{err}"
    );
    assert!(
        err.contains("5:") || err.contains("line 5"),
        "no line number: {err}"
    );
    assert!(!d.join("results").exists());

    write(
        &d.join("missing.yaml"),
        "name: m\ndataset: {kind: logs, train: [nope.csv], test: [nope.csv]}\nregressors:\n  - kind: zero\n",
    );
    let out = gpodo(&["run", "missing.yaml"], d);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("nope.csv"), "{err}");
}

#[test]
fn bench_writes_ratios_to_the_exact_gp_row_and_rejects_a_bad_baseline() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut csv = String::from("a,b,y1,y2\n");
    for i in 0..150 {
        let x = i as f64 * 0.05;
        let noise = ((i * 37 % 11) as f64 - 5.0) * 0.002;
        csv.push_str(&format!(
            "{x},{},{},{}\n",
            (0.7 * x).cos(),
            (1.3 * x).sin() * 0.01 + noise,
            0.002 * x - noise
        ));
    }
    write(&d.join("table.csv"), &csv);
    write(
        &d.join("b.yaml"),
        "name: b\ndataset: {kind: residual_table, path: table.csv, targets: [y1, y2], train_fraction: 0.8}\nregressors:\n  - kind: zero\n  - kind: exact_gp\n    hyperopt: {max_iters: 20}\n  - kind: sparse_gp\n    inducing: {count: 15}\n    hyperopt: {max_iters: 20}\nbench: {predict_queries: 7, learning_curve_every: 40}\n",
    );
    let out = gpodo(&["-q", "bench", "b.yaml"], d);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let b = metrics(&d.join("results/b/bench.json"));
    assert_eq!(b["baseline"], 1);
    let rows = b["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[1]["predict_latency"]["count"], 7);
    assert!(rows.iter().all(|r| r["online"].is_null()));
    let report = std::fs::read_to_string(d.join("results/b/bench.md")).unwrap();
    // The baseline's own row has ratio 1 and speed-up 1.
    let exact_line = report
        .lines()
        .find(|l| l.starts_with("| exact GP"))
        .unwrap();
    assert!(
        exact_line.contains("| 1.0× |") && exact_line.contains("| 1.000 |"),
        "{exact_line}"
    );

    write(
        &d.join("bad.yaml"),
        "name: b\ndataset: {kind: residual_table, path: table.csv, targets: [y1, y2], train_fraction: 0.8}\nregressors:\n  - kind: zero\nbench: {baseline: 3}\n",
    );
    let out = gpodo(&["bench", "bad.yaml"], d);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.yaml") && err.contains("bench.baseline"),
        "{err}"
    );
}

#[test]
fn a_run_piped_to_a_file_logs_without_colour_codes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A warning (a reference table that is missing) and the info lines.
    write(
        &d.join("piped.yaml"),
        "name: piped\ndataset: {kind: simulated, preset: exoter-prl, seed: 3, training_runs: 1, training_run_secs: 60, test_max_secs: 30}\nregressors:\n  - kind: zero\ncompare_with: {path: missing.csv, targets: [a]}\n",
    );
    let out = Command::new(GPODO)
        .args(["run", "piped.yaml"])
        .current_dir(d)
        .env_remove("NO_COLOR")
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{log}");
    assert!(log.contains("WARN") && log.contains("INFO"), "{log}");
    assert!(
        !log.contains('\u{1b}'),
        "escape codes in a piped log: {log:?}"
    );
}

#[test]
fn a_residual_table_report_gives_its_own_units_no_empty_columns_and_the_counts_used() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A yaw-rate target (rad/s) and no wheels: no statistic of wheel
    // speed, slip or attitude applies.
    let mut csv = String::from("speed,steer,unplugged,yaw_rate_error\n");
    for i in 0..80 {
        let x = i as f64 * 0.1;
        csv.push_str(&format!("{x},{},0,{}\n", x.cos(), 0.01 * x.sin()));
    }
    write(&d.join("yaw.csv"), &csv);
    write(
        &d.join("yaw.yaml"),
        "name: yaw\ndataset: {kind: residual_table, path: yaw.csv, targets: [yaw_rate_error], train_fraction: 0.75}\nregressors:\n  - kind: zero\n  - kind: sparse_gp\n    inducing: {count: 1000000000}\n    hyperopt: {max_iters: 5}\n",
    );
    let out = gpodo(&["-q", "run", "yaw.yaml"], d);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = std::fs::read_to_string(d.join("results/yaw/report.md")).unwrap();
    let section = report
        .split("## Residual statistics")
        .nth(1)
        .unwrap()
        .split("\n## ")
        .next()
        .unwrap();
    assert!(section.contains("the table's target units"), "{section}");
    assert!(
        !section.contains("mm/s") && !section.contains("wheel"),
        "{section}"
    );
    assert!(
        section.contains("| rows | n | mean abs | p95 abs |\n"),
        "{section}"
    );
    assert!(
        !section
            .lines()
            .filter(|l| l.starts_with("| train") || l.starts_with("| test"))
            .any(|l| l.contains('–')),
        "{section}"
    );
    // The fits' times say what they are.
    assert!(report.contains("fit wall [s]") && report.contains("CPU time:"));
    // A constant input is named as such, not as a short lengthscale.
    let hyper = report
        .split("## Learned hyperparameters")
        .nth(1)
        .unwrap()
        .split("\n## ")
        .next()
        .unwrap();
    assert!(
        hyper.contains("left out of the shortest lengthscales: unplugged."),
        "{hyper}"
    );
    let sparse_row = hyper
        .lines()
        .find(|l| l.starts_with("| sparse GP"))
        .unwrap();
    assert!(!sparse_row.contains("unplugged"), "{sparse_row}");
    // A count the rows cannot give is said, with the count used.
    assert!(
        report.contains("used 60 inducing points, one per training row, not the 1000000000 asked"),
        "{report}"
    );
    // Table I's label shows the count used.
    let table_one = report.split("## Table I").nth(1).unwrap();
    assert!(
        table_one.contains("| sparse GP (VFE, m=60 of 1000000000 asked): rbf"),
        "{table_one}"
    );
}

//! A sweep with an external regressor that fails in one run: that run is
//! recorded as failed with the plugin's reason, the other is recorded, the
//! command exits non-zero naming the failure, and `--resume` runs only the
//! failed run again. Needs a `python3` with NumPy (`GPODO_PYTHON`); skipped
//! with a message without one, unless `GPODO_REQUIRE_PYTHON` is set (CI).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

mod common;

use common::{gpodo_on, python};

fn records(dir: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(dir.join("runs.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[test]
fn a_failed_external_run_is_recorded_the_others_go_on_and_resume_reruns_only_it() {
    let Some(python) = python() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let plugin = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../regressors/tests/plugins/misbehaving.py")
        .canonicalize()
        .unwrap();
    let (good, bad) = (tmp.path().join("absent"), tmp.path().join("present"));
    std::fs::write(&bad, "").unwrap();
    let yaml = format!(
        "name: flaky
dataset: {{ kind: simulated, preset: exoter-prl, seed: 1, training_runs: 1, training_run_secs: 60, test_max_secs: 90 }}
regressors:
  - kind: zero
  - kind: external
    command: [{python}, {plugin}, fail_if_marker]
    label: flaky plugin
    marker: {good}
sweep:
  regressors[1].marker: [{good}, {bad}]
",
        plugin = plugin.display(),
        good = good.display(),
        bad = bad.display()
    );
    let file = tmp.path().join("flaky.yaml");
    std::fs::write(&file, yaml).unwrap();
    let out_dir = tmp.path().join("out");
    let run = |extra: &[&str]| gpodo_on("run", &file, &out_dir, extra);

    let first = run(&[]);
    let stderr = String::from_utf8_lossy(&first.stderr);
    assert!(
        !first.status.success(),
        "a failed run must fail the command"
    );
    assert!(stderr.contains("1 of 2 run(s) failed"), "{stderr}");
    assert!(stderr.contains("--resume"), "{stderr}");
    let recs = records(&out_dir);
    assert_eq!(recs.len(), 2, "{recs:?}");
    let failed: Vec<&serde_json::Value> =
        recs.iter().filter(|r| r["failure"].is_string()).collect();
    assert_eq!(failed.len(), 1);
    let reason = failed[0]["failure"].as_str().unwrap();
    assert!(
        reason.contains("flaky plugin") && reason.contains("request `fit`"),
        "{reason}"
    );
    assert!(
        reason.contains("exists"),
        "the plugin's own message: {reason}"
    );
    let failed_key = failed[0]["key"].as_str().unwrap().to_string();
    let report = std::fs::read_to_string(out_dir.join("report.md")).unwrap();
    assert!(report.contains("1 run(s) failed"), "{report}");

    // Fixed: only the failed run runs again.
    std::fs::remove_file(&bad).unwrap();
    let second = run(&["--resume"]);
    assert!(
        second.status.success(),
        "{}",
        String::from_utf8_lossy(&second.stderr)
    );
    let stdout = String::from_utf8_lossy(&second.stdout);
    assert!(
        stdout.contains("1 run(s) done") && stdout.contains("1 skipped"),
        "{stdout}"
    );
    let recs = records(&out_dir);
    assert_eq!(recs.len(), 3);
    let successes: Vec<&str> = recs
        .iter()
        .filter(|r| r["failure"].is_null())
        .map(|r| r["key"].as_str().unwrap())
        .collect();
    assert_eq!(successes.len(), 2);
    assert!(successes.contains(&failed_key.as_str()));
    let report = std::fs::read_to_string(out_dir.join("report.md")).unwrap();
    assert!(!report.contains("failed**"), "{report}");
    assert!(!report.contains("more than once"), "{report}");
}

#[test]
fn a_crashing_plugin_fails_its_own_bench_row_only() {
    let Some(python) = python() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let plugin = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../regressors/tests/plugins/misbehaving.py")
        .canonicalize()
        .unwrap();
    let yaml = format!(
        "name: crashing
dataset: {{ kind: simulated, preset: exoter-prl, seed: 1, training_runs: 1, training_run_secs: 60, test_max_secs: 60 }}
regressors:
  - kind: zero
  - kind: external
    command: [{python}, {plugin}, crash_on_fit]
  - kind: ilgr
bench: {{ predict_queries: 5, learning_curve_every: 30 }}
",
        plugin = plugin.display()
    );
    let file = tmp.path().join("crashing.yaml");
    std::fs::write(&file, yaml).unwrap();
    let out_dir = tmp.path().join("out");
    let out = gpodo_on("bench", &file, &out_dir, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("1 regressor(s) failed"), "{stderr}");
    assert!(stderr.contains("about to crash on purpose"), "{stderr}");
    let md = std::fs::read_to_string(out_dir.join("bench.md")).unwrap();
    assert!(
        md.contains("**Failed**") && md.contains("external: misbehaving.py"),
        "{md}"
    );
    assert!(
        md.contains("| ILGR") && md.contains("| parametric only"),
        "{md}"
    );
}

#[test]
fn an_external_plugin_learns_online_in_a_gated_scheme() {
    let Some(python) = python() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let ridge = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../plugins/python/examples/ridge.py")
        .canonicalize()
        .unwrap();
    let yaml = format!(
        "name: online-plugin
dataset: {{ kind: simulated, preset: exoter-prl, seed: 1, training_runs: 1, training_run_secs: 60, test_max_secs: 90 }}
regressors:
  - kind: zero
schemes:
  - label: ridge online
    online: {{ regressor: {{ kind: external, command: [{python}, {ridge}], alpha: 10.0 }} }}
    selector: {{ kind: fixed_rate, fps: 1.0 }}
",
        ridge = ridge.display()
    );
    let file = tmp.path().join("online.yaml");
    std::fs::write(&file, yaml).unwrap();
    let out_dir = tmp.path().join("out");
    let out = gpodo_on("run", &file, &out_dir, &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let record = &records(&out_dir)[0];
    let scheme = &record["metrics"]["schemes"][0];
    assert_eq!(scheme["label"], "ridge online");
    assert!(
        scheme["online_targets"].as_u64().unwrap() > 10,
        "the plugin learned from VO: {scheme}"
    );
}

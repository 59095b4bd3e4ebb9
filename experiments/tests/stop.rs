//! A stop (Ctrl-C) asked for while a sweep runs: fits end at their next
//! iteration, and no run that had not finished is recorded, not even as
//! failed. Its own test binary: the stop is process-wide.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_experiments::plan::load_plan;
use gpodo_experiments::runner::{RunOptions, RunnerError, run_sweep};

#[test]
fn a_stopped_sweep_records_nothing_unfinished() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("stop.yaml");
    std::fs::write(
        &file,
        "name: stop
dataset: { kind: simulated, preset: exoter-prl, seed: 3, training_runs: 1, training_run_secs: 60, test_max_secs: 60 }
residuals: { window_secs: 1.0 }
regressors:
  - kind: exact_gp
    kernel: rbf
seeds: [1, 2]
",
    )
    .unwrap();
    let plan = load_plan(&file).unwrap();
    let options = RunOptions {
        out: Some(dir.path().join("out")),
        resume: false,
        force: false,
        shard: None,
        slurm_task: None,
        quiet: true,
    };
    gpodo_experiments::util::stop::request();
    let err = run_sweep(&plan, &options).unwrap_err();
    assert!(matches!(err, RunnerError::Stopped), "{err}");
    assert!(err.to_string().contains("--resume"), "{err}");
    let records =
        std::fs::read_to_string(dir.path().join("out").join("runs.jsonl")).unwrap_or_default();
    assert!(records.trim().is_empty(), "{records}");
}

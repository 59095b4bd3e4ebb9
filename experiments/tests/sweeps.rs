//! Sweeps end to end with the `gpodo` binary: N shards run as separate
//! processes record exactly the runs (and the same metrics, byte for byte)
//! as the unsharded sweep; a partly run sweep resumes where it stopped and
//! refuses to overwrite without `--resume` or `--force`; the report merges
//! shards and names missing and duplicate runs (and fails while any is);
//! a Slurm task resubmitted alone runs its own shard of the recorded count;
//! `gpodo plan` lists the runs.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Output};

const GPODO: &str = env!("CARGO_BIN_EXE_gpodo");

/// Four short runs: two drift budgets × two seeds, a zero and an ILGR
/// regressor, a fixed-rate and a gated scheme.
const SWEEP: &str = "name: tiny
dataset: { kind: simulated, preset: exoter-prl, seed: 1, training_runs: 1, training_run_secs: 60, test_max_secs: 90 }
regressors:
  - kind: zero
  - kind: ilgr
schemes:
  - label: fixed
    selector: { kind: fixed_rate, fps: 1.0 }
  - label: gated
    regressor: 1
    selector: { kind: uncertainty_budget, budget_m2: 1.0e-4 }
sweep:
  schemes[1].selector.budget_m2: [1.0e-4, 3.0e-4]
seeds: [1, 2]
";

fn gpodo(args: &[&str], cwd: &Path, threads: Option<&str>) -> Output {
    let mut cmd = Command::new(GPODO);
    cmd.args(args)
        .current_dir(cwd)
        .env_remove("SLURM_ARRAY_TASK_ID");
    if let Some(t) = threads {
        cmd.env("RAYON_NUM_THREADS", t);
    }
    cmd.output().unwrap()
}

fn ok(out: &Output) {
    assert!(
        out.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// key → metrics (serialised), over every record file of a folder.
fn metrics_by_key(dir: &Path) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if !(name.starts_with("runs") && name.ends_with(".jsonl")) {
            continue;
        }
        for line in std::fs::read_to_string(&path).unwrap().lines() {
            let v: serde_json::Value = serde_json::from_str(line).unwrap();
            let key = v["key"].as_str().unwrap().to_string();
            let previous = out.insert(key.clone(), v["metrics"].to_string());
            assert!(previous.is_none(), "{key} recorded twice");
        }
    }
    out
}

#[test]
fn shards_as_separate_processes_reproduce_the_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("tiny.yaml"), SWEEP).unwrap();
    let plan = gpodo(&["plan", "tiny.yaml"], d, None);
    ok(&plan);
    let listing = String::from_utf8_lossy(&plan.stdout);
    assert!(listing.contains("4 run(s)"), "{listing}");
    assert!(
        listing.contains("schemes[1].selector.budget_m2=0.0003, seed=2"),
        "{listing}"
    );

    ok(&gpodo(
        &["-q", "run", "tiny.yaml", "--out", "whole"],
        d,
        None,
    ));
    let whole = metrics_by_key(&d.join("whole"));
    assert_eq!(whole.len(), 4);
    assert!(d.join("whole/report.md").is_file());
    assert!(d.join("whole/tables/table2.csv").is_file());

    // Three shards, one of them on a single thread.
    let children: Vec<_> = (0..3)
        .map(|i| {
            let shard = format!("{i}/3");
            let mut cmd = Command::new(GPODO);
            cmd.args([
                "-q",
                "run",
                "tiny.yaml",
                "--out",
                "sharded",
                "--shard",
                &shard,
            ])
            .current_dir(d);
            if i == 1 {
                cmd.env("RAYON_NUM_THREADS", "1");
            }
            cmd.stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for child in children {
        ok(&child.wait_with_output().unwrap());
    }
    for i in 0..3 {
        assert!(d.join(format!("sharded/runs.{i}.jsonl")).is_file());
    }
    let sharded = metrics_by_key(&d.join("sharded"));
    assert_eq!(
        sharded, whole,
        "sharded runs differ from the unsharded sweep"
    );
    let report = gpodo(&["report", "sharded"], d, None);
    ok(&report);
    let text = String::from_utf8_lossy(&report.stdout);
    assert!(text.contains("4 runs, 0 missing, 0 duplicated"), "{text}");
}

#[test]
fn a_stopped_sweep_resumes_and_the_report_names_gaps_and_duplicates() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("tiny.yaml"), SWEEP).unwrap();
    // As if killed after half the runs: only shard 0 of 2 recorded, into
    // the sweep's own record file.
    ok(&gpodo(
        &["-q", "run", "tiny.yaml", "--out", "r", "--shard", "0/2"],
        d,
        None,
    ));
    std::fs::rename(d.join("r/runs.0.jsonl"), d.join("r/runs.jsonl")).unwrap();
    let partial = metrics_by_key(&d.join("r"));
    assert_eq!(partial.len(), 2);
    // The report is written, and says by its exit status that runs are
    // missing.
    let report = gpodo(&["report", "r"], d, None);
    assert!(!report.status.success());
    assert!(String::from_utf8_lossy(&report.stdout).contains("2 missing"));
    assert!(String::from_utf8_lossy(&report.stderr).contains("2 planned run(s) missing"));
    assert!(
        std::fs::read_to_string(d.join("r/report.md"))
            .unwrap()
            .contains("Incomplete: 2 planned run(s)")
    );
    // Without --resume nothing is overwritten.
    let refused = gpodo(&["-q", "run", "tiny.yaml", "--out", "r"], d, None);
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--resume"));
    assert_eq!(metrics_by_key(&d.join("r")), partial);
    // Resuming runs only the two missing runs.
    let resumed = gpodo(
        &["-q", "run", "tiny.yaml", "--out", "r", "--resume"],
        d,
        None,
    );
    ok(&resumed);
    let stdout = String::from_utf8_lossy(&resumed.stdout);
    assert!(
        stdout.starts_with("2 run(s) done") && stdout.contains("2 skipped"),
        "{stdout}"
    );
    let all = metrics_by_key(&d.join("r"));
    assert_eq!(all.len(), 4);
    for (k, m) in &partial {
        assert_eq!(&all[k], m);
    }
    // A record copied into a second file is a duplicate.
    let first = std::fs::read_to_string(d.join("r/runs.jsonl")).unwrap();
    std::fs::write(d.join("r/runs.7.jsonl"), first.lines().next().unwrap()).unwrap();
    let report = gpodo(&["report", "r"], d, None);
    assert!(!report.status.success());
    assert!(String::from_utf8_lossy(&report.stdout).contains("0 missing, 1 duplicated"));
}

#[test]
fn the_same_config_gives_byte_identical_metrics() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let single = SWEEP.replace("seeds: [1, 2]\n", "").replace(
        "sweep:\n  schemes[1].selector.budget_m2: [1.0e-4, 3.0e-4]\n",
        "",
    );
    std::fs::write(d.join("one.yaml"), single).unwrap();
    ok(&gpodo(
        &["-q", "run", "one.yaml", "--out", "a"],
        d,
        Some("2"),
    ));
    ok(&gpodo(
        &["-q", "run", "one.yaml", "--out", "b"],
        d,
        Some("1"),
    ));
    assert_eq!(metrics_by_key(&d.join("a")), metrics_by_key(&d.join("b")));
    // A single run writes the full report and its figures.
    assert!(d.join("a/report.md").is_file() && d.join("a/metrics.json").is_file());
    assert!(d.join("a/plots").is_dir() && d.join("a/trajectories").is_dir());
    assert!(d.join("a/summary.md").is_file());
}

/// `gpodo run` as Slurm array task `task` of an array of `array_size`.
fn slurm_task(d: &Path, task: &str, array_size: &str, extra: &[&str]) -> Output {
    let mut args = vec!["-q", "run", "tiny.yaml", "--out", "s"];
    args.extend_from_slice(extra);
    Command::new(GPODO)
        .args(&args)
        .current_dir(d)
        .env("SLURM_ARRAY_TASK_ID", task)
        .env("SLURM_ARRAY_TASK_COUNT", array_size)
        .output()
        .unwrap()
}

#[test]
fn a_slurm_task_resubmitted_alone_runs_exactly_its_shard_of_the_recorded_count() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("tiny.yaml"), SWEEP).unwrap();
    // Without --shard, the first task of a fresh folder cannot know N.
    let unknown = slurm_task(d, "0", "2", &[]);
    assert!(!unknown.status.success());
    assert!(String::from_utf8_lossy(&unknown.stderr).contains("--shard 0/N"));
    // Task 0 of an array of 2, as sweep.sbatch starts it.
    ok(&slurm_task(d, "0", "2", &["--shard", "0/2"]));
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("s/plan.json")).unwrap()).unwrap();
    assert_eq!(plan["shards"], 2);
    // Task 1 lost and resubmitted alone (`--array=1`: an array of 1):
    // shard 1 of the recorded 2, exactly the two runs shard 0 left.
    let resubmitted = slurm_task(d, "1", "1", &[]);
    ok(&resubmitted);
    let stdout = String::from_utf8_lossy(&resubmitted.stdout);
    assert!(
        stdout.starts_with("2 run(s) done") && stdout.contains("2 left to other shards"),
        "{stdout}"
    );
    assert!(d.join("s/runs.1.jsonl").is_file());
    assert_eq!(metrics_by_key(&d.join("s")).len(), 4);
    ok(&gpodo(&["report", "s"], d, None));
    // A shard count that changes is refused, and nothing is run.
    let changed = gpodo(
        &[
            "-q",
            "run",
            "tiny.yaml",
            "--out",
            "s",
            "--shard",
            "0/3",
            "--resume",
        ],
        d,
        None,
    );
    assert!(!changed.status.success());
    assert!(String::from_utf8_lossy(&changed.stderr).contains("started as 2 shards"));
    assert_eq!(metrics_by_key(&d.join("s")).len(), 4);
}

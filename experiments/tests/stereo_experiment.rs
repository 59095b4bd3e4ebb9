//! `frontend.vo: {kind: stereo}` through `gpodo run`: Table II's fixed
//! rates on a short simulated test traverse, tracked by the stereo VO on
//! the rendered camera's images, and on the same camera recorded in bags
//! (`dataset: {kind: bags}` with a topic map's `camera:`); a dataset
//! without a camera refused with the field named.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use common::{assert_succeeded, gpodo_on};

const EXPERIMENT: &str = "\
name: stereo-smoke
dataset:
  kind: simulated
  preset: exoter-prl
  seed: 7
  training_runs: 1
  training_run_secs: 60
  test_max_secs: 16
motion_model:
  kind: weighted_jacobian
residuals:
  window_secs: 1.0
regressors:
  - kind: zero
frontend:
  vo: { kind: stereo }
schemes:
  - label: ORB-SLAM 2.5 fps
    selector: { kind: fixed_rate, fps: 2.5 }
  - label: ORB-SLAM 0.5 fps
    selector: { kind: fixed_rate, fps: 0.5 }
";

/// The run in `out` processed 16 s at 2.5 and 0.5 fps without a loss,
/// each scheme's RMSE under 5 cm.
fn assert_both_rates_tracked(out: &std::path::Path) {
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    let schemes = metrics["schemes"].as_array().unwrap();
    assert_eq!(schemes.len(), 2);
    let frames: Vec<u64> = schemes
        .iter()
        .map(|s| s["run"]["frames"].as_u64().unwrap())
        .collect();
    assert!(frames[0] >= 38 && frames[1] >= 7, "{frames:?}");
    for s in schemes {
        assert_eq!(
            s["run"]["tracking_losses"].as_u64(),
            Some(0),
            "{}",
            s["label"]
        );
        let rmse = s["run"]["metrics"]["rmse_m"].as_f64().unwrap_or(f64::NAN);
        eprintln!(
            "{}: {} frames, RMSE {rmse:.4} m",
            s["label"], s["run"]["frames"]
        );
        assert!(
            rmse.is_finite() && rmse < 0.05,
            "{}: RMSE {rmse}",
            s["label"]
        );
    }
}

/// `gpodo run` of `file` into `out` on `threads` threads.
fn run_on_threads(file: &std::path::Path, out: &std::path::Path, threads: &str) {
    let run = std::process::Command::new(common::GPODO)
        .args(["--quiet", "run"])
        .arg(file)
        .arg("--out")
        .arg(out)
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .unwrap();
    assert_succeeded(&run, "gpodo run: ");
}

#[test]
fn the_stereo_vo_tracks_the_fixed_rates_on_the_rendered_camera() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("stereo.yaml");
    std::fs::write(&file, EXPERIMENT).unwrap();
    let out = dir.path().join("out");
    run_on_threads(&file, &out, "2");
    assert_both_rates_tracked(&out);
    let config = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(config.contains("ORB-SLAM 0.5 fps"));
    // The same numbers on one thread: every frame rendered once whichever
    // scheme asks first, each scheme's keyframe ratio its own.
    let one = dir.path().join("one");
    run_on_threads(&file, &one, "1");
    let schemes = |dir: &std::path::Path| {
        let metrics: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap())
                .unwrap();
        metrics["schemes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["run"].clone())
            .collect::<Vec<_>>()
    };
    assert_eq!(schemes(&out), schemes(&one));
}

#[test]
fn a_dataset_without_a_camera_is_refused_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let logs = dir.path().join("logs");
    let sim = std::process::Command::new(common::GPODO)
        .args(["-q", "simulate", "--out"])
        .arg(&logs)
        .args([
            "--training-runs",
            "1",
            "--training-run-secs",
            "30",
            "--test-max-secs",
            "10",
        ])
        .output()
        .unwrap();
    assert_succeeded(&sim, "gpodo simulate: ");
    let text = EXPERIMENT.replace(
        "dataset:\n  kind: simulated\n  preset: exoter-prl\n  seed: 7\n  training_runs: 1\n  training_run_secs: 60\n  test_max_secs: 16\n",
        "dataset: {kind: logs, train: [logs/train_01.csv], test: [logs/test.csv]}\n",
    );
    let file = dir.path().join("stereo.yaml");
    std::fs::write(&file, text).unwrap();
    let out = gpodo_on("run", &file, &dir.path().join("out"), &[]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("frontend.vo.kind"), "{stderr}");
}

#[test]
fn the_stereo_vo_tracks_a_recorded_camera_through_a_bags_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let bags = dir.path().join("bags");
    let sim = std::process::Command::new(common::GPODO)
        .args(["-q", "simulate", "--format", "mcap", "--camera", "--out"])
        .arg(&bags)
        .args([
            "--training-runs",
            "1",
            "--training-run-secs",
            "30",
            "--test-max-secs",
            "16",
        ])
        .output()
        .unwrap();
    assert_succeeded(&sim, "gpodo simulate: ");
    let topics = std::fs::read_to_string(bags.join("topics.yaml")).unwrap();
    assert!(topics.contains("/camera/left/image_raw"), "{topics}");
    let indented: String = topics.lines().map(|l| format!("    {l}\n")).collect();
    let text = EXPERIMENT.replace(
        "dataset:\n  kind: simulated\n  preset: exoter-prl\n  seed: 7\n  training_runs: 1\n  training_run_secs: 60\n  test_max_secs: 16\n",
        &format!(
            "dataset:\n  kind: bags\n  train: [bags/train_01.mcap]\n  test: [bags/test.mcap]\n  topics:\n{indented}"
        ),
    );
    let file = dir.path().join("stereo.yaml");
    std::fs::write(&file, text).unwrap();
    let out = dir.path().join("out");
    assert_succeeded(&gpodo_on("run", &file, &out, &[]), "gpodo run: ");
    assert_both_rates_tracked(&out);
}

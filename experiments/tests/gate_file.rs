//! The gate file of `gpodo live --gate`: the shipped example loads, and
//! bad files are refused naming line, column and what was expected.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use gpodo_experiments::error::ConfigError;
use gpodo_experiments::plan::gate::load_gate;
use gpodo_frontends::SelectorSpec;

fn write(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("gate.yaml");
    std::fs::write(&path, text).unwrap();
    path
}

/// The error's line, column, path and message.
fn located(e: ConfigError) -> (usize, usize, String, String) {
    let message = e.to_string();
    match e {
        ConfigError::Located {
            line, column, path, ..
        } => (line, column, path, message),
        other => panic!("not located: {other}"),
    }
}

#[test]
fn the_tutorials_gate_file_loads_with_its_defaults() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/tutorials/gate.yaml");
    let gate = load_gate(&file).unwrap();
    assert!(matches!(gate.selector, SelectorSpec::MaxGap { .. }));
    assert!(gate.online.is_some());
    assert_eq!(gate.lost_frame_period_secs, Some(0.4));
    assert_eq!(gate.topics.vo_odometry, "/vo/pose");
    assert_eq!(gate.topics.gated_prefix, "/gated");
    assert_eq!(gate.lost.status_topic, None);
    assert_eq!(gate.targets.min_interval_secs, 4.0);
    assert_eq!(gate.checkpoint.every_secs, 30.0);
}

#[test]
fn offline_only_policies_are_refused_by_name_and_place() {
    let dir = tempfile::tempdir().unwrap();
    let oracle = "# gate\nselector:\n  kind: max_gap\n  inner: { kind: oracle, frames: 500 }\n";
    let (line, column, path, message) = located(load_gate(&write(dir.path(), oracle)).unwrap_err());
    assert_eq!((line, path.as_str()), (3, "selector"), "{message}");
    assert!(column >= 1);
    assert!(message.contains("cannot gate a live camera"), "{message}");
    assert!(message.contains("ground truth"), "{message}");
    let front = "selector: { kind: front_loaded, early_fps: 2.5, early_secs: 60, same_as: x }\n";
    let (_, _, _, message) = located(load_gate(&write(dir.path(), front)).unwrap_err());
    assert!(message.contains("another scheme's run"), "{message}");
}

#[test]
fn bad_values_and_unknown_fields_are_located() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "selector: { kind: fixed_rate, fps: 0.5 }\npairing: { tolerance_secs: -0.01 }\n",
            2,
            "pairing.tolerance_secs",
            "exact",
        ),
        (
            "selector: { kind: fixed_rate, fps: 0.5 }\nlost:\n  silent_secs: 1.0\n  covarience_at_least: 9999\n",
            4,
            "lost",
            "covariance_at_least",
        ),
        (
            "selector: { kind: fixed_rate, fps: 0.5 }\ntargets: { min_interval_secs: 4, max_interval_secs: 2 }\n",
            2,
            "targets.max_interval_secs",
            "min_interval_secs",
        ),
        (
            "selector: { kind: fixed_rate, fps: 0.5 }\nonline: { regressor: { kind: ilgr }, refit_every: 5, batch_secs: 30 }\n",
            2,
            "online.batch_secs",
            "not both",
        ),
        (
            "selector: { kind: uncertainty_budget, budget_m2: -1 }\n",
            1,
            "selector.budget_m2",
            "positive",
        ),
    ];
    for (text, want_line, want_path, want_words) in cases {
        let (line, _, path, message) = located(load_gate(&write(dir.path(), text)).unwrap_err());
        assert_eq!(line, want_line, "{message}");
        assert!(path.starts_with(want_path), "{path}: {message}");
        assert!(message.contains(want_words), "{message}");
    }
}

#[test]
fn the_tutorials_gate_file_builds_the_gate_and_a_learner_that_resumes_its_checkpoint() {
    use gpodo_experiments::commands::gate::build_gate;
    use gpodo_frontends::vo_target::VoTarget;
    use gpodo_node::learner::LearnerStart;
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/tutorials/gate.yaml");
    let gate = load_gate(&file).unwrap();
    let rover = b"a rover description";
    let columns = ["cmd_v".to_string(), "pitch".to_string()];
    let built = build_gate(&gate, rover, None, None, &columns).unwrap();
    assert_eq!(built.pairing.tolerance_ns, 0);
    assert_eq!(built.pairing.history_depth, 10);
    assert!(
        built.gate.policy().contains("while_lost"),
        "{}",
        built.gate.policy()
    );
    let mut learner = built.learner.unwrap();
    assert_eq!(learner.start(), LearnerStart::Empty);
    for i in 0..8 {
        learner
            .learn(&VoTarget {
                inputs: vec![0.1 * f64::from(i), 0.0],
                residual: nalgebra::Vector3::new(0.004, 0.0, 0.0),
                time_secs: 4.0 * f64::from(i + 1),
                duration_secs: 4.0,
            })
            .unwrap();
    }
    let dir = tempfile::tempdir().unwrap();
    let checkpoint = dir.path().join("gate-model.json");
    assert!(learner.checkpoint(&checkpoint).unwrap());
    let resumed = build_gate(&gate, rover, None, Some(&checkpoint), &columns)
        .unwrap()
        .learner
        .unwrap();
    assert_eq!(resumed.start(), LearnerStart::Checkpoint(8));
    assert_eq!(
        resumed.predict(&[0.3, 0.0]).unwrap(),
        learner.predict(&[0.3, 0.0]).unwrap()
    );
    let Err(e) = build_gate(&gate, b"another rover", None, Some(&checkpoint), &columns) else {
        panic!("a checkpoint of another rover resumed");
    };
    assert!(format!("{e:#}").contains("rover_sha256"), "{e:#}");
}

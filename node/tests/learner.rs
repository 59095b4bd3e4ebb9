//! The live learner: the prior until it learns, a checkpoint resumed to
//! the same predictions as a learner that never stopped, and checkpoints
//! of another rover refused.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_frontends::online::OnlineMode;
use gpodo_frontends::vo_target::VoTarget;
use gpodo_node::checkpoint::{CheckpointError, sha256_hex};
use gpodo_node::learner::{LearnerIdentity, LearnerStart, LiveLearner};
use gpodo_regressors::RegressorSpec;
use nalgebra::Vector3;

mod common;

use common::{fresh_learner, learner_identity, learner_target as target};

fn identity(rover: &[u8]) -> LearnerIdentity {
    learner_identity(sha256_hex(rover))
}

fn fresh() -> LiveLearner {
    fresh_learner(identity(b"rover"))
}

#[test]
fn it_predicts_the_prior_until_it_has_learned() {
    let mut learner = fresh();
    let before = learner.predict(&[0.2, 0.5]).unwrap();
    assert_eq!(before.mean, Vector3::zeros());
    assert_eq!(before.variance, Vector3::repeat(1e-4));
    for i in 0..30 {
        learner.learn(&target(i)).unwrap();
    }
    let after = learner.predict(&[0.2, 0.5]).unwrap();
    assert!((after.mean.x - 0.002).abs() < 1e-3, "{after:?}");
    assert!(after.variance.x < 1e-4, "{after:?}");
    assert_eq!(learner.targets_learned(), 30);
}

#[test]
fn a_resumed_checkpoint_predicts_as_a_learner_that_never_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("learner.json");
    let mut uninterrupted = fresh();
    let mut stopped = fresh();
    // Nothing is written before anything is learned.
    assert!(!stopped.checkpoint(&path).unwrap());
    for i in 0..35 {
        uninterrupted.learn(&target(i)).unwrap();
        stopped.learn(&target(i)).unwrap();
    }
    assert!(stopped.checkpoint(&path).unwrap());
    drop(stopped);
    let mut resumed =
        LiveLearner::resume(&path, OnlineMode::Update, 1e-4, identity(b"rover"), "ilgr").unwrap();
    assert_eq!(resumed.start(), LearnerStart::Checkpoint(35));
    for i in 35..60 {
        uninterrupted.learn(&target(i)).unwrap();
        resumed.learn(&target(i)).unwrap();
    }
    assert_eq!(resumed.targets_learned(), 60);
    for row in [[0.3, -0.2], [-0.9, 0.4], [0.0, 1.0]] {
        let (a, b) = (
            uninterrupted.predict(&row).unwrap(),
            resumed.predict(&row).unwrap(),
        );
        assert_eq!(a, b, "at {row:?}");
    }
}

#[test]
fn a_checkpoint_of_another_rover_or_kind_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("learner.json");
    let mut learner = fresh();
    for i in 0..5 {
        learner.learn(&target(i)).unwrap();
    }
    learner.checkpoint(&path).unwrap();
    let refused = |rover: &[u8], kind: &str| match LiveLearner::resume(
        &path,
        OnlineMode::Update,
        1e-4,
        identity(rover),
        kind,
    ) {
        Err(CheckpointError::Mismatch { field, .. }) => field,
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("resumed for {kind}"),
    };
    assert_eq!(refused(b"another rover", "ilgr"), "rover_sha256");
    assert_eq!(refused(b"rover", "sparse_spectrum"), "kind");
}

#[test]
fn on_its_worker_thread_it_ends_as_in_lock_step_and_checkpoints_when_stopped() {
    use gpodo_node::learner_worker::{CheckpointPolicy, LearnerWorker};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("learner.json");
    let mut lock_step = fresh();
    let worker = LearnerWorker::spawn(
        fresh(),
        Some(CheckpointPolicy {
            path: path.clone(),
            every_secs: 30.0,
        }),
    );
    // Before it has learned: the prior.
    assert_eq!(
        worker.predict(&[0.2, 0.5]).unwrap().variance,
        Vector3::repeat(1e-4)
    );
    for i in 0..60 {
        lock_step.learn(&target(i)).unwrap();
        worker.learn(target(i));
    }
    let summary = worker.stop().unwrap();
    assert_eq!(summary.last_error, None);
    assert_eq!(summary.checkpoints, 1, "the one written on stopping");
    assert_eq!(summary.learner.targets_learned(), 60);
    for row in [[0.3, -0.2], [-0.9, 0.4]] {
        assert_eq!(
            summary.learner.predict(&row).unwrap(),
            lock_step.predict(&row).unwrap()
        );
    }
    let resumed =
        LiveLearner::resume(&path, OnlineMode::Update, 1e-4, identity(b"rover"), "ilgr").unwrap();
    assert_eq!(resumed.targets_learned(), 60);
    assert_eq!(
        resumed.predict(&[0.3, -0.2]).unwrap(),
        lock_step.predict(&[0.3, -0.2]).unwrap()
    );
}

#[test]
fn a_saved_online_model_goes_on_learning_and_other_kinds_are_refused() {
    use gpodo_regressors::model_file::{ModelFile, Provenance};
    use gpodo_traits::{ResidualDataset, SampleMatrix};
    let n = 40;
    let rows: Vec<VoTarget> = (0..n).map(target).collect();
    let data = ResidualDataset::new(
        SampleMatrix::from_row_major(n, 2, rows.iter().flat_map(|t| t.inputs.clone()).collect())
            .unwrap(),
        SampleMatrix::from_row_major(
            n,
            3,
            rows.iter()
                .flat_map(|t| t.residual.iter().copied())
                .collect(),
        )
        .unwrap(),
        vec!["cmd_v".into(), "pitch".into()],
        ["res_vx", "res_vy", "res_vz"].map(String::from).to_vec(),
    )
    .unwrap();
    let fit = |kind: &str| {
        let spec: RegressorSpec = serde_json::from_str(kind).unwrap();
        ModelFile::fit(&spec, &data, None, Provenance::default())
            .unwrap()
            .0
    };
    let saved = fit(r#"{"kind": "ilgr"}"#);
    let mut learner =
        LiveLearner::from_saved_model(&saved, OnlineMode::Update, 1e-4, sha256_hex(b"rover"))
            .unwrap();
    assert_eq!(learner.start(), LearnerStart::SavedModel);
    // It predicts as the saved model from the start, not the prior.
    let x = SampleMatrix::from_row_major(1, 2, vec![0.3, -0.2]).unwrap();
    let file_prediction = saved
        .predictor()
        .unwrap()
        .predict(&saved.input_names, &x)
        .unwrap();
    let live = learner.predict(&[0.3, -0.2]).unwrap();
    assert_eq!(live.mean.x, file_prediction.mean.row(0)[0]);
    learner.learn(&target(41)).unwrap();
    assert_eq!(learner.targets_learned(), 1);
    let exact = fit(r#"{"kind": "exact_gp", "kernel": "rbf", "hyperopt": {"max_iters": 5}}"#);
    let Err(e) =
        LiveLearner::from_saved_model(&exact, OnlineMode::Update, 1e-4, sha256_hex(b"rover"))
    else {
        panic!("an exact GP accepted to learn online");
    };
    assert!(e.to_string().contains("ilgr"), "{e}");
}

//! Fixtures shared by the node's tests: a simulated ExoTeR drive, an exact
//! GP fitted on it and saved with its row recipe, and a drive written as a
//! bag.

#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use gpodo_datasets::residuals::{ResidualConfig, log_steps, residual_dataset_from_steps};
use gpodo_kinematics::spec::MotionModelSpec;
use gpodo_regressors::RegressorSpec;
use gpodo_regressors::model_file::{ModelFile, Provenance, RowRecipe};
use gpodo_testbed::sim::preset::{Preset, SimulatorConfig};

pub fn exoter_yaml() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../kinematics/rovers/exoter.yaml")
}

/// A simulated testbed, and an exact GP fitted on its training run's 1-s
/// rows and saved with their recipe (`absolute` for a |residual| model).
pub fn fitted(
    dir: &Path,
    absolute: bool,
) -> (gpodo_testbed::sim::preset::SimulatedTestbed, PathBuf) {
    let mut config = SimulatorConfig::preset(Preset::ExoterPrl, 5);
    config.training_runs = 1;
    config.training_run_secs = 60.0;
    config.test_max_secs = 40.0;
    let testbed = config.simulate().unwrap();
    let spec = MotionModelSpec::default();
    let (motion, rover) = spec.build().unwrap();
    let rover = rover.unwrap();
    let log = &testbed.train[0];
    let steps = log_steps(log, motion.as_ref(), rover.wheel_radius_m).unwrap();
    let residuals = ResidualConfig {
        absolute_targets: absolute,
        ..ResidualConfig::default()
    };
    let train = residual_dataset_from_steps(&[log], &[steps], &residuals).unwrap();
    let regressor: RegressorSpec = serde_json::from_str(
        r#"{"kind": "exact_gp", "kernel": "rbf", "hyperopt": {"max_iters": 15}}"#,
    )
    .unwrap();
    let (mut file, _) = ModelFile::fit(&regressor, &train, None, Provenance::default()).unwrap();
    file.rows = Some(RowRecipe {
        rate_hz: Some(1.0 / config.dt_secs),
        window_secs: residuals.window_secs,
        absolute_targets: absolute,
        motion_model: serde_json::to_value(&spec).unwrap(),
    });
    let path = dir.join(if absolute { "abs.gpodo" } else { "m.gpodo" });
    file.save(&path).unwrap();
    (testbed, path)
}

/// Joint states and IMU messages of a log written as a bag, read back in
/// time order (the IMU first at a tie), as `(stamp_ns, message)`.
pub fn bag_messages(
    dir: &Path,
    log: &gpodo_datasets::log::RoverLog,
) -> (
    gpodo_datasets::bags::import::TopicMap,
    Vec<(i64, gpodo_datasets::bags::messages::RosMessage)>,
) {
    use gpodo_datasets::bags::OnDamage;
    use gpodo_datasets::bags::messages::RosMessage;
    use gpodo_datasets::bags::topic::{TopicRequest, read_topics};
    use gpodo_datasets::bags::write::{write_mcap, written_topic_map};
    let written = write_mcap(log, dir).unwrap();
    let map = written_topic_map(log, 1.0 / 0.08);
    let requests = [
        TopicRequest {
            topic: &map.imu.clone().unwrap(),
            role: "imu",
            expected: &["sensor_msgs/Imu"],
            optional: false,
        },
        TopicRequest {
            topic: &map.joints.as_ref().unwrap().topic,
            role: "joints",
            expected: &["sensor_msgs/JointState"],
            optional: false,
        },
    ];
    let (topics, _) = read_topics(&written.path, &requests, OnDamage::Stop).unwrap();
    let mut all: Vec<(i64, usize, RosMessage)> = Vec::new();
    for (t, list) in topics.into_iter().enumerate() {
        for s in list {
            let ns = match &s.message {
                RosMessage::Imu(m) => m.header.stamp_ns,
                RosMessage::JointState(m) => m.header.stamp_ns,
                _ => continue,
            };
            all.push((ns, t, s.message));
        }
    }
    all.sort_by_key(|(ns, t, _)| (*ns, *t));
    (map, all.into_iter().map(|(ns, _, m)| (ns, m)).collect())
}

/// A VO's `nav_msgs/Odometry` at `stamp_ns`: the pose `[x, y, z, qx, qy,
/// qz, qw]` with `position_variance` on each axis.
pub fn vo_odometry(
    stamp_ns: i64,
    pose: [f64; 7],
    position_variance: f64,
) -> gpodo_datasets::bags::messages::Odometry {
    use gpodo_datasets::bags::messages::{Header, Odometry, Pose, Twist};
    let mut pose_covariance = vec![0.0; 36];
    for i in 0..3 {
        pose_covariance[i * 7] = position_variance;
    }
    Odometry {
        header: Header {
            stamp_ns,
            frame_id: "vo".into(),
        },
        child_frame_id: "base_link".into(),
        pose: Pose {
            position: [pose[0], pose[1], pose[2]],
            orientation: [pose[3], pose[4], pose[5], pose[6]],
        },
        pose_covariance,
        twist: Twist {
            linear: [0.0; 3],
            angular: [0.0; 3],
        },
        twist_covariance: vec![0.0; 36],
    }
}

/// The identity of an ILGR learner on two inputs, for the rover whose
/// description hashes to `rover_sha256`.
pub fn learner_identity(rover_sha256: String) -> gpodo_node::learner::LearnerIdentity {
    gpodo_node::learner::LearnerIdentity {
        label: "ILGR online".into(),
        input_names: vec!["cmd_v".into(), "pitch".into()],
        input_standardizer: None,
        rows: None,
        rover_sha256,
    }
}

/// A fresh ILGR learner with `identity`, its prior variance 1e-4.
pub fn fresh_learner(
    identity: gpodo_node::learner::LearnerIdentity,
) -> gpodo_node::learner::LiveLearner {
    let spec: RegressorSpec = serde_json::from_str(r#"{"kind": "ilgr"}"#).unwrap();
    gpodo_node::learner::LiveLearner::new(
        gpodo_regressors::online_model::OnlineModel::from_spec(&spec).unwrap(),
        gpodo_frontends::online::OnlineMode::Update,
        1e-4,
        identity,
        gpodo_node::learner::LearnerStart::Empty,
    )
    .unwrap()
}

/// Target `i`: a residual smooth in two inputs, one every 4 s.
pub fn learner_target(i: usize) -> gpodo_frontends::vo_target::VoTarget {
    let x = [(i as f64 * 0.37).sin(), (i as f64 * 0.11).cos()];
    gpodo_frontends::vo_target::VoTarget {
        inputs: x.to_vec(),
        residual: nalgebra::Vector3::new(0.01 * x[0], -0.004 * x[1], 0.001),
        time_secs: 4.0 * (i + 1) as f64,
        duration_secs: 4.0,
    }
}

/// The drift budget (1e-4 m², at most every 0.4 s) with a turn and
/// distance guard: the gated policy the gate's tests run.
pub fn drift_budget_with_guard() -> gpodo_frontends::SelectorSpec {
    use gpodo_frontends::SelectorSpec;
    use gpodo_frontends::gating::UncertaintyBudgetParams;
    SelectorSpec::MaxGap {
        inner: Box::new(SelectorSpec::UncertaintyBudget(UncertaintyBudgetParams {
            budget_m2: 1e-4,
            min_period_secs: 0.4,
            count_mean: Some(false),
        })),
        max_gap_secs: None,
        max_distance_m: Some(0.3),
        max_rotation_rad: Some(0.15),
    }
}

/// ILGR with a 2-s initial lengthscale, offline and live alike.
pub fn ilgr_params() -> gpodo_regressors::IlgrParams {
    gpodo_regressors::IlgrParams {
        init_lengthscale: 2.0,
        ..gpodo_regressors::IlgrParams::default()
    }
}

/// A live ILGR learner ([`ilgr_params`]) starting empty on the inputs
/// `a` and `b`, with prior variance `variance`.
pub fn live_ilgr(variance: f64) -> gpodo_node::learner::LiveLearner {
    gpodo_node::learner::LiveLearner::new(
        gpodo_regressors::online_model::OnlineModel::from_spec(&RegressorSpec::Ilgr(ilgr_params()))
            .unwrap(),
        gpodo_frontends::online::OnlineMode::Update,
        variance,
        gpodo_node::learner::LearnerIdentity {
            label: "ilgr".into(),
            input_names: vec!["a".into(), "b".into()],
            input_standardizer: None,
            rows: None,
            rover_sha256: String::new(),
        },
        gpodo_node::learner::LearnerStart::Empty,
    )
    .unwrap()
}

/// Asserts that the offline learner and the live one predict alike, to
/// 1e-12, on three rows of two inputs.
pub fn assert_same_learner(
    offline: &mut dyn gpodo_frontends::prediction::ResidualSource,
    live: &gpodo_node::learner::LiveLearner,
) {
    for inputs in [[0.0, 1.0], [0.5, -0.8], [-0.9, 0.1]] {
        let window = gpodo_frontends::traverse::TraverseWindow {
            start_secs: 0.0,
            end_secs: 0.0,
            steps: 0..0,
            inputs: inputs.to_vec(),
            true_residual: nalgebra::Vector3::zeros(),
        };
        let a = offline.on_window(0, &window).unwrap();
        let b = live.predict(&inputs).unwrap();
        assert!((a.mean - b.mean).abs().max() <= 1e-12, "{a:?} {b:?}");
        assert!((a.variance - b.variance).abs().max() <= 1e-12);
    }
}

/// An odometry output at `time_secs` with the motion model's `twist` as
/// published, no row, no residual and no inputs (tests set what they
/// need).
pub fn output_at(time_secs: f64, twist: gpodo_traits::BodyTwist) -> gpodo_node::LiveOutput {
    gpodo_node::LiveOutput {
        time_secs,
        row: None,
        covered_secs: 0.0,
        inputs: Vec::new(),
        uncorrected: twist,
        twist,
        variance: [1e-4; 6],
        pose: nalgebra::Isometry3::identity(),
        pose_covariance: [0.0; 36],
        uncorrected_pose: nalgebra::Isometry3::identity(),
        out_of_range: Vec::new(),
        residual: None,
    }
}

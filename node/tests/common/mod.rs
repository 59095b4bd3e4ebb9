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

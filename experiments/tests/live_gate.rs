//! `gpodo live --gate FILE --replay BAG`: a simulated recording with the
//! rendered stereo camera and a VO trajectory (the ground truth at each
//! frame, with a gap where the VO gave nothing) replayed through the gate
//! and an online learner that starts empty.
//!
//! * Every pair is decided and written to the decisions CSV; the gate
//!   skips pairs, and in the VO's gap (no pose within 1 s of a forwarded
//!   pair) it says tracking is lost and looks every 0.4 s.
//! * Until the learner has learned, `/odom/gp` is the wheels' twist with
//!   the learner's prior variance; after, its predictions.
//! * The learner is written to the checkpoint at the end, and a second
//!   replay resumes it, counting on from it.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::path::Path;

use gpodo_datasets::bags::write::{
    WheelUnits, write_mcap, write_mcap_with_camera, written_topic_map_in,
};
use gpodo_testbed::camera::traverse::{camera_stream, frame_times, pose_at};
use gpodo_testbed::camera::{GroundMaps, SceneSpec, SensorSpec, StereoRenderer};
use gpodo_testbed::sim::preset::{Preset, SimulatorConfig};
use gpodo_traits::CameraParams;

use common::{assert_succeeded, bag_odometry, fit_bag_model, gpodo_live_gated};

/// The VO gave nothing from here to there (s, the drive's clock).
const GAP: std::ops::Range<f64> = 14.0..18.0;

const GATE: &str = "\
selector:
  kind: max_gap
  max_gap_secs: null
  max_rotation_rad: 0.15
  max_distance_m: 0.3
  inner: { kind: uncertainty_budget, budget_m2: 1.0e-4, count_mean: false }
online: { regressor: { kind: ilgr, init_lengthscale: 2.0 } }
lost_frame_period_secs: 0.4
lost: { silent_secs: 1.0 }
topics:
  left_image: /camera/left/image_raw
  right_image: /camera/right/image_raw
  left_info: /camera/left/camera_info
  right_info: /camera/right/camera_info
  vo_odometry: /vo/pose
checkpoint: { path: learner.json }
";

#[test]
fn a_gated_replay_decides_every_pair_learns_from_the_vo_and_resumes_its_checkpoint() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let mut config = SimulatorConfig::preset(Preset::ExoterPrl, 3);
    config.training_runs = 1;
    config.training_run_secs = 60.0;
    config.test_max_secs = 40.0;
    let testbed = config.simulate().unwrap();
    std::fs::create_dir_all(dir.join("train")).unwrap();
    std::fs::create_dir_all(dir.join("test")).unwrap();
    write_mcap(&testbed.train[0], &dir.join("train")).unwrap();
    let log = &testbed.test[0];
    let ground =
        GroundMaps::build(&testbed.terrain, &testbed.soils, &SceneSpec::default(), 3).unwrap();
    let renderer = StereoRenderer::new(
        CameraParams::exoter_bumblebee2().scaled(0.25),
        &ground,
        SensorSpec::default(),
        3,
    )
    .unwrap();
    let vo: Vec<_> = frame_times(log, 2.5)
        .into_iter()
        .filter(|t| !GAP.contains(t))
        .map(|t| (t, pose_at(log, t).unwrap()))
        .collect();
    let mut stream = camera_stream(&renderer, log, 2.5);
    let bag = write_mcap_with_camera(
        log,
        &dir.join("test"),
        &vo,
        WheelUnits::default(),
        Some(&mut stream),
    )
    .unwrap()
    .path;
    // The joints and the IMU: the gate file names the camera's topics.
    let map = written_topic_map_in(log, 12.5, WheelUnits::default());
    let topics = dir.join("topics.yaml");
    std::fs::write(&topics, serde_saphyr::to_string(&map).unwrap()).unwrap();
    let train = std::fs::read_dir(dir.join("train"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let model = fit_bag_model(dir, &topics, &train, &bag, 15);
    let gate = dir.join("gate.yaml");
    std::fs::write(&gate, GATE).unwrap();

    let replay = |out: &Path, decisions: &Path| {
        gpodo_live_gated(&model, &topics, &bag, out, &gate, decisions)
    };
    let (first, first_decisions) = (dir.join("first.mcap"), dir.join("first.csv"));
    let out = replay(&first, &first_decisions);
    assert_succeeded(&out, "gpodo live --gate --replay: ");
    let said = String::from_utf8_lossy(&out.stdout).to_string();
    println!("{said}");

    // Every pair decided; some skipped; in the gap, lost and looking.
    let csv = std::fs::read_to_string(&first_decisions).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), frame_times(log, 2.5).len());
    let processed = rows.iter().filter(|r| r[1] == "processed").count();
    assert!(
        processed > 5 && processed < rows.len(),
        "{processed} of {}",
        rows.len()
    );
    let lost: Vec<&Vec<&str>> = rows
        .iter()
        .filter(|r| r.last() == Some(&"vo silent"))
        .collect();
    assert!(!lost.is_empty(), "{csv}");
    assert!(
        lost.iter()
            .all(|r| r[1] == "processed" || r[2].contains("tracking lost"))
    );

    // The prior until the learner has learned, its predictions after.
    let (gp, wheel) = (
        bag_odometry(&first, "/odom/gp"),
        bag_odometry(&first, "/odom/wheel"),
    );
    assert_eq!(gp[1].twist.linear, wheel[1].twist.linear);
    assert_eq!(gp[1].twist_covariance[0], 1e-4);
    let last = gp.len() - 1;
    assert_ne!(gp[last].twist.linear, wheel[last].twist.linear);
    // The learner's own variance (on the saved model's standardised
    // inputs, as offline), not the prior's.
    assert_ne!(gp[last].twist_covariance[0], 1e-4);

    // Written at the end; a second replay goes on from it.
    let learned = |said: &str| -> u64 {
        let line = said.lines().find(|l| l.starts_with("learner: ")).unwrap();
        line["learner: ".len()..]
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let n = learned(&said);
    assert!(n >= 3, "{said}");
    assert!(dir.join("learner.json").exists());
    let out = replay(&dir.join("second.mcap"), &dir.join("second.csv"));
    assert_succeeded(&out, "the second replay: ");
    let again = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(learned(&again) > n, "{again}");
    // Resumed, its first outputs carry the learned model's variance.
    let resumed = bag_odometry(&dir.join("second.mcap"), "/odom/gp");
    assert_ne!(resumed[1].twist_covariance[0], 1e-4);
}

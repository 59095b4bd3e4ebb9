//! The frame gate and its learner on ROS 2 against Cyclone DDS (the
//! `cyclonedds` package from PyPI, no ROS): a Python peer plays the
//! camera driver, the robot's sensors and the VO behind the gate
//! (`tests/ros2_gate_peer.py`). It publishes a simulated drive's joint
//! states, IMU messages and rendered stereo pairs (real pixels, with their
//! camera infos), and answers each pair the gate forwards with the
//! odometry a replay's VO gave for it (a null pose where that VO lost
//! track). The same drive replayed with the same gate and VO in the loop
//! is the reference:
//!
//! * the gated pairs arrive on reliable QoS as they were sent, byte for
//!   byte (their CDR);
//! * the gate decides every pair as in the replay, and forwards the same
//!   pairs;
//! * the learner ends in the replay's state (its predictions to 1e-12).
//!
//! The peer sends each message after the node has answered the one before
//! (a joint state's odometry, a pair's decision, the VO's odometry
//! acknowledged), so that DDS delivers them in the replay's order.
//! Loopback only, on a domain of this run's own; the node stops by itself
//! after the drive's outputs (or 20 s without input). Needs the `ros2`
//! feature; skipped without the Python packages unless
//! `GPODO_REQUIRE_PYTHON` is set, as in CI.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};

use gpodo_datasets::bags::messages::{Odometry, RosMessage};
use gpodo_datasets::bags::write::{
    EPOCH_NS, WheelUnits, write_mcap_with_camera, written_topic_map,
};
use gpodo_datasets::bags::write_camera::written_camera_topics;
use gpodo_frontends::gate::GateState;
use gpodo_frontends::online::OnlineMode;
use gpodo_frontends::params::FrontendParams;
use gpodo_frontends::scheme::causal_selector;
use gpodo_node::gate::lost::LostSettings;
use gpodo_node::gate::pairing::PairingSettings;
use gpodo_node::gate::session::{GateSession, LearnerEnd, Learning, PredictionClock};
use gpodo_node::gate::topics::GateTopics;
use gpodo_node::gate::{LiveGate, LiveGateSettings};
use gpodo_node::learner::{LearnerIdentity, LearnerStart, LiveLearner};
use gpodo_node::replay::{GatedReplay, Pace, Playback, RecordedPair, replay_gated};
use gpodo_node::ros2::{Ros2Gate, Ros2Settings, run};
use gpodo_node::{LiveModel, LiveSettings};
use gpodo_regressors::online_model::OnlineModel;
use gpodo_regressors::{IlgrParams, RegressorSpec};
use gpodo_testbed::camera::traverse::{camera_stream, pose_at};
use gpodo_testbed::camera::{GroundMaps, SceneSpec, SensorSpec, StereoRenderer};
use gpodo_testkit::python_with;
use gpodo_traits::CameraParams;

use common::{exoter_yaml, fitted, vo_odometry};

/// Cyclone DDS on loopback alone, finding peers by unicast.
const CYCLONE_LOOPBACK: &str = r#"<CycloneDDS><Domain id="any"><General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20</MaxAutoParticipantIndex><Peers><Peer address="127.0.0.1"/></Peers></Discovery></Domain></CycloneDDS>"#;

/// The VO lost track from here to there (s, the drive's clock): its
/// answers are null poses.
const LOST: std::ops::Range<f64> = 14.0..17.0;

fn topics() -> GateTopics {
    let camera = written_camera_topics();
    GateTopics {
        left_image: camera.left,
        right_image: camera.right,
        left_info: camera.left_info.unwrap(),
        right_info: camera.right_info.unwrap(),
        vo_odometry: "/vo/odometry".into(),
        gated_prefix: "/gated".into(),
        decisions: "/gpodo/gate/decisions".into(),
    }
}

/// The gate: the drift budget with a turn and distance guard, ILGR
/// learning online on the node's rows, lost only on what the VO says.
fn session<T>(model: &LiveModel) -> GateSession<T> {
    let params = FrontendParams::default();
    let spec = common::drift_budget_with_guard();
    let gate = LiveGate::new(
        causal_selector(&spec, params.lost_frame_period_secs, None).unwrap(),
        GateState::new(
            params.odometry,
            params.odometry_mode,
            params.initial_residual_variance,
        ),
        LiveGateSettings {
            lost: LostSettings {
                silent_secs: None,
                ..LostSettings::default()
            },
            ..LiveGateSettings::default()
        },
    );
    let learner = LiveLearner::new(
        OnlineModel::from_spec(&RegressorSpec::Ilgr(IlgrParams {
            init_lengthscale: 2.0,
            ..IlgrParams::default()
        }))
        .unwrap(),
        OnlineMode::Update,
        params.initial_residual_variance,
        LearnerIdentity {
            label: "online: ilgr".into(),
            input_names: model.columns().to_vec(),
            input_standardizer: None,
            rows: None,
            rover_sha256: String::new(),
        },
        LearnerStart::Empty,
    )
    .unwrap();
    GateSession::new(
        gate,
        PairingSettings::default(),
        Some(Learning::LockStep(Box::new(learner))),
        model.columns(),
        PredictionClock::Sample,
        2.4,
    )
    .unwrap()
}

/// The VO's answer at `stamp_ns`: the ground truth's pose, or a null pose
/// while it has lost track; `[x, y, z, qx, qy, qz, qw]`.
fn vo_pose(log: &gpodo_datasets::log::RoverLog, stamp_ns: i64) -> [f64; 7] {
    let t = (stamp_ns - EPOCH_NS as i64) as f64 * 1e-9;
    if LOST.contains(&t) {
        return [0.0; 7];
    }
    let p = pose_at(log, t).unwrap();
    let q = p.rotation.quaternion();
    let v = p.translation.vector;
    [v.x, v.y, v.z, q.i, q.j, q.k, q.w]
}

fn odometry(stamp_ns: i64, pose: [f64; 7]) -> Odometry {
    vo_odometry(stamp_ns, pose, 1e-4)
}

fn learner_of<T>(session: GateSession<T>) -> LiveLearner {
    match session.finish() {
        LearnerEnd::LockStep(l) => *l,
        _ => panic!("a lock-step learner"),
    }
}

#[test]
fn a_cyclone_dds_peer_gets_the_replays_gated_pairs_and_the_learner_ends_alike() {
    let Some(python) = python_with(&["cyclonedds", "mcap_ros2.reader"], "cyclonedds") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let (testbed, model_path) = fitted(dir, false);
    let log = testbed.test[0].clone();
    // The rendered camera at a quarter of the Bumblebee2's resolution.
    let ground =
        GroundMaps::build(&testbed.terrain, &testbed.soils, &SceneSpec::default(), 3).unwrap();
    let renderer = StereoRenderer::new(
        CameraParams::exoter_bumblebee2().scaled(0.25),
        &ground,
        SensorSpec::default(),
        3,
    )
    .unwrap();
    let mut stream = camera_stream(&renderer, &log, 2.5);
    let bag = write_mcap_with_camera(&log, dir, &[], WheelUnits::default(), Some(&mut stream))
        .unwrap()
        .path;
    let map = written_topic_map(&log, 1.0 / 0.08);
    let rover = gpodo_kinematics::RoverDescription::from_path(&exoter_yaml()).unwrap();
    let load = || {
        LiveModel::load(
            &model_path,
            &exoter_yaml(),
            true,
            false,
            LiveSettings::default(),
        )
        .unwrap()
    };
    let topics = topics();

    // The replay, the VO in the loop.
    let mut model = load();
    let mut replayed = session(&model);
    let mut answers: BTreeMap<i64, [f64; 7]> = BTreeMap::new();
    let mut vo = |pair: &RecordedPair<'_>, _: &gpodo_node::gate::GateDecision| {
        assert!(matches!(pair.left, RosMessage::Image(_)));
        let pose = vo_pose(&log, pair.stamp_ns);
        answers.insert(pair.stamp_ns, pose);
        Some(odometry(pair.stamp_ns, pose))
    };
    let summary = replay_gated(
        &bag,
        &map,
        &rover,
        &mut model,
        &dir.join("replay.mcap"),
        None,
        Playback::to_the_end(Pace::Fast),
        Some(GatedReplay {
            topics: &topics,
            session: &mut replayed,
            vo: &mut vo,
        }),
    )
    .unwrap();
    let counts = replayed.counts();
    let expected_decisions: BTreeMap<i64, bool> = summary
        .decisions
        .iter()
        .map(|d| (d.stamp_ns, d.processed))
        .collect();
    assert!(counts.targets >= 3, "{counts:?}");
    assert!(counts.lost_poses >= 1, "{counts:?}");
    assert!(counts.forwarded < counts.decided, "{counts:?}");
    let replay_learner = learner_of(replayed);

    // The same over DDS.
    let domain = 100 + (std::process::id() % 100) as u16;
    let cyclone = dir.join("cyclone.xml");
    std::fs::write(&cyclone, CYCLONE_LOOPBACK).unwrap();
    let vo_table: BTreeMap<String, [f64; 7]> = expected_decisions
        .keys()
        .map(|&s| (s.to_string(), vo_pose(&log, s)))
        .collect();
    std::fs::write(
        dir.join("vo.json"),
        serde_json::to_string(&vo_table).unwrap(),
    )
    .unwrap();
    let gated: Vec<String> = gpodo_node::gate::pairing::Part::ALL
        .iter()
        .map(|&p| topics.gated(p))
        .collect();
    let peer_topics = serde_json::json!({
        "joints": map.joints.as_ref().unwrap().topic,
        "imu": map.imu.as_ref().unwrap(),
        "left_image": topics.left_image,
        "right_image": topics.right_image,
        "left_info": topics.left_info,
        "right_info": topics.right_info,
        "vo_odometry": topics.vo_odometry,
        "decisions": topics.decisions,
        "gated": gated,
    });
    std::fs::write(dir.join("topics.json"), peer_topics.to_string()).unwrap();
    let received = dir.join("received.json");
    let peer = Command::new(&python)
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ros2_gate_peer.py"))
        .arg(domain.to_string())
        .arg(&bag)
        .arg(dir.join("topics.json"))
        .arg(dir.join("vo.json"))
        .arg(&received)
        .env("CYCLONEDDS_URI", format!("file://{}", cyclone.display()))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut model = load();
    let mut live = session(&model);
    let settings = Ros2Settings {
        domain_id: domain,
        max_outputs: Some(summary.outputs),
        idle_exit_secs: Some(20.0),
        interfaces: vec!["127.0.0.1".parse().unwrap()],
        ..Ros2Settings::default()
    };
    let dds = run(
        &map,
        &rover,
        &mut model,
        &settings,
        Some(Ros2Gate {
            topics: &topics,
            status_topic: None,
            session: &mut live,
        }),
        &|| false,
    )
    .unwrap();
    let peer = peer.wait_with_output().unwrap();
    assert!(
        peer.status.success(),
        "the Cyclone DDS peer: {}\n{}",
        String::from_utf8_lossy(&peer.stdout),
        String::from_utf8_lossy(&peer.stderr),
    );
    let traffic = dds.gate.unwrap();
    eprintln!("{dds:?}\nreplay: {counts:?}\nDDS: {:?}", live.counts());
    let got: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&received).unwrap()).unwrap();

    // Every pair decided as in the replay; the same pairs forwarded, each
    // arriving as it was sent.
    let decisions: BTreeMap<i64, bool> = got["decisions"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(k, v)| (k.parse().unwrap(), v["decision"] == "processed"))
        .collect();
    assert_eq!(decisions, expected_decisions);
    assert_eq!(got["pairs_sent"], expected_decisions.len());
    let forwarded = expected_decisions.values().filter(|p| **p).count() as u64;
    assert_eq!(traffic.forwarded, forwarded);
    assert_eq!(got["gated_identical"], 4 * forwarded);
    assert_eq!(got["gated_different"], 0);
    assert_eq!(got["vo_answers"], forwarded);
    assert_eq!(live.counts(), counts);
    assert_eq!(answers.len() as u64, forwarded);

    // The learner ends where the replay's did.
    let live_learner = learner_of(live);
    assert_eq!(
        live_learner.targets_learned(),
        replay_learner.targets_learned()
    );
    let row = vec![0.1; model.columns().len()];
    for scale in [0.0, 1.0, -2.0] {
        let r: Vec<f64> = row.iter().map(|v| v * scale).collect();
        let (a, b) = (
            live_learner.predict(&r).unwrap(),
            replay_learner.predict(&r).unwrap(),
        );
        assert!((a.mean - b.mean).abs().max() <= 1e-12, "{a:?} {b:?}");
        assert!((a.variance - b.variance).abs().max() <= 1e-12);
    }
}

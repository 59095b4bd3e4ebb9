//! The node on ROS 2 against Cyclone DDS (the `cyclonedds` package from
//! PyPI, no ROS): a Python peer publishes a simulated recording's joint
//! states and IMU messages as ROS 2 does, and receives the node's odometry
//! and diagnostics. What it receives equals the replay of the same
//! recording, message for message and bit for bit, though the peer
//! restarts its publishers half way and sends a tenth of the recording in
//! a burst as fast as it can.
//!
//! Loopback only: both sides use 127.0.0.1 alone and find each other by
//! unicast (the loopback interface has no multicast here), on a domain id
//! of this run's own. The node stops by itself after the recording's
//! outputs (or 20 s without input). Needs the `ros2` feature; skipped
//! without the Python packages unless `GPODO_REQUIRE_PYTHON` is set, as in
//! CI.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::path::Path;
use std::process::{Command, Stdio};

use gpodo_datasets::bags::messages::{Odometry, RosMessage};
use gpodo_datasets::bags::topic::read_topic;
use gpodo_datasets::bags::write::{write_mcap, written_topic_map};
use gpodo_node::ros2::{Ros2Settings, run};
use gpodo_node::{LiveModel, LiveSettings};
use gpodo_testkit::python_with;

use common::{exoter_yaml, fitted};

/// Cyclone DDS on loopback alone, finding peers by unicast.
const CYCLONE_LOOPBACK: &str = r#"<CycloneDDS><Domain id="any"><General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20</MaxAutoParticipantIndex><Peers><Peer address="127.0.0.1"/></Peers></Discovery></Domain></CycloneDDS>"#;

fn odometry(bag: &Path, topic: &str) -> Vec<Odometry> {
    let messages = read_topic(bag, topic, "odometry", &["nav_msgs/Odometry"]).unwrap();
    messages
        .into_iter()
        .map(|s| match s.message {
            RosMessage::Odometry(o) => o,
            other => panic!("not odometry: {other:?}"),
        })
        .collect()
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn a_cyclone_dds_peer_gets_what_the_replay_writes() {
    let Some(python) = python_with(&["cyclonedds", "mcap_ros2.reader"], "cyclonedds") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let (testbed, model_path) = fitted(dir, false);
    let mut log = testbed.test[0].clone();
    log.samples.truncate(300);
    log.ground_truth.truncate(300);
    log.camera_times_secs
        .retain(|t| *t <= log.samples[299].time_secs);
    let bag = write_mcap(&log, dir).unwrap().path;
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

    let replayed = dir.join("replay.mcap");
    gpodo_node::replay::replay(
        &bag,
        &map,
        &rover,
        &mut load(),
        &replayed,
        None,
        gpodo_node::replay::Playback::to_the_end(gpodo_node::replay::Pace::Fast),
    )
    .unwrap();
    let expected = odometry(&replayed, "/odom/gp");
    assert_eq!(expected.len(), 300);

    // A domain of this run's own (0–232 are valid; 100–199 here).
    let domain = 100 + (std::process::id() % 100) as u16;
    let cyclone = dir.join("cyclone.xml");
    std::fs::write(&cyclone, CYCLONE_LOOPBACK).unwrap();
    let received = dir.join("received.json");
    let peer = Command::new(&python)
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ros2_peer.py"))
        .arg(domain.to_string())
        .arg(&bag)
        .arg(&map.joints.as_ref().unwrap().topic)
        .arg(map.imu.as_ref().unwrap())
        .arg(&received)
        .env("CYCLONEDDS_URI", format!("file://{}", cyclone.display()))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let settings = Ros2Settings {
        domain_id: domain,
        max_outputs: Some(expected.len()),
        idle_exit_secs: Some(20.0),
        interfaces: vec!["127.0.0.1".parse().unwrap()],
        ..Ros2Settings::default()
    };
    let mut model = load();
    let summary = run(&map, &rover, &mut model, &settings, None, &|| false).unwrap();
    let peer = peer.wait_with_output().unwrap();
    assert!(
        peer.status.success(),
        "the Cyclone DDS peer: {}\n{}",
        String::from_utf8_lossy(&peer.stdout),
        String::from_utf8_lossy(&peer.stderr),
    );
    eprintln!("{summary:?}");
    assert_eq!(summary.outputs, 300, "{summary:?}");
    assert_eq!(summary.undecodable, 0);
    let (p50, p99) = summary.latency_secs.unwrap();
    assert!(p50 > 0.0 && p99 >= p50);

    let got: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&received).unwrap()).unwrap();
    assert_eq!(got["sent_joint_states"], 300);
    let odometry = got["odometry"].as_array().unwrap();
    assert_eq!(
        odometry.len(),
        expected.len(),
        "odometry messages received on Cyclone DDS against those of the replay"
    );
    for (k, (o, e)) in odometry.iter().zip(&expected).enumerate() {
        assert_eq!(
            o["stamp_ns"].as_i64().unwrap(),
            e.header.stamp_ns,
            "message {k}"
        );
        assert_eq!(o["frame_id"], "odom");
        assert_eq!(o["child_frame_id"], "base_link");
        // The same computation on the same inputs: the same bits.
        assert_eq!(floats(&o["linear"]), e.twist.linear.to_vec(), "message {k}");
        assert_eq!(
            floats(&o["angular"]),
            e.twist.angular.to_vec(),
            "message {k}"
        );
        assert_eq!(
            floats(&o["twist_covariance"]),
            e.twist_covariance,
            "message {k}"
        );
        assert_eq!(
            floats(&o["position"]),
            e.pose.position.to_vec(),
            "message {k}"
        );
        assert_eq!(
            floats(&o["orientation"]),
            e.pose.orientation.to_vec(),
            "message {k}"
        );
    }
    let diagnostics = got["diagnostics"].as_array().unwrap();
    assert!(!diagnostics.is_empty(), "no /diagnostics received");
    let last = &diagnostics[diagnostics.len() - 1];
    assert_eq!(last["name"], "gpodo live: /odom/gp");
    assert_eq!(last["values"]["model kind"], "exact_gp");
    assert_eq!(last["values"]["inputs not used"], "0");
    let p99: f64 = last["values"]["latency p99 (ms)"]
        .as_str()
        .unwrap()
        .parse()
        .unwrap();
    assert!(p99 > 0.0 && p99.is_finite(), "{last}");
}

//! Faults on the gate's topics, through the node's gate session: a pair
//! with a half missing, an image out of order, a camera info that does
//! not match its image, an image topic gone silent and a VO that restarts
//! from the origin. Each is counted in the gate's `/diagnostics` status,
//! which warns; none stops the gate, and none is learned from: every
//! target the learner gets is the drive's true residual.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use gpodo_datasets::bags::messages::Odometry;

use common::vo_odometry;
use gpodo_frontends::SelectorSpec;
use gpodo_frontends::gate::GateState;
use gpodo_frontends::odometry::OdometryNoise;
use gpodo_frontends::odometry_mode::OdometryMode;
use gpodo_frontends::online::OnlineMode;
use gpodo_frontends::scheme::causal_selector;
use gpodo_node::LiveOutput;
use gpodo_node::gate::pairing::{PairingSettings, Part, PartHeader};
use gpodo_node::gate::session::{GateSession, LearnerEnd, Learning, PredictionClock};
use gpodo_node::gate::{LiveGate, LiveGateSettings, PoseOutcome};
use gpodo_node::learner::{LearnerIdentity, LearnerStart, LiveLearner};
use gpodo_regressors::online_model::OnlineModel;
use gpodo_regressors::{IlgrParams, RegressorSpec};
use gpodo_traits::BodyTwist;
use nalgebra::Vector3;

const NS: i64 = 1_000_000_000;

fn session() -> GateSession<u32> {
    let spec = SelectorSpec::FixedRate {
        fps: 2.5,
        phase_secs: 0.0,
    };
    let gate = LiveGate::new(
        causal_selector(&spec, None, None).unwrap(),
        GateState::new(OdometryNoise::default(), OdometryMode::default(), 1e-4),
        LiveGateSettings::default(),
    );
    let learner = LiveLearner::new(
        OnlineModel::from_spec(&RegressorSpec::Ilgr(IlgrParams::default())).unwrap(),
        OnlineMode::Update,
        1e-4,
        LearnerIdentity {
            label: "ilgr".into(),
            input_names: vec!["a".into()],
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
        &["a".to_string()],
        PredictionClock::Sample,
        2.4,
    )
    .unwrap()
    .with_child_frame_id(Some("base_link".into()))
}

/// An odometry output at `t`: 0.1 m/s ahead on the wheels, the row `[1]`.
fn output(t: f64) -> LiveOutput {
    let twist = BodyTwist {
        linear_mps: Vector3::new(0.1, 0.0, 0.0),
        angular_radps: Vector3::zeros(),
    };
    LiveOutput {
        row: Some(vec![1.0]),
        covered_secs: 1.0,
        inputs: vec![1.0],
        residual: Some(([0.0; 3], [1e-4; 3])),
        ..common::output_at(t, twist)
    }
}

fn odometry(stamp_ns: i64, x: f64) -> Odometry {
    vo_odometry(stamp_ns, [x, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0], 1e-6)
}

fn value(status: &gpodo_datasets::bags::write::DiagnosticStatus, key: &str) -> u64 {
    let v = &status.values.iter().find(|(k, _)| k == key).unwrap().1;
    v.parse().unwrap()
}

#[test]
fn faults_are_counted_and_warned_of_and_none_is_learned_from() {
    let mut s = session();
    let header = |stamp_ns, width| PartHeader {
        stamp_ns,
        width,
        height: 48,
    };
    let mut targets = Vec::new();
    let mut step = 0;
    for k in 0..60_i64 {
        let stamp = k * 2 * NS / 5;
        let now = stamp as f64 * 1e-9;
        // The odometry up to the frame: 12.5 Hz.
        while step * 80_000_000 <= stamp {
            s.output(&output(step as f64 * 0.08), step * 80_000_000)
                .unwrap();
            step += 1;
        }
        s.watch(now);
        let mut parts = vec![
            (Part::LeftImage, 64),
            (Part::RightImage, 64),
            (Part::LeftInfo, 64),
            (Part::RightInfo, 64),
        ];
        match k {
            // The right image of pair 5 never comes.
            5 => parts.retain(|(p, _)| *p != Part::RightImage),
            // Pair 10's left camera info describes another size.
            10 => parts[2].1 = 100,
            // The right camera goes silent for 3.6 s.
            20..=28 => parts.retain(|(p, _)| *p != Part::RightImage),
            _ => {}
        }
        let mut pair = None;
        for (part, width) in parts {
            pair = pair.or(s.part(part, header(stamp, width), 0, now));
        }
        if k == 8 {
            // An image of pair 3 comes after pair 8.
            assert!(
                s.part(Part::LeftImage, header(3 * 2 * NS / 5, 64), 0, now)
                    .is_none()
            );
        }
        let Some(pair) = pair else { continue };
        let (decision, forwarded) = s.decide(pair, now);
        assert!(decision.processed && forwarded.is_some());
        // The VO sees the rover 10 % faster than the wheels; it restarts
        // from the origin at pair 40.
        let x = if k == 40 { 0.0 } else { 0.11 * now };
        let mut pose = odometry(stamp, x);
        // Pair 50's pose comes in the camera's frame, not the body's.
        if k == 50 {
            pose.child_frame_id = "left_camera".into();
        }
        match s.vo_odometry(&pose) {
            PoseOutcome::Target(t) => targets.push(t),
            PoseOutcome::OtherFrame => assert_eq!(k, 50),
            _ => {}
        }
    }
    let status = s.status();
    assert_eq!(status.level, 1, "{status:?}");
    // The left image of pair 5, and the nine of the silence.
    assert_eq!(value(&status, "images without pair"), 1 + 9, "{status:?}");
    assert_eq!(value(&status, "messages out of order"), 1);
    assert_eq!(value(&status, "infos not matching"), 1);
    assert_eq!(value(&status, "image topics gone silent"), 1);
    // The restart, and the pose after it, off the origin by the route.
    assert_eq!(value(&status, "VO jumps"), 2);
    assert_eq!(value(&status, "targets refused"), 0);
    assert_eq!(value(&status, "VO poses of another child frame"), 1);
    // Pairs 5, 10 and 20–28 were never made.
    let counts = s.counts();
    assert_eq!(counts.decided, 60 - 11);
    assert!(!targets.is_empty());
    for t in &targets {
        assert!(
            (t.residual - Vector3::new(0.01, 0.0, 0.0)).norm() < 1e-9,
            "{t:?}"
        );
    }
    let LearnerEnd::LockStep(learner) = s.finish() else {
        panic!("a lock-step learner")
    };
    assert_eq!(learner.targets_learned(), targets.len() as u64);
    assert_eq!(counts.targets, targets.len() as u64);
}

//! The live frame gate on a drive built by hand: what it forwards, the
//! targets it forms against closed forms, and what it does not learn from.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_frontends::SelectorSpec;
use gpodo_frontends::gate::GateState;
use gpodo_frontends::gating::UncertaintyBudgetParams;
use gpodo_frontends::odometry::OdometryNoise;
use gpodo_frontends::odometry_mode::OdometryMode;
use gpodo_frontends::prediction::ResidualPrediction;
use gpodo_frontends::scheme::causal_selector;
use gpodo_frontends::vo_target::NoTarget;
use gpodo_node::gate::lost::LostReason;
use gpodo_node::gate::{LiveGate, LiveGateSettings, PoseOutcome};
use gpodo_traits::BodyTwist;
use nalgebra::Vector3;

const IDENTITY: [f64; 4] = [0.0, 0.0, 0.0, 1.0];
const NS: i64 = 1_000_000_000;

fn gate(spec: &SelectorSpec, lost_period: Option<f64>) -> LiveGate {
    let selector = causal_selector(spec, lost_period, None).unwrap();
    let state = GateState::new(OdometryNoise::default(), OdometryMode::default(), 1e-4);
    LiveGate::new(selector, state, LiveGateSettings::default())
}

fn ahead(mps: f64) -> BodyTwist {
    BodyTwist {
        linear_mps: Vector3::new(mps, 0.0, 0.0),
        angular_radps: Vector3::zeros(),
    }
}

/// Drives 0.4 s at 0.1 m/s in 0.01 s steps with inputs `[1.0]`.
fn drive_frame(g: &mut LiveGate) {
    for _ in 0..40 {
        g.drive(&ahead(0.1), 0.01, Some(&[1.0]));
    }
}

#[test]
fn a_fixed_rate_forwards_every_nth_pair_and_its_poses_give_the_residual() {
    let mut g = gate(
        &SelectorSpec::FixedRate {
            fps: 0.5,
            phase_secs: 0.0,
        },
        None,
    );
    let mut forwarded = Vec::new();
    let mut targets = Vec::new();
    // 2.5 fps for 20 s; the VO sees the rover 10 % faster than the
    // wheels say: a residual of 0.01 m/s ahead.
    for k in 0..50_i64 {
        if k > 0 {
            drive_frame(&mut g);
        }
        let stamp = k * 2 * NS / 5;
        let d = g.decide(stamp, stamp as f64 * 1e-9);
        assert_eq!(d.tracking_lost, None);
        if d.processed {
            assert_eq!(d.keyframe_threshold_scale, Some(1.0));
            forwarded.push(k);
            let x = 0.11 * stamp as f64 * 1e-9;
            match g.vo_pose(stamp, [x, 0.0, 0.0], IDENTITY, [1e-6; 3]) {
                PoseOutcome::Target(t) => targets.push(t),
                PoseOutcome::Pose(_) => {}
                other => panic!("{other:?} at {k}"),
            }
        }
    }
    assert_eq!(forwarded, (0..50).step_by(5).collect::<Vec<_>>());
    // Targets over the default 4 s minimum: 0–4, 4–8, 8–12, 12–16.
    assert_eq!(targets.len(), 4);
    for t in &targets {
        assert!(
            (t.residual - Vector3::new(0.01, 0.0, 0.0)).norm() < 1e-9,
            "{t:?}"
        );
        assert!((t.duration_secs - 4.0).abs() < 1e-9);
        assert_eq!(t.inputs, vec![1.0]);
    }
    let c = g.counts();
    assert_eq!((c.decided, c.forwarded, c.targets), (50, 10, 4));
}

#[test]
fn while_the_vo_is_lost_a_gated_policy_looks_every_period() {
    let spec = SelectorSpec::UncertaintyBudget(UncertaintyBudgetParams {
        budget_m2: 1.0,
        ..UncertaintyBudgetParams::default()
    });
    let mut g = gate(&spec, Some(0.4));
    // The first pair is forwarded (nothing processed yet); the VO
    // answers with a null pose: lost.
    let first = g.decide(0, 0.0);
    assert!(first.processed);
    assert_eq!(
        g.vo_pose(0, [0.0; 3], [0.0; 4], [1e-6; 3]),
        PoseOutcome::Lost(LostReason::NullPose)
    );
    let mut looks = 0;
    for k in 1..10_i64 {
        drive_frame(&mut g);
        let d = g.decide(k * 2 * NS / 5, 0.4 * k as f64);
        assert_eq!(d.tracking_lost, Some(LostReason::NullPose));
        assert!(d.reason.contains("tracking lost"), "{}", d.reason);
        looks += usize::from(d.processed);
        if d.processed {
            // Still lost.
            g.vo_pose(k * 2 * NS / 5, [0.0; 3], [0.0; 4], [1e-6; 3]);
        }
    }
    assert_eq!(looks, 9, "a pair every 0.4 s while lost");
    // A budget of 1 m² is never spent in 4 s at 0.01 m/s: once tracking,
    // the policy alone decides and skips.
    drive_frame(&mut g);
    let d = g.decide(4 * NS, 4.0);
    assert!(d.processed);
    assert!(matches!(
        g.vo_pose(4 * NS, [0.4, 0.0, 0.0], IDENTITY, [1e-6; 3]),
        PoseOutcome::Pose(None)
    ));
    drive_frame(&mut g);
    let d = g.decide(4 * NS + 2 * NS / 5, 4.4);
    assert_eq!(d.tracking_lost, None);
    assert!(!d.processed);
}

#[test]
fn unanswered_pairs_resets_and_jumps_are_not_learned_from() {
    let mut g = gate(
        &SelectorSpec::FixedRate {
            fps: 2.5,
            phase_secs: 0.0,
        },
        None,
    );
    let mut outcomes = Vec::new();
    for k in 0..60_i64 {
        if k > 0 {
            drive_frame(&mut g);
        }
        let stamp = k * 2 * NS / 5;
        assert!(g.decide(stamp, stamp as f64 / 1e9).processed);
        let x = 0.1 * stamp as f64 / 1e9;
        let position = match k {
            // The VO gives nothing for pairs 12 and 13.
            12 | 13 => continue,
            // It restarts from the origin at 25.
            25 => [0.0; 3],
            // And relocalises 2 m off at 30.
            30.. => [x - 2.0, 0.5, 0.0],
            _ => [x, 0.0, 0.0],
        };
        outcomes.push((k, g.vo_pose(stamp, position, IDENTITY, [1e-6; 3])));
    }
    let jumps: Vec<i64> = outcomes
        .iter()
        .filter(|(_, o)| *o == PoseOutcome::Jump)
        .map(|(k, _)| *k)
        .collect();
    // 26 is off the origin by the route so far: a jump back.
    assert_eq!(jumps, vec![25, 26, 30]);
    let c = g.counts();
    assert_eq!((c.unanswered, c.jumps), (2, 3));
    // The interval after the unanswered pairs starts afresh at 14.
    assert!(matches!(outcomes[12], (14, PoseOutcome::Pose(None))));
    // Targets over 4 s from 0, from 14 (after the unanswered pairs), and
    // from 30 (the last jump) on; each the true zero residual.
    let mut learned = Vec::new();
    for (k, o) in &outcomes {
        if let PoseOutcome::Target(t) = o {
            assert!(t.residual.norm() < 1e-9, "{k}: {t:?}");
            learned.push(*k);
        }
        assert!(!matches!(o, PoseOutcome::Pose(Some(NoTarget::TooLong))));
    }
    assert_eq!(learned, vec![10, 24, 40, 50]);
    assert_eq!(c.targets, 4);
    // A pose for a pair never forwarded.
    assert_eq!(
        g.vo_pose(1, [0.0; 3], IDENTITY, [1e-6; 3]),
        PoseOutcome::Unexpected
    );
}

#[test]
fn a_new_prediction_changes_what_the_policy_sees() {
    let spec = SelectorSpec::UncertaintyBudget(UncertaintyBudgetParams {
        budget_m2: 1e-4,
        ..UncertaintyBudgetParams::default()
    });
    let mut g = gate(&spec, None);
    assert!(g.decide(0, 0.0).processed);
    // A confident model: 1e-8 (m/s)² per axis; 4 s of it is 4.8e-7 m².
    g.predict(ResidualPrediction {
        mean: Vector3::zeros(),
        variance: Vector3::repeat(1e-8),
        absolute: None,
    })
    .unwrap();
    let mut processed = 0;
    for k in 1..=10_i64 {
        drive_frame(&mut g);
        processed += usize::from(g.decide(k * 2 * NS / 5, 0.4 * k as f64).processed);
    }
    assert_eq!(processed, 0);
    // An unsure one: 1e-4 per axis spends the budget by 0.8 s.
    g.predict(ResidualPrediction {
        mean: Vector3::zeros(),
        variance: Vector3::repeat(1e-4),
        absolute: None,
    })
    .unwrap();
    drive_frame(&mut g);
    drive_frame(&mut g);
    assert!(g.decide(12 * 2 * NS / 5, 4.8).processed);
}

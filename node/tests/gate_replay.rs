//! The live gate makes the offline scheme's decisions: on a traverse, the
//! offline front end runs a gated policy with ILGR learning online from
//! the statistical tracker; the live gate and learner are then driven in
//! lock-step over the same traverse, and for each pair the gate forwards
//! they are given the pose the offline VO produced for that frame (a null
//! pose where it lost track), as a VO behind the gate would publish it.
//! The gate must forward exactly the frames the offline scheme processed,
//! and the learner must end where the offline one did.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::collections::HashMap;

use gpodo_frontends::gate::GateState;
use gpodo_frontends::online::{OnlineLearner, OnlineMode};
use gpodo_frontends::params::{FrontendParams, VoSpec};
use gpodo_frontends::run_frontend;
use gpodo_frontends::scheme::causal_selector;
use gpodo_frontends::traverse::{Traverse, TraverseWindow};
use gpodo_frontends::vo::{CameraParams, SimulatedVo, SimulatedVoParams};
use gpodo_node::gate::{LiveGate, LiveGateSettings, PoseOutcome};
use gpodo_regressors::Ilgr;
use gpodo_traits::BodyTwist;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// The sensor period (s); the camera runs at 2.5 Hz, every fifth sample.
const DT: f64 = 0.08;

/// An S-curve at 5 cm/s for `secs`, the wheels 6 mm/s slow ahead, with
/// 1-s windows whose inputs follow the curve.
fn s_curve(secs: f64) -> Traverse {
    let n = (secs / DT).round() as usize + 1;
    // Times from nanosecond stamps, as a recording's are.
    let times: Vec<f64> = (0..n)
        .map(|k| (k as i64 * 80_000_000) as f64 * 1e-9)
        .collect();
    let pose = |t: f64| {
        let yaw = 0.6 * (0.05 * t).sin();
        Isometry3::from_parts(
            Translation3::new(0.05 * t, 0.3 * (0.05 * t).sin() * (0.05 * t), 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        )
    };
    let gt: Vec<Isometry3<f64>> = times.iter().map(|&t| pose(t)).collect();
    let slip = Vector3::new(0.006, 0.0, 0.0);
    let twists: Vec<BodyTwist> = gt
        .windows(2)
        .map(|w| {
            let delta = w[0].inverse() * w[1];
            BodyTwist {
                linear_mps: delta.translation.vector / DT - slip,
                angular_radps: delta.rotation.scaled_axis() / DT,
            }
        })
        .collect();
    let per_window = (1.0 / DT).round() as usize;
    let windows: Vec<TraverseWindow> = (0..(n - 1) / per_window)
        .map(|w| {
            let steps = w * per_window..(w + 1) * per_window;
            let t = times[steps.start];
            TraverseWindow {
                start_secs: t,
                end_secs: times[steps.end],
                steps,
                inputs: vec![(0.05 * t).sin(), (0.05 * t).cos()],
                true_residual: slip,
            }
        })
        .collect();
    let camera: Vec<f64> = times[..n - 1].iter().step_by(5).copied().collect();
    Traverse::new("s-curve", times, gt, twists, windows, camera).unwrap()
}

#[test]
fn the_live_gate_forwards_the_offline_schemes_frames_and_learns_the_same_model() {
    let vo = SimulatedVoParams {
        seed: 9,
        camera: CameraParams::default(),
        min_overlap: 0.3,
        features_per_frame: 300.0,
        ..SimulatedVoParams::default()
    };
    assert_eq!(gate_against_offline(vo), 0, "a wide window keeps track");
}

#[test]
fn the_live_gate_follows_the_offline_scheme_through_losses_and_relocalisations() {
    // A window of 2 px: the wheels' prior misses it after some gaps, and
    // the gate looks every 0.4 s until the tracker relocalises.
    let vo = SimulatedVoParams {
        seed: 4,
        search_radius_px: 2.0,
        search_softness_px: 0.5,
        ..SimulatedVoParams::default()
    };
    let lost = gate_against_offline(vo);
    assert!(lost > 5, "{lost} frames lost");
}

/// Runs the offline scheme and the live gate and learner against it;
/// returns the frames the VO lost.
fn gate_against_offline(vo_params: SimulatedVoParams) -> usize {
    let t = s_curve(600.0);
    let params = FrontendParams {
        vo: VoSpec::Simulated(vo_params),
        ..FrontendParams::default()
    };
    let spec = common::drift_budget_with_guard();
    let lost_period = params.lost_frame_period_secs;

    // Offline.
    let mut selector = causal_selector(&spec, lost_period, None).unwrap();
    let mut offline_learner = OnlineLearner::new(
        "ilgr",
        Box::new(Ilgr::new(common::ilgr_params()).unwrap()),
        OnlineMode::Update,
        params.initial_residual_variance,
    )
    .unwrap();
    let mut vo = SimulatedVo::new(vo_params, &t).unwrap();
    let run = run_frontend(
        &t,
        &params,
        selector.as_mut(),
        &mut offline_learner,
        &mut vo,
    )
    .unwrap();
    assert!(run.online_targets > 20, "{} targets", run.online_targets);
    let poses: HashMap<usize, Option<Isometry3<f64>>> =
        run.processed.iter().map(|f| (f.frame, f.vo_pose)).collect();

    // Live, in lock-step.
    let state = GateState::new(
        params.odometry,
        params.odometry_mode,
        params.initial_residual_variance,
    );
    let mut gate = LiveGate::new(
        causal_selector(&spec, lost_period, None).unwrap(),
        state,
        LiveGateSettings {
            targets: params.online,
            ..LiveGateSettings::default()
        },
    );
    let mut learner = common::live_ilgr(params.initial_residual_variance);
    let times = t.times_secs();
    let windows = t.windows();
    let mut step_window = vec![None; times.len() - 1];
    for (w, window) in windows.iter().enumerate() {
        for s in window.steps.clone() {
            step_window[s] = Some(w);
        }
    }
    let (mut step, mut next_window) = (0, 0);
    let mut forwarded = Vec::new();
    let (mut jumps, mut lost) = (0, 0);
    for (frame, &time) in t.camera_times_secs().iter().enumerate() {
        while times[step] < time {
            let inputs = step_window[step].map(|w| windows[w].inputs.as_slice());
            gate.drive(&t.twists()[step], times[step + 1] - times[step], inputs);
            step += 1;
            while windows
                .get(next_window)
                .is_some_and(|w| w.end_secs <= times[step])
            {
                let prediction = learner.predict(&windows[next_window].inputs).unwrap();
                gate.predict(prediction).unwrap();
                next_window += 1;
            }
        }
        let stamp_ns = (time * 1e9).round() as i64;
        assert_eq!(stamp_ns as f64 * 1e-9, time);
        if !gate.decide(stamp_ns, time).processed {
            continue;
        }
        forwarded.push(frame);
        let Some(offline) = poses.get(&frame) else {
            panic!("the gate forwarded frame {frame}, which the offline scheme skipped");
        };
        let (position, quaternion) = match offline {
            Some(p) => {
                let q = p.rotation.quaternion();
                (p.translation.vector.into(), [q.i, q.j, q.k, q.w])
            }
            None => ([0.0; 3], [0.0; 4]),
        };
        match gate.vo_pose(stamp_ns, position, quaternion, [1e-6; 3]) {
            PoseOutcome::Target(target) => learner.learn(&target).unwrap(),
            PoseOutcome::Jump => jumps += 1,
            PoseOutcome::Lost(_) => lost += 1,
            PoseOutcome::Pose(_) => {}
            PoseOutcome::Unexpected | PoseOutcome::OtherFrame => {
                panic!("frame {frame}: a pose for no forwarded pair")
            }
        }
    }
    let offline_frames: Vec<usize> = run.processed.iter().map(|f| f.frame).collect();
    assert_eq!(forwarded, offline_frames);
    assert_eq!(jumps, 0);
    assert_eq!(lost, run.processed.iter().filter(|f| !f.tracked).count());
    assert_eq!(learner.targets_learned(), run.online_targets as u64);
    // The learners end in the same state: the same predictions.
    common::assert_same_learner(&mut offline_learner, &learner);
    println!(
        "{} frames forwarded of {}, {} lost, {} targets",
        forwarded.len(),
        t.camera_times_secs().len(),
        lost,
        run.online_targets
    );
    lost
}

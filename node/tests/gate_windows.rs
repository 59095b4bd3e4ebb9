//! The node's gate session on the offline front end's window clock makes
//! the offline scheme's decisions with the VO in the loop.
//!
//! A traverse is sampled at 12.5 Hz with a camera at 2.5 Hz between the
//! samples and 1-s regressor windows that do not fall on samples, so steps
//! straddle window ends and frames fall inside steps. Offline,
//! `run_frontend` runs a gated policy with ILGR learning online from the
//! statistical tracker. Live, the session is fed each sample as an
//! odometry output and each pair once a sample at or after it has come,
//! as the replay does; every pair it forwards is processed by the same
//! front end stepped by the gate (`FrontEnd`), whose tracked pose (or a
//! null pose, lost) goes back as the VO's odometry. The gate must forward
//! exactly the frames the offline scheme processed, and the learners must
//! end in the same state.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use gpodo_datasets::residuals::{LogStep, window_rows};
use gpodo_frontends::gate::GateState;
use gpodo_frontends::online::{OnlineLearner, OnlineMode};
use gpodo_frontends::params::{FrontendParams, MotionPrior, VoSpec};
use gpodo_frontends::prediction::{Precomputed, ResidualPrediction};
use gpodo_frontends::run::FrontEnd;
use gpodo_frontends::scheme::causal_selector;
use gpodo_frontends::traverse::{Traverse, TraverseWindow};
use gpodo_frontends::vo::{FrameRef, SimulatedVo, SimulatedVoParams};
use gpodo_frontends::{SelectorSpec, run_frontend};
use gpodo_node::LiveOutput;
use gpodo_node::gate::pairing::{PairingSettings, StereoPair};
use gpodo_node::gate::session::{GateSession, LearnerEnd, Learning, PredictionClock};
use gpodo_node::gate::{LiveGate, LiveGateSettings};
use gpodo_regressors::Ilgr;
use gpodo_traits::BodyTwist;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// The sample period (ns): 12.5 Hz.
const DT_NS: i64 = 80_000_000;
/// The camera's period and its offset from the samples (ns).
const CAMERA_NS: (i64, i64) = (400_000_000, 30_000_000);
/// The regressor windows (s): 12.5 samples each.
const WINDOW_SECS: f64 = 1.0;

/// A sample's own inputs, varying within a window.
fn sample_inputs(t: f64) -> Vec<f64> {
    vec![(0.05 * t).sin() + 0.2 * (3.0 * t).sin(), (0.05 * t).cos()]
}

/// An S-curve at 5 cm/s for `secs`, the wheels 6 mm/s slow ahead; the
/// per-step inputs and the offline windows over them.
fn s_curve(secs: f64) -> (Traverse, Vec<LogStep>) {
    let n = (secs * 1e9) as i64 / DT_NS + 1;
    let times: Vec<f64> = (0..n).map(|k| (k * DT_NS) as f64 * 1e-9).collect();
    let pose = |t: f64| {
        let yaw = 0.6 * (0.05 * t).sin();
        Isometry3::from_parts(
            Translation3::new(0.05 * t, 0.3 * (0.05 * t).sin() * (0.05 * t), 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        )
    };
    let gt: Vec<Isometry3<f64>> = times.iter().map(|&t| pose(t)).collect();
    let slip = Vector3::new(0.006, 0.0, 0.0);
    let steps: Vec<LogStep> = times
        .windows(2)
        .zip(gt.windows(2))
        .map(|(t, g)| {
            let dt = t[1] - t[0];
            let delta = g[0].inverse() * g[1];
            LogStep {
                time_secs: t[0],
                dt_secs: dt,
                inputs: sample_inputs(t[0]),
                twist: BodyTwist {
                    linear_mps: delta.translation.vector / dt - slip,
                    angular_radps: delta.rotation.scaled_axis() / dt,
                },
                residual: slip,
            }
        })
        .collect();
    let windows = window_rows(&steps, WINDOW_SECS)
        .into_iter()
        .map(|r| TraverseWindow {
            start_secs: r.start_secs,
            end_secs: r.end_secs,
            steps: r.steps,
            inputs: r.inputs,
            true_residual: r.residual,
        })
        .collect();
    let last_ns = (n - 1) * DT_NS;
    let camera: Vec<f64> = (0..)
        .map(|j| CAMERA_NS.1 + j * CAMERA_NS.0)
        .take_while(|&ns| ns <= last_ns)
        .map(|ns| ns as f64 * 1e-9)
        .collect();
    let twists = steps.iter().map(|s| s.twist).collect();
    let traverse = Traverse::new("s-curve", times, gt, twists, windows, camera).unwrap();
    (traverse, steps)
}

/// An odometry output at sample `k`: its time, the step's twist from
/// there and the sample's inputs (the published row and residual do not
/// reach the gate on the window clock).
fn output(t: &Traverse, steps: &[LogStep], k: usize) -> LiveOutput {
    let time_secs = t.times_secs()[k];
    let twist = steps.get(k).map_or_else(BodyTwist::default, |s| s.twist);
    LiveOutput {
        inputs: sample_inputs(time_secs),
        ..common::output_at(time_secs, twist)
    }
}

#[test]
fn on_the_window_clock_the_gate_makes_the_offline_decisions_with_the_vo_in_the_loop() {
    let (lost, relocalised) = gate_against_offline(
        140.0,
        SimulatedVoParams {
            seed: 9,
            min_overlap: 0.3,
            features_per_frame: 300.0,
            ..SimulatedVoParams::default()
        },
    );
    assert_eq!((lost, relocalised), (0, 0), "a wide window keeps track");
}

#[test]
fn on_the_window_clock_the_gate_follows_the_offline_scheme_through_losses() {
    // A window of 2 px: the constant-velocity prior misses it, and from
    // then on the gate looks every 0.4 s (the S-curve never comes back to
    // a keyframe to relocalise against).
    let (lost, _) = gate_against_offline(
        300.0,
        SimulatedVoParams {
            seed: 4,
            search_radius_px: 2.0,
            search_softness_px: 0.5,
            ..SimulatedVoParams::default()
        },
    );
    assert!(lost > 5, "{lost} frames lost");
}

/// Runs the offline scheme over `secs` of the S-curve and the session
/// against it; returns the frames the VO lost and its relocalisations.
fn gate_against_offline(secs: f64, vo_params: SimulatedVoParams) -> (usize, usize) {
    let (t, steps) = s_curve(secs);
    // The VO behind the gate tracks with its own motion prior, as an
    // external SLAM does.
    let params = FrontendParams {
        vo: VoSpec::Simulated(vo_params),
        motion_prior: MotionPrior::ConstantVelocity,
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
    assert!(run.online_targets > 10, "{} targets", run.online_targets);

    // The VO in the loop: the same front end, stepped by the gate.
    let mut tracker = SimulatedVo::new(vo_params, &t).unwrap();
    let uninformed = ResidualPrediction::uninformed(params.initial_residual_variance);
    let mut no_model = Precomputed::new("none", vec![uninformed; t.windows().len()]);
    let mut behind = FrontEnd::new(&t, &params, &mut no_model, &mut tracker).unwrap();

    // Live, in lock-step.
    let gate = LiveGate::new(
        causal_selector(&spec, lost_period, None).unwrap(),
        GateState::new(
            params.odometry,
            params.odometry_mode,
            params.initial_residual_variance,
        ),
        LiveGateSettings {
            targets: params.online,
            ..LiveGateSettings::default()
        },
    );
    let learner = common::live_ilgr(params.initial_residual_variance);
    let mut session = GateSession::new(
        gate,
        PairingSettings::default(),
        Some(Learning::LockStep(Box::new(learner))),
        &["a".to_string(), "b".to_string()],
        PredictionClock::Windows {
            window_secs: WINDOW_SECS,
        },
        2.4,
    )
    .unwrap();
    let times = t.times_secs();
    let mut next_sample = 0;
    let mut forwarded = Vec::new();
    let mut lost = 0;
    for (frame, &time) in t.camera_times_secs().iter().enumerate() {
        // A pair is decided once a sample at or after it has come.
        while next_sample < times.len() && (next_sample == 0 || times[next_sample - 1] < time) {
            session
                .output(&output(&t, &steps, next_sample), next_sample as i64 * DT_NS)
                .unwrap();
            next_sample += 1;
        }
        let stamp_ns = CAMERA_NS.1 + frame as i64 * CAMERA_NS.0;
        let pair = StereoPair {
            stamp_ns,
            left: (),
            right: (),
            left_info: (),
            right_info: (),
        };
        let (decision, chosen) = session.decide(pair, time);
        if chosen.is_none() {
            continue;
        }
        forwarded.push(frame);
        behind.advance_to(time).unwrap();
        let processed = behind
            .process(
                FrameRef {
                    index: frame,
                    time_secs: time,
                },
                decision.keyframe_threshold_scale.unwrap_or(1.0),
            )
            .unwrap();
        let pose = match processed.vo_pose {
            Some(p) => {
                let q = p.rotation.quaternion();
                let x = p.translation.vector;
                [x.x, x.y, x.z, q.i, q.j, q.k, q.w]
            }
            None => {
                lost += 1;
                [0.0; 7]
            }
        };
        session.vo_odometry(&common::vo_odometry(stamp_ns, pose, 1e-6));
    }
    while next_sample < times.len() {
        session
            .output(&output(&t, &steps, next_sample), next_sample as i64 * DT_NS)
            .unwrap();
        next_sample += 1;
    }
    let counts = session.counts();
    let LearnerEnd::LockStep(learner) = session.finish() else {
        panic!("a lock-step learner");
    };

    let offline_frames: Vec<usize> = run.processed.iter().map(|f| f.frame).collect();
    assert_eq!(forwarded, offline_frames);
    assert_eq!(counts.jumps, 0);
    assert_eq!(lost, run.processed.iter().filter(|f| !f.tracked).count());
    assert_eq!(learner.targets_learned(), run.online_targets as u64);
    // The learners end in the same state: the same predictions.
    common::assert_same_learner(&mut offline_learner, &learner);
    println!(
        "{} frames forwarded of {}, {} lost, {} relocalisations, {} targets",
        forwarded.len(),
        t.camera_times_secs().len(),
        lost,
        run.relocalisations,
        run.online_targets
    );
    (lost, run.relocalisations)
}

#[test]
fn without_a_learner_the_saved_models_prediction_changes_only_at_window_ends() {
    let gate = LiveGate::new(
        causal_selector(
            &SelectorSpec::FixedRate {
                fps: 0.5,
                phase_secs: 0.0,
            },
            None,
            None,
        )
        .unwrap(),
        GateState::new(Default::default(), Default::default(), 1e-4),
        LiveGateSettings::default(),
    );
    let mut session: GateSession<()> = GateSession::new(
        gate,
        PairingSettings::default(),
        None,
        &["a".to_string(), "b".to_string()],
        PredictionClock::Windows {
            window_secs: WINDOW_SECS,
        },
        2.4,
    )
    .unwrap();
    // Samples every 0.3 s; the saved model's variance on each one's row
    // is 1e-6 times its index.
    let mut in_force = Vec::new();
    for k in 0..12_i64 {
        let out = LiveOutput {
            inputs: vec![0.0, 0.0],
            residual: Some(([0.0; 3], [1e-6 * k as f64; 3])),
            ..common::output_at(0.3 * k as f64, BodyTwist::default())
        };
        session.output(&out, k * 300_000_000).unwrap();
        // A pair at the sample: the gate is driven to it.
        session.decide(pair(k * 300_000_000), 0.0);
        in_force.push(session.prediction().variance.x);
    }
    // Windows end at 1, 2 and 3 s; the samples at or after them are 4
    // (1.2 s), 7 (2.1 s) and 10 (3.0 s). Before the first: the prior.
    let expected: Vec<f64> = (0..12_i64)
        .map(|k| match k {
            0..4 => 1e-4,
            4..7 => 1e-6 * 4.0,
            7..10 => 1e-6 * 7.0,
            _ => 1e-6 * 10.0,
        })
        .collect();
    assert_eq!(in_force, expected);
}

fn pair(stamp_ns: i64) -> StereoPair<()> {
    StereoPair {
        stamp_ns,
        left: (),
        right: (),
        left_info: (),
        right_info: (),
    }
}

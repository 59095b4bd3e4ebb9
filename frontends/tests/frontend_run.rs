//! Front-end runs on hand-made traverses: exact odometry and near-noiseless
//! visual odometry recover the trajectory; visual odometry corrects biased
//! wheels, more so with more frames; skipping frames without a prior loses
//! track and relocalises only at a mapped place; an online learner picks up
//! a constant residual and then asks for fewer frames; the oracle respects
//! its budget; a replayed SLAM log runs Table II's controls and the
//! hindsight search.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_frontends::gating::{UncertaintyBudget, UncertaintyBudgetParams};
use gpodo_frontends::odometry_mode::OdometryMode;
use gpodo_frontends::online::{OnlineLearner, OnlineMode};
use gpodo_frontends::oracle::{OracleParams, plan_frames};
use gpodo_frontends::params::{FrontendParams, MotionPrior, VoSpec};
use gpodo_frontends::prediction::{Precomputed, ResidualPrediction};
use gpodo_frontends::traverse::Traverse;
use gpodo_frontends::vo::{SimulatedVo, SimulatedVoParams};
use gpodo_frontends::{FixedRate, run_frontend};
use gpodo_regressors::{Ilgr, IlgrParams};
use nalgebra::Vector3;

mod common;
use common::{earlier_tracker, s_curve, traverse};

fn zero_predictions(t: &Traverse, variance: f64) -> Precomputed {
    Precomputed::new(
        "zero",
        vec![ResidualPrediction::uninformed(variance); t.windows().len()],
    )
}

fn params(vo: SimulatedVoParams) -> FrontendParams {
    FrontendParams {
        vo: VoSpec::Simulated(vo),
        ..FrontendParams::default()
    }
}

fn precise_vo() -> SimulatedVoParams {
    SimulatedVoParams {
        translation_sigma_m: 1e-9,
        translation_sigma_per_m: 0.0,
        rotation_sigma_rad: 1e-9,
        rotation_sigma_per_rad: 0.0,
        ..earlier_tracker()
    }
}

#[test]
fn exact_odometry_and_precise_vo_recover_the_trajectory() {
    let t = traverse(120.0, s_curve, Vector3::zeros(), &[0.0]);
    let p = params(precise_vo());
    let mut vo = SimulatedVo::new(precise_vo(), &t).unwrap();
    let mut selector = FixedRate::new(2.5).unwrap();
    let mut source = zero_predictions(&t, 1e-8);
    let run = run_frontend(&t, &p, &mut selector, &mut source, &mut vo).unwrap();
    assert_eq!(run.frames, 300);
    assert_eq!(run.processed[1].time_secs, 0.4);
    assert_eq!(run.tracking_losses, 0);
    assert!(run.keyframes >= 2);
    assert!(run.metrics.rmse_m < 1e-6, "{:?}", run.metrics);
    assert_eq!(run.trajectory.len(), t.len());
}

#[test]
fn vo_corrects_biased_wheels_and_more_frames_correct_more() {
    // The wheels see 8 mm/s less than the rover drives; the model knows
    // nothing of it (zero mean, a small variance).
    let bias = Vector3::new(0.008, 0.0, 0.0);
    let t = traverse(300.0, s_curve, bias, &[0.0]);
    let vo_params = SimulatedVoParams {
        seed: 4,
        ..earlier_tracker()
    };
    let p = params(vo_params);
    let run = |fps: f64| {
        let mut vo = SimulatedVo::new(vo_params, &t).unwrap();
        let mut selector = FixedRate::new(fps).unwrap();
        // A variance that covers the bias: the fusion trusts the VO.
        let mut source = zero_predictions(&t, 1e-4);
        run_frontend(&t, &p, &mut selector, &mut source, &mut vo).unwrap()
    };
    let (dense, sparse) = (run(2.5), run(0.2));
    let dead_reckoning = 0.008 * 300.0;
    println!(
        "final error: dead reckoning {dead_reckoning:.3} m, 2.5 fps {:.3} m, 0.2 fps {:.3} m",
        dense.metrics.final_error_m, sparse.metrics.final_error_m
    );
    // The source's covariance treats 1-s windows as independent, so a bias
    // that persists for the whole run is only partly removed.
    assert!(dense.metrics.final_error_m < 0.3 * dead_reckoning);
    assert!(sparse.metrics.final_error_m < dead_reckoning);
    assert!(dense.metrics.rmse_m < sparse.metrics.rmse_m);
}

/// 1 m east in 20 s, a quarter turn left on the spot in 10 s, back to
/// east in 10 s, then 1 m further east: sparse frames lose track in the
/// turn.
fn quarter_turn() -> Traverse {
    let quarter = std::f64::consts::FRAC_PI_2;
    let path = move |t: f64| match t {
        t if t < 20.0 => (0.05 * t, 0.0, 0.0),
        t if t < 30.0 => (1.0, 0.0, quarter * (t - 20.0) / 10.0),
        t if t < 40.0 => (1.0, 0.0, quarter * (40.0 - t) / 10.0),
        t => (1.0 + 0.05 * (t - 40.0), 0.0, 0.0),
    };
    traverse(60.0, path, Vector3::zeros(), &[0.0])
}

#[test]
fn a_fast_turn_between_sparse_frames_loses_track_and_relocalises_at_a_mapped_place() {
    let t = quarter_turn();
    let vo_params = earlier_tracker();
    let p = params(vo_params);
    let mut vo = SimulatedVo::new(vo_params, &t).unwrap();
    // One frame every 5 s: the frames at 25 s and 30 s look 45° and 90°
    // away from every keyframe; the one at 40 s looks where the rover
    // looked at 20 s.
    let mut selector = FixedRate::new(0.2).unwrap();
    let mut source = zero_predictions(&t, 1e-6);
    let run = run_frontend(&t, &p, &mut selector, &mut source, &mut vo).unwrap();
    println!(
        "losses {}, relocalisations {}, lost {:.1} s, frames {:?}",
        run.tracking_losses,
        run.relocalisations,
        run.lost_secs,
        run.processed
            .iter()
            .map(|f| (f.time_secs, f.tracked, f.keyframe))
            .collect::<Vec<_>>()
    );
    assert_eq!(run.tracking_losses, 1);
    assert_eq!(run.relocalisations, 1);
    // Lost half-way through the turn (25 s), relocalised at 40 s.
    assert!(
        run.lost_secs > 9.0 && run.lost_secs < 16.0,
        "{}",
        run.lost_secs
    );
    assert!(
        run.processed
            .iter()
            .any(|f| f.time_secs > 39.0 && f.time_secs < 41.0 && f.tracked)
    );
    // Processing every frame the turn is tracked all the way.
    let mut vo = SimulatedVo::new(vo_params, &t).unwrap();
    let mut selector = FixedRate::new(2.5).unwrap();
    let run = run_frontend(&t, &p, &mut selector, &mut source, &mut vo).unwrap();
    assert_eq!(run.tracking_losses, 0);
}

#[test]
fn an_online_learner_picks_up_a_constant_residual_and_then_looks_less() {
    let bias = Vector3::new(0.006, 0.0, 0.0);
    let t = traverse(900.0, s_curve, bias, &[0.3, -0.2]);
    let vo_params = SimulatedVoParams {
        seed: 9,
        ..earlier_tracker()
    };
    let p = params(vo_params);
    let mut vo = SimulatedVo::new(vo_params, &t).unwrap();
    let mut selector = UncertaintyBudget::new(UncertaintyBudgetParams {
        budget_m2: 1e-4,
        min_period_secs: 0.4,
        count_mean: Some(false),
    })
    .unwrap();
    let model = Ilgr::new(IlgrParams {
        init_lengthscale: 2.0,
        ..IlgrParams::default()
    })
    .unwrap();
    let mut source = OnlineLearner::new("ilgr", Box::new(model), OnlineMode::Update, 1e-4).unwrap();
    let run = run_frontend(&t, &p, &mut selector, &mut source, &mut vo).unwrap();
    let count = |a: f64, b: f64| {
        run.processed
            .iter()
            .filter(|f| f.time_secs >= a && f.time_secs < b)
            .count()
    };
    // Frames per second while the model knows nothing (the first 40 s)
    // and once it has learned (the last 150 s).
    let (early, late) = (
        count(0.0, 40.0) as f64 / 40.0,
        count(750.0, 900.0) as f64 / 150.0,
    );
    let last = run.predictions.last().unwrap().1;
    println!(
        "targets {}, frames early {early:.2}/s, late {late:.2}/s, final prediction {:?} ± {:?}",
        run.online_targets,
        last.mean,
        last.variance.map(f64::sqrt)
    );
    for (t, p) in run.predictions.iter().step_by(100) {
        println!(
            "t {t:6.1}: mean {:.4?} std {:.4?}",
            p.mean.as_slice(),
            p.variance.map(f64::sqrt).as_slice()
        );
    }
    assert!(run.online_targets > 50);
    assert!((last.mean.x - 0.006).abs() < 0.002, "{:?}", last.mean);
    // The VO noise in the targets sets a floor to the model's variance;
    // once the mean is learned the rover looks at most two thirds as often.
    assert!(late < 0.67 * early, "early {early:.2}/s, late {late:.2}/s");
}

#[test]
fn the_oracle_respects_its_budget_and_gap_limit() {
    let t = traverse(200.0, s_curve, Vector3::new(0.004, 0.0, 0.0), &[0.0]);
    let vo = SimulatedVo::new(earlier_tracker(), &t).unwrap();
    let predictions = vec![Vector3::zeros(); t.windows().len()];
    let params = OracleParams {
        frames: Some(60),
        max_gap_secs: 10.0,
        max_distance_m: None,
        ..OracleParams::default()
    };
    let plan = plan_frames(&t, &predictions, &vo, MotionPrior::Odometry, &params, 60).unwrap();
    assert!(
        plan.frames.len() <= 60 && plan.frames.len() >= 20,
        "{}",
        plan.frames.len()
    );
    assert_eq!(plan.frames[0], 0);
    for w in plan.times_secs.windows(2) {
        assert!(w[1] - w[0] <= 10.0 + 1e-9);
    }
    // A larger budget cannot cost more.
    let more = plan_frames(&t, &predictions, &vo, MotionPrior::Odometry, &params, 90).unwrap();
    assert!(more.cost <= plan.cost);
    // Too small a budget to respect the gap limit plans the fewest that do.
    let raised = plan_frames(&t, &predictions, &vo, MotionPrior::Odometry, &params, 5).unwrap();
    assert!(raised.frames.len() > 5 && raised.frames.len() <= 60);
    // A distance limit holds between consecutive frames.
    let limited = OracleParams {
        max_distance_m: Some(0.2),
        ..params.clone()
    };
    let plan = plan_frames(&t, &predictions, &vo, MotionPrior::Odometry, &limited, 300).unwrap();
    for w in plan.times_secs.windows(2) {
        let (a, b) = (t.sample_at_or_before(w[0]), t.sample_at_or_before(w[1]));
        assert!(t.distance_at(b) - t.distance_at(a) <= 0.2 + 1e-9, "{w:?}");
    }
}

#[test]
fn a_replayed_vo_log_drives_the_front_end_and_its_gaps_are_losses() {
    use gpodo_frontends::tum::{StampedPose, format_tum, parse_tum};
    use gpodo_frontends::vo::{ReplayVo, ReplayVoParams};
    // The rover drives 0.05 m/s east; the SLAM log of every frame is the
    // truth, except 20–24 s where it lost track.
    let t = traverse(
        60.0,
        |t| (0.05 * t, 0.0, 0.0),
        Vector3::new(0.004, 0.0, 0.0),
        &[0.0],
    );
    let log: Vec<StampedPose> = t
        .camera_times_secs()
        .iter()
        .filter(|&&s| !(20.0..24.0).contains(&s))
        .map(|&s| StampedPose {
            time_secs: s,
            pose: t.ground_truth_at(s),
        })
        .collect();
    // Through the file format, as a user's log would come.
    let log = parse_tum(&format_tum("replay", &log), "log.tum").unwrap();
    let params = ReplayVoParams {
        path: "log.tum".into(),
        ..ReplayVoParams::default()
    };
    let mut vo = ReplayVo::new(params.clone(), &t, &log).unwrap();
    assert_eq!(vo.logged_frames(), t.camera_times_secs().len() - 50);
    let p = FrontendParams {
        vo: VoSpec::Replay(params),
        ..FrontendParams::default()
    };
    let mut selector = FixedRate::new(2.5).unwrap();
    let mut source = zero_predictions(&t, 1e-4);
    let run = run_frontend(&t, &p, &mut selector, &mut source, &mut vo).unwrap();
    println!(
        "replay: losses {}, relocalisations {}, lost {:.1} s, RMSE {:.4} m",
        run.tracking_losses, run.relocalisations, run.lost_secs, run.metrics.rmse_m
    );
    assert_eq!(run.tracking_losses, 1);
    assert_eq!(run.relocalisations, 1);
    assert!(
        run.lost_secs >= 4.0 && run.lost_secs < 5.0,
        "{}",
        run.lost_secs
    );
    // The log is exact: the fused trajectory is far better than the biased
    // wheels (0.004 m/s × 60 s = 0.24 m).
    assert!(run.metrics.final_error_m < 0.05, "{:?}", run.metrics);
}

#[test]
fn the_hindsight_search_is_never_worse_than_the_policy_it_starts_from() {
    use gpodo_frontends::SelectorSpec;
    use gpodo_frontends::hindsight::HindsightSearchParams;
    use gpodo_frontends::scheme::{SchemeContext, SchemeResiduals, SchemeSpecRef, run_scheme};

    let t = traverse(200.0, s_curve, Vector3::new(0.006, 0.0, 0.0), &[0.0]);
    let predictions = vec![ResidualPrediction::uninformed(1e-4); t.windows().len()];
    let residuals = || SchemeResiduals::Trained {
        label: "zero".into(),
        predictions: predictions.clone(),
    };
    let mut improved = 0;
    for seed in [1, 2, 3] {
        let p = params(SimulatedVoParams {
            seed,
            ..earlier_tracker()
        });
        let ctx = SchemeContext {
            params: &p,
            matched_frames: None,
            matched_times: None,
            recorded_vo: None,
            frames: None,
        };
        for budget_m2 in [2e-5, 1e-4] {
            let causal_spec = SelectorSpec::UncertaintyBudget(UncertaintyBudgetParams {
                budget_m2,
                ..UncertaintyBudgetParams::default()
            });
            let causal = run_scheme(
                &SchemeSpecRef::new("causal", &causal_spec),
                &t,
                residuals(),
                &ctx,
            )
            .unwrap();
            let times: Vec<f64> = causal.run.processed.iter().map(|f| f.time_secs).collect();
            let oracle_spec = SelectorSpec::Oracle(OracleParams {
                same_as: Some("causal".into()),
                search: Some(HindsightSearchParams {
                    evaluations: 12,
                    seed: 0,
                }),
                ..OracleParams::default()
            });
            let oracle = run_scheme(
                &SchemeSpecRef::new("hindsight", &oracle_spec),
                &t,
                residuals(),
                &SchemeContext {
                    matched_frames: Some(causal.run.frames),
                    matched_times: Some(&times),
                    recorded_vo: None,
                    frames: None,
                    ..ctx
                },
            )
            .unwrap();
            let search = oracle.oracle.and_then(|o| o.search).unwrap();
            // Replaying the policy's frames reproduces its run exactly (same
            // tracker streams), so the search starts no worse than it.
            assert_eq!(search.start_rmse_m[0], causal.run.metrics.rmse_m);
            assert_eq!(oracle.run.frames, causal.run.frames, "seed {seed}");
            // On the draws it searched, never worse than where it started.
            assert!(
                search.rmse_m <= causal.run.metrics.rmse_m,
                "seed {seed}, budget {budget_m2}: {} > {}",
                search.rmse_m,
                causal.run.metrics.rmse_m
            );
            // The row reports the schedule on other draws.
            assert_eq!(search.fresh_draws_rmse_m, Some(oracle.run.metrics.rmse_m));
            assert_ne!(search.rmse_m, oracle.run.metrics.rmse_m, "seed {seed}");
            improved += usize::from(search.rmse_m < causal.run.metrics.rmse_m);
        }
    }
    // The search does find better schedules, not only keep the start.
    assert!(improved >= 3, "improved on {improved} of 6");
}

#[test]
fn a_replayed_log_runs_the_table_two_controls_and_the_hindsight_search() {
    use gpodo_frontends::SelectorSpec;
    use gpodo_frontends::hindsight::HindsightSearchParams;
    use gpodo_frontends::scheme::{SchemeContext, SchemeResiduals, SchemeSpecRef, run_scheme};
    use gpodo_frontends::tum::{StampedPose, format_tum};
    use gpodo_frontends::vo::ReplayVoParams;

    // The rover drives 0.05 m/s east with wheels 4 mm/s slow; the logged
    // SLAM poses are the truth except 20–24 s, where it lost track.
    let bias = Vector3::new(0.004, 0.0, 0.0);
    let t = traverse(60.0, |t| (0.05 * t, 0.0, 0.0), bias, &[0.0]);
    let log: Vec<StampedPose> = t
        .camera_times_secs()
        .iter()
        .filter(|&&s| !(20.0..24.0).contains(&s))
        .map(|&s| StampedPose {
            time_secs: s,
            pose: t.ground_truth_at(s),
        })
        .collect();
    let dir = std::env::temp_dir().join(format!("gpodo-replay-controls-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("log.tum"), format_tum("replay", &log)).unwrap();
    let p = FrontendParams {
        vo: VoSpec::Replay(ReplayVoParams {
            path: dir.join("log.tum"),
            ..ReplayVoParams::default()
        }),
        ..FrontendParams::default()
    };
    let ctx = SchemeContext {
        params: &p,
        matched_frames: None,
        matched_times: None,
        recorded_vo: None,
        frames: None,
    };
    let n = t.windows().len();
    let gp = || SchemeResiduals::Trained {
        label: "gp".into(),
        predictions: vec![
            ResidualPrediction {
                mean: bias,
                ..ResidualPrediction::uninformed(1e-6)
            };
            n
        ],
    };
    let zero = || SchemeResiduals::Trained {
        label: "zero".into(),
        predictions: vec![ResidualPrediction::uninformed(1e-4); n],
    };
    let run = |label: &str, selector: &SelectorSpec, residuals, ctx: &SchemeContext<'_>| {
        run_scheme(&SchemeSpecRef::new(label, selector), &t, residuals, ctx).unwrap()
    };
    let gated = SelectorSpec::UncertaintyBudget(UncertaintyBudgetParams {
        budget_m2: 1e-5,
        ..UncertaintyBudgetParams::default()
    });
    let fixed = |fps| SelectorSpec::FixedRate {
        fps,
        phase_secs: 0.0,
    };
    let policy = run("gated", &gated, gp(), &ctx);
    let on_zero = run("gated, zero residuals", &gated, zero(), &ctx);
    let dense = run("2.5 fps", &fixed(2.5), gp(), &ctx);
    let sparse = run("0.5 fps", &fixed(0.5), gp(), &ctx);
    assert_eq!(dense.run.frames, 150);
    assert_eq!(sparse.run.frames, 30);
    for r in [&policy, &on_zero, &dense, &sparse] {
        // Every scheme meets the logged gap (a loss) unless it skips it.
        assert!(
            r.run.tracking_losses <= 1,
            "{}: {:?}",
            r.label,
            r.run.tracking_losses
        );
        assert!(r.run.metrics.rmse_m.is_finite());
    }
    assert_eq!(dense.run.tracking_losses, 1);
    // The selector reads the residuals: the GP's confident predictions and
    // the zero regressor's uninformed ones ask for different frames.
    assert_ne!(policy.run.frames, on_zero.run.frames);
    // The hindsight search replays the policy's frames over the same log.
    let times: Vec<f64> = policy.run.processed.iter().map(|f| f.time_secs).collect();
    let oracle = SelectorSpec::Oracle(OracleParams {
        same_as: Some("gated".into()),
        search: Some(HindsightSearchParams {
            evaluations: 6,
            seed: 1,
        }),
        ..OracleParams::default()
    });
    let searched = run(
        "hindsight",
        &oracle,
        gp(),
        &SchemeContext {
            matched_frames: Some(policy.run.frames),
            matched_times: Some(&times),
            recorded_vo: None,
            frames: None,
            ..ctx
        },
    );
    // At most the policy's frames (the surrogate plan may use fewer), and
    // never worse.
    assert!(searched.run.frames <= policy.run.frames);
    assert!(searched.run.metrics.rmse_m <= policy.run.metrics.rmse_m);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn while_lost_a_gated_scheme_looks_every_0_4_s_and_a_fixed_rate_keeps_its_rate() {
    use gpodo_frontends::SelectorSpec;
    use gpodo_frontends::scheme::{SchemeContext, SchemeResiduals, SchemeSpecRef, run_scheme};

    let t = quarter_turn();
    let p = params(earlier_tracker());
    let ctx = SchemeContext {
        params: &p,
        matched_frames: None,
        matched_times: None,
        recorded_vo: None,
        frames: None,
    };
    let residuals = || SchemeResiduals::Trained {
        label: "zero".into(),
        predictions: vec![ResidualPrediction::uninformed(1e-6); t.windows().len()],
    };
    let run = |selector: &SelectorSpec| {
        run_scheme(&SchemeSpecRef::new("s", selector), &t, residuals(), &ctx)
            .unwrap()
            .run
    };
    // A budget nothing reaches, guarded every 5 s: 0.2 fps while tracking.
    let gated = SelectorSpec::MaxGap {
        inner: Box::new(SelectorSpec::UncertaintyBudget(UncertaintyBudgetParams {
            budget_m2: 1.0,
            ..UncertaintyBudgetParams::default()
        })),
        max_gap_secs: Some(5.0),
        max_distance_m: None,
        max_rotation_rad: None,
    };
    let fixed = SelectorSpec::FixedRate {
        fps: 0.2,
        phase_secs: 0.0,
    };
    // Gaps between consecutive processed frames from a lost tracker.
    let lost_gaps = |run: &gpodo_frontends::FrontendRun| -> Vec<f64> {
        run.processed
            .windows(2)
            .filter(|w| !w[0].tracked)
            .map(|w| w[1].time_secs - w[0].time_secs)
            .collect()
    };
    let gated_run = run(&gated);
    let fixed_run = run(&fixed);
    assert!(gated_run.tracking_losses >= 1 && fixed_run.tracking_losses >= 1);
    let (g, f) = (lost_gaps(&gated_run), lost_gaps(&fixed_run));
    assert!(
        !g.is_empty() && g.iter().all(|d| (d - 0.4).abs() < 0.05),
        "{g:?}"
    );
    assert!(
        !f.is_empty() && f.iter().all(|d| (d - 5.0).abs() < 0.05),
        "{f:?}"
    );
    // Looking every 0.4 s, the gated scheme is found again sooner.
    assert!(gated_run.lost_secs < fixed_run.lost_secs);
}

#[test]
fn with_shared_errors_only_keyframes_are_graph_nodes_and_frames_follow_their_keyframe() {
    use gpodo_frontends::vo::TrackerErrorModel;

    let t = traverse(120.0, s_curve, Vector3::zeros(), &[0.0]);
    let run = |error_model: TrackerErrorModel, vo_params: SimulatedVoParams| {
        let vo_params = SimulatedVoParams {
            error_model,
            ..vo_params
        };
        let mut vo = SimulatedVo::new(vo_params, &t).unwrap();
        let mut selector = FixedRate::new(2.5).unwrap();
        let mut source = zero_predictions(&t, 1e-6);
        run_frontend(&t, &params(vo_params), &mut selector, &mut source, &mut vo).unwrap()
    };
    let shared = run(TrackerErrorModel::Shared, earlier_tracker());
    let independent = run(TrackerErrorModel::Independent, earlier_tracker());
    // The start pose and the keyframes; or the start pose and every frame.
    assert_eq!(shared.graph_nodes, shared.keyframes + 1);
    assert_eq!(independent.graph_nodes, independent.frames + 1);
    assert!(
        shared.keyframes * 5 < shared.frames,
        "{} of {}",
        shared.keyframes,
        shared.frames
    );
    // A precise tracker: every frame between keyframes is placed by its
    // keyframe's pose and its own measurement, so the trajectory is exact
    // up to the odometry since the last frame (exact here).
    let precise = run(TrackerErrorModel::Shared, precise_vo());
    assert_eq!(precise.graph_nodes, precise.keyframes + 1);
    assert!(precise.metrics.rmse_m < 1e-4, "{}", precise.metrics.rmse_m);
}

/// The odometry modes: the authors' (uncorrected, σ = the |residual|
/// regressor's prediction) leaves the wheels as they are, so with one
/// frame its trajectory is the uncorrected odometry's, while the corrected
/// mode removes the bias; a drift budget counts the uncorrected error
/// under the authors' mode and the corrected odometry's variance under
/// gpodo's; the authors' mode without a |residual| regressor is an error.
#[test]
fn the_odometry_mode_decides_correction_covariance_and_budget() {
    use gpodo_frontends::SelectorSpec;
    use gpodo_frontends::prediction::AbsolutePrediction;
    use gpodo_frontends::scheme::{SchemeContext, SchemeResiduals, SchemeSpecRef, run_scheme};

    let bias = Vector3::new(0.004, 0.0, 0.0);
    let t = traverse(60.0, |t| (0.05 * t, 0.0, 0.0), bias, &[0.0]);
    let p = FrontendParams::default();
    let ctx = SchemeContext {
        params: &p,
        matched_frames: None,
        matched_times: None,
        recorded_vo: None,
        frames: None,
    };
    let n = t.windows().len();
    let predictions = |absolute: bool| SchemeResiduals::Trained {
        label: "gp".into(),
        predictions: vec![
            ResidualPrediction {
                mean: bias,
                variance: Vector3::repeat(1e-12),
                absolute: absolute.then_some(AbsolutePrediction {
                    mean: bias.abs(),
                    variance: Vector3::repeat(1e-12),
                }),
            };
            n
        ],
    };
    let zero = SchemeResiduals::Trained {
        label: "zero".into(),
        predictions: vec![ResidualPrediction::uninformed(1e-12); n],
    };
    let run = |selector: &SelectorSpec, mode: OdometryMode, residuals| {
        run_scheme(
            &SchemeSpecRef {
                odometry: mode,
                ..SchemeSpecRef::new("s", selector)
            },
            &t,
            residuals,
            &ctx,
        )
    };
    // One frame in 60 s: the trajectory is the odometry.
    let once = SelectorSpec::FixedRate {
        fps: 0.01,
        phase_secs: 0.0,
    };
    let corrected = run(&once, OdometryMode::CORRECTED, predictions(true)).unwrap();
    let authors = run(&once, OdometryMode::AUTHORS, predictions(true)).unwrap();
    let uncorrected = run(&once, OdometryMode::CORRECTED, zero).unwrap();
    assert_eq!(authors.run.frames, 1);
    assert!(
        (authors.run.metrics.rmse_m - uncorrected.run.metrics.rmse_m).abs() < 1e-12,
        "{} vs {}",
        authors.run.metrics.rmse_m,
        uncorrected.run.metrics.rmse_m
    );
    assert!(
        corrected.run.metrics.rmse_m < 0.1 * authors.run.metrics.rmse_m,
        "{} vs {}",
        corrected.run.metrics.rmse_m,
        authors.run.metrics.rmse_m
    );
    // The budget: under the authors' mode each 1-s window adds
    // (4 mm/s · 1 s)², so (5 mm)² fills in two windows (about 30 frames in
    // 60 s); the corrected odometry's variance fills it only before the
    // first prediction (the uninformed 1e-4 (m/s)²).
    let budget = SelectorSpec::UncertaintyBudget(UncertaintyBudgetParams::default());
    let counted = run(&budget, OdometryMode::AUTHORS, predictions(true)).unwrap();
    let variance_only = run(&budget, OdometryMode::CORRECTED, predictions(true)).unwrap();
    assert!(
        counted.run.frames >= 25 && variance_only.run.frames <= 5,
        "{} and {} frames",
        counted.run.frames,
        variance_only.run.frames
    );
    let err = run(&once, OdometryMode::AUTHORS, predictions(false)).unwrap_err();
    assert!(err.to_string().contains("|residual|"), "{err}");
}

#[test]
fn the_keyframe_aware_oracle_plans_only_gaps_bridged_from_the_reference() {
    use gpodo_frontends::vo::{FrameRef, TrackPurpose, TrackRequest, VisualOdometry};
    // Biased wheels, so the odometry prior errs more the further back its
    // start: the request from an earlier keyframe is the harder one.
    let t = traverse(200.0, s_curve, Vector3::new(0.01, 0.0, 0.0), &[0.0]);
    let vo = SimulatedVo::new(earlier_tracker(), &t).unwrap();
    let predictions = vec![Vector3::zeros(); t.windows().len()];
    let plain = OracleParams {
        frames: Some(60),
        max_distance_m: None,
        max_rotation_rad: None,
        ..OracleParams::default()
    };
    let aware = OracleParams {
        keyframe_overlap: Some(0.8),
        ..plain.clone()
    };
    let plan = |p: &OracleParams, budget| {
        plan_frames(&t, &predictions, &vo, MotionPrior::Odometry, p, budget).unwrap()
    };
    // At 40 frames the constraint needs more: the fewest it can plan.
    assert!(plan(&aware, 40).frames.len() > plan(&plain, 40).frames.len());
    // At 60 both plan 60; a constraint added cannot lower the optimum.
    let (plain_plan, aware_plan) = (plan(&plain, 60), plan(&aware, 60));
    // The plan checked below: the one at the fewest frames, whose gaps
    // press against the constraint.
    let aware_plan_40 = plan(&aware, 40);
    assert_eq!(aware_plan.frames.len(), plain_plan.frames.len());
    assert!(aware_plan.cost >= plain_plan.cost - 1e-12);

    // Recompute the reference of every planned gap here: the candidate
    // grid, the furthest earlier candidate overlapping the gap's start by
    // 0.8 or more, the odometry prior integrated over the gap.
    let camera = t.camera_times_secs();
    let mut grid = vec![0usize];
    for (i, &time) in camera.iter().enumerate().skip(1) {
        if time - camera[grid[grid.len() - 1]] >= 0.4 - 1e-9 {
            grid.push(i);
        }
    }
    let frame = |i: usize| FrameRef {
        index: i,
        time_secs: camera[i],
    };
    let times = t.times_secs();
    let mut checked_further_back = 0;
    for w in aware_plan_40.frames.windows(2) {
        let (a, b) = (w[0], w[1]);
        let at = grid.iter().position(|&c| c == a).unwrap();
        let mut r = at;
        while r > 0 && vo.predicted_overlap(frame(grid[r - 1]), frame(a)).unwrap() >= 0.8 {
            r -= 1;
        }
        let mut k = t.sample_at_or_before(camera[a]);
        if times[k] < camera[a] {
            k += 1;
        }
        let mut odometry = nalgebra::Isometry3::identity();
        while times[k] < camera[b] {
            odometry *= t.twists()[k].pose_delta(times[k + 1] - times[k]);
            k += 1;
        }
        let r_from_a = t.ground_truth_at(camera[grid[r]]).inverse() * t.ground_truth_at(camera[a]);
        let p = vo.success_probability(&TrackRequest {
            reference: frame(grid[r]),
            current: frame(b),
            prior: Some(r_from_a * odometry),
            purpose: TrackPurpose::Tracking,
        });
        assert!(p >= 0.99, "gap {a} → {b} from reference {}: {p}", grid[r]);
        checked_further_back += usize::from(r < at);
    }
    assert!(checked_further_back > 0, "no gap had an earlier reference");
}

//! On a recording, the live gate makes the offline scheme's decisions.
//!
//! A simulated drive is recorded as `gpodo simulate --camera --format
//! mcap` records it: joint states, IMU, ground truth, a stereo camera at
//! 2.5 fps and a VO topic at the frames. Offline, the recording is imported
//! as `gpodo run` imports it and the front end runs the gate file's policy
//! with its learner learning online from the statistical tracker. Live,
//! the recording is replayed through the node's feed (joint states as they
//! come, the IMU held) and gate, and every pair the gate forwards goes to
//! the same VO (the statistical tracker, or the stereo VO on the recorded
//! images), in the front end stepped by the gate (`FrontEnd`), whose
//! tracked pose (or a null pose, lost) comes back as the VO's odometry.
//! The gate must forward exactly the frames the offline scheme processed,
//! with a tracker that keeps track and with one that loses it, and the
//! learners must end in the same state.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use gpodo_datasets::bags::write::{
    WheelUnits, write_mcap, write_mcap_with_camera, written_topic_map_in,
};
use gpodo_datasets::bags::write_camera::CameraStream;
use gpodo_experiments::commands::live_gate::{Learner, LiveGateRun};
use gpodo_experiments::commands::replay_frontend::{FrontEndVo, RecordedTraverse};
use gpodo_frontends::online::{OnlineLearner, OnlineMode};
use gpodo_frontends::params::{FrontendParams, MotionPrior, VoSpec};
use gpodo_frontends::prediction::{Precomputed, ResidualPrediction, ResidualSource};
use gpodo_frontends::run::FrontEnd;
use gpodo_frontends::run_frontend;
use gpodo_frontends::scheme::causal_selector;
use gpodo_frontends::vo::SimulatedVoParams;
use gpodo_frontends::vo::stereo::StereoVoParams;
use gpodo_node::gate::GateDecision;
use gpodo_node::gate::session::LearnerEnd;
use gpodo_node::replay::{GatedReplay, Playback, RecordedPair, replay_gated};
use gpodo_regressors::model_file::ModelFile;
use gpodo_testbed::camera::traverse::{camera_stream, frame_times, pose_at};
use gpodo_testbed::camera::{GroundMaps, SceneSpec, SensorSpec, StereoRenderer};
use gpodo_testbed::sim::preset::{Preset, SimulatorConfig};
use gpodo_traits::CameraParams;
use gpodo_vision::GrayImage;

use common::{assert_succeeded, exoter, fit_bag_model, gpodo_live_gated};

const GATE: &str = "\
selector:
  kind: max_gap
  max_gap_secs: null
  max_rotation_rad: 0.15
  max_distance_m: 0.3
  inner: { kind: uncertainty_budget, budget_m2: 1.0e-4, count_mean: false }
online: { regressor: { kind: ilgr, init_lengthscale: 2.0 } }
lost_frame_period_secs: 0.4
predictions: windows
lost: { silent_secs: 1.0 }
topics:
  left_image: /camera/left/image_raw
  right_image: /camera/right/image_raw
  left_info: /camera/left/camera_info
  right_info: /camera/right/camera_info
  vo_odometry: /vo/pose
";

#[test]
fn on_a_recording_the_live_gate_makes_the_offline_schemes_decisions() {
    let (lost, targets) = gate_against_offline(
        "kind: simulated, seed: 11",
        VoSpec::Simulated(SimulatedVoParams {
            seed: 11,
            ..SimulatedVoParams::default()
        }),
        None,
    );
    assert_eq!(lost, 0, "a wide window keeps track");
    assert!(targets > 10, "{targets} targets");
}

#[test]
fn on_a_recording_the_live_gate_follows_the_offline_scheme_through_losses() {
    // Tracking succeeds half the time at an overlap of 0.86, with a prior
    // or without: the tracker loses track early and, on a route that never
    // comes back, stays lost; the gate looks every 0.4 s.
    let (lost, _) = gate_against_offline(
        "kind: simulated, seed: 4, min_overlap: 0.86, prior_free_min_overlap: 0.86, overlap_softness: 0.03",
        VoSpec::Simulated(SimulatedVoParams {
            seed: 4,
            min_overlap: 0.86,
            prior_free_min_overlap: 0.86,
            overlap_softness: 0.03,
            ..SimulatedVoParams::default()
        }),
        None,
    );
    assert!(lost > 5, "{lost} frames lost");
}

#[test]
fn on_a_recording_the_live_gate_makes_the_offline_decisions_with_the_stereo_vo_on_its_images() {
    // The rendered camera at a quarter of ExoTeR's 1024 × 768; the stereo
    // VO reads the recorded camera infos' intrinsics and baseline.
    let (_, targets) = gate_against_offline(
        "kind: stereo",
        VoSpec::Stereo(StereoVoParams::default()),
        Some(0.25),
    );
    assert!(targets > 3, "{targets} targets");
}

/// Runs the offline scheme and the replayed node on one recording with
/// the VO `vo` (written `vo_yaml` in a gate file) behind the gate, the
/// camera rendered at `rendered` times ExoTeR's size (else flat images:
/// the gate and the statistical tracker read no pixels); returns the
/// frames the VO lost and the targets learned.
fn gate_against_offline(vo_yaml: &str, vo: VoSpec, rendered: Option<f64>) -> (usize, usize) {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let mut config = SimulatorConfig::preset(Preset::ExoterPrl, 5);
    config.training_runs = 1;
    config.training_run_secs = 60.0;
    config.test_max_secs = if rendered.is_some() { 60.0 } else { 150.0 };
    let testbed = config.simulate().unwrap();
    std::fs::create_dir_all(dir.join("train")).unwrap();
    std::fs::create_dir_all(dir.join("test")).unwrap();
    let train = write_mcap(&testbed.train[0], &dir.join("train"))
        .unwrap()
        .path;
    let log = &testbed.test[0];
    let ground = rendered.map(|_| {
        GroundMaps::build(&testbed.terrain, &testbed.soils, &SceneSpec::default(), 3).unwrap()
    });
    let renderer = rendered.zip(ground.as_ref()).map(|(scale, ground)| {
        StereoRenderer::new(
            CameraParams::exoter_bumblebee2().scaled(scale),
            ground,
            SensorSpec::default(),
            3,
        )
        .unwrap()
    });
    let mut stream = match &renderer {
        Some(renderer) => camera_stream(renderer, log, 2.5),
        None => {
            let camera = CameraParams::exoter_bumblebee2().scaled(0.125);
            let [w, h] = camera.image_size_px.map(|v| v as usize);
            CameraStream {
                camera,
                times_secs: frame_times(log, 2.5),
                frames: Box::new(move |_, _| {
                    Ok((GrayImage::filled(w, h, 90), GrayImage::filled(w, h, 90)))
                }),
            }
        }
    };
    let recorded_vo: Vec<_> = frame_times(log, 2.5)
        .into_iter()
        .map(|t| (t, pose_at(log, t).unwrap()))
        .collect();
    let bag = write_mcap_with_camera(
        log,
        &dir.join("test"),
        &recorded_vo,
        WheelUnits::default(),
        Some(&mut stream),
    )
    .unwrap()
    .path;
    let rate_hz = gpodo_experiments::commands::simulate::median_rate_hz(log).unwrap();
    let map = written_topic_map_in(log, rate_hz, WheelUnits::default());
    let topics = dir.join("topics.yaml");
    std::fs::write(&topics, serde_saphyr::to_string(&map).unwrap()).unwrap();
    let model_path = fit_bag_model(dir, &topics, &train, &bag, 10);
    let gate_path = dir.join("gate.yaml");
    std::fs::write(&gate_path, GATE).unwrap();

    // Offline: the recording imported as `gpodo run` imports it, its
    // traverse made with the model's motion model, window and input
    // scaling.
    let saved = ModelFile::load(&model_path).unwrap();
    let file = gpodo_experiments::plan::gate::load_gate(&gate_path).unwrap();
    let online = file.online.as_ref().unwrap();
    // The VO behind the gate tracks with its own motion prior, as an
    // external SLAM does; so does the offline scheme's.
    let params = FrontendParams {
        vo,
        motion_prior: MotionPrior::ConstantVelocity,
        initial_residual_variance: file.initial_residual_variance,
        online: file.targets,
        ..FrontendParams::default()
    };
    let recorded =
        RecordedTraverse::load(&bag, &map, &file.topics, &saved, &exoter(), &params).unwrap();
    let traverse = &recorded.traverse;
    let spec = file
        .selector
        .for_odometry(&gpodo_frontends::odometry_mode::OdometryMode::default())
        .unwrap();
    let mut selector = causal_selector(&spec, file.lost_frame_period_secs, None).unwrap();
    let mut offline_learner = OnlineLearner::new(
        "ilgr",
        online.regressor.build().unwrap(),
        OnlineMode::Update,
        params.initial_residual_variance,
    )
    .unwrap()
    .with_standardized_inputs(traverse.inputs_standardized());
    let mut offline_vo = recorded.vo(&params).unwrap();
    let run = run_frontend(
        traverse,
        &params,
        selector.as_mut(),
        &mut offline_learner,
        offline_vo.as_mut(),
    )
    .unwrap();

    // Live: the recording replayed through the node, the same tracker
    // behind the gate.
    let rover = gpodo_kinematics::RoverDescription::from_path(&exoter()).unwrap();
    let mut model = gpodo_node::LiveModel::load(
        &model_path,
        &exoter(),
        true,
        false,
        gpodo_node::LiveSettings::default(),
    )
    .unwrap();
    let mut gate = LiveGateRun::<(usize, usize)>::build(
        &gate_path,
        &exoter(),
        &model_path,
        None,
        &model,
        Learner::LockStep,
    )
    .unwrap();
    let mut tracker = recorded.vo(&params).unwrap();
    let uninformed = ResidualPrediction::uninformed(params.initial_residual_variance);
    let mut no_model = Precomputed::new("none", vec![uninformed; traverse.windows().len()]);
    let mut behind = FrontEnd::new(traverse, &params, &mut no_model, tracker.as_mut()).unwrap();
    let mut answers = FrontEndVo::new(&mut behind, &recorded, "base_link");
    let mut vo = |pair: &RecordedPair<'_>, decision: &GateDecision| answers.answer(pair, decision);
    let summary = replay_gated(
        &bag,
        &map,
        &rover,
        &mut model,
        &dir.join("odom.mcap"),
        None,
        Playback::to_the_end(gpodo_node::replay::Pace::Fast),
        Some(GatedReplay {
            topics: &gate.file.topics,
            session: &mut gate.session,
            vo: &mut vo,
        }),
    )
    .unwrap();
    assert!(summary.skipped.is_empty(), "{:?}", summary.skipped);
    assert!(answers.error.is_none(), "{:?}", answers.error);
    let counts = gate.session.counts();
    let LearnerEnd::LockStep(learner) = gate.session.finish() else {
        panic!("a lock-step learner");
    };
    let camera_times = traverse.camera_times_secs();
    let forwarded = &answers.processed;
    let lost = answers.lost;

    // The node's odometry is the offline traverse's, step for step.
    let wheel = common::bag_odometry(&dir.join("odom.mcap"), "/odom/wheel");
    assert_eq!(wheel.len(), traverse.times_secs().len());
    let worst = traverse
        .twists()
        .iter()
        .zip(&wheel)
        .map(|(t, o)| {
            (t.linear_mps - nalgebra::Vector3::from(o.twist.linear))
                .abs()
                .max()
        })
        .fold(0.0, f64::max);
    assert!(worst <= 1e-12, "the twists differ by up to {worst:e} m/s");
    let offline_frames: Vec<usize> = run.processed.iter().map(|f| f.frame).collect();
    println!(
        "{} of {} frames forwarded, {} lost, {} targets offline, {} live, {} jumps",
        forwarded.len(),
        camera_times.len(),
        lost,
        run.online_targets,
        learner.targets_learned(),
        counts.jumps
    );
    assert_eq!(summary.decisions.len(), camera_times.len());
    assert!(offline_frames.len() > 10 && offline_frames.len() < camera_times.len());
    assert_eq!(lost, run.processed.iter().filter(|f| !f.tracked).count());
    assert_eq!(forwarded, &offline_frames);
    assert_eq!(learner.targets_learned(), run.online_targets as u64);
    // `gpodo live --gate --replay` with the same front end behind the gate
    // (`replay_frontend:`) makes the same decisions.
    let cli_gate = dir.join("gate-frontend.yaml");
    std::fs::write(
        &cli_gate,
        format!(
            "{GATE}replay_frontend: {{ vo: {{ {vo_yaml} }}, motion_prior: constant_velocity }}\n"
        ),
    )
    .unwrap();
    let decisions = dir.join("decisions.csv");
    let out = gpodo_live_gated(
        &model_path,
        &topics,
        &bag,
        &dir.join("cli.mcap"),
        &cli_gate,
        &decisions,
    );
    assert_succeeded(&out, "gpodo live --gate --replay with a front end: ");
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains(&format!("learner: {} targets learned", run.online_targets)),
        "{said}"
    );
    let cli_frames: Vec<usize> = std::fs::read_to_string(&decisions)
        .unwrap()
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(1) == Some("processed"))
        .map(|l| {
            let stamp: i64 = l.split(',').next().unwrap().parse().unwrap();
            let t = (stamp - recorded.start_epoch_ns) as f64 * 1e-9;
            camera_times.iter().position(|&c| c == t).unwrap()
        })
        .collect();
    assert_eq!(cli_frames, offline_frames);

    // The learners end in the same state: the same predictions on the
    // traverse's windows.
    for (i, window) in traverse.windows().iter().enumerate().step_by(7) {
        let a = offline_learner.on_window(i, window).unwrap();
        let z = saved.input_standardizer.as_ref().unwrap();
        let raw: Vec<f64> = (window.inputs.iter().zip(z.mean.iter().zip(&z.std)))
            .map(|(x, (m, s))| x * s + m)
            .collect();
        let b = learner.predict(&raw).unwrap();
        assert!((a.mean - b.mean).abs().max() <= 1e-12, "{a:?} {b:?}");
        assert!((a.variance - b.variance).abs().max() <= 1e-12);
    }
    (lost, run.online_targets)
}

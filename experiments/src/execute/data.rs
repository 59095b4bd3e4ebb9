//! A dataset specification turned into residual rows: simulated or loaded
//! runs, the motion model, dead reckoning on the test runs, the residual
//! rows, and the rows standardised as the regressors see them.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use gpodo_frontends::tum::StampedPose;

use gpodo_datasets::bags::import::TopicMap;
use gpodo_datasets::log::{RoverLog, read_log_csv};
use gpodo_datasets::residuals::{
    LogStep, ResidualConfig, StepWindows, log_steps, residual_dataset_from_steps,
};
use gpodo_datasets::speed_check::{median_speed_ratio, unit_warning};
use gpodo_datasets::table::{TableSpec, read_residual_table, split_fraction};
use gpodo_kinematics::RoverDescription;
use gpodo_testbed::sim::preset::SimulatorConfig;
use gpodo_traits::Standardizer;
use gpodo_traits::{MotionModel, ResidualDataset};

use crate::config::{AttitudeWithoutImu, DatasetSpec, ExperimentConfig, MotionModelSpec};
use crate::error::PipelineError;
use crate::execute::calibration::{ResidualStatistics, residual_statistics};
use crate::execute::odometry::{DeadReckoning, dead_reckoning};
use crate::execute::results::{Attitude, DatasetSummary, ModelRows, RunSummary};

/// The median ratio of the motion model's speed to the ground truth's over
/// the moving parts of the training runs' `steps`, with a warning when it is
/// outside [`gpodo_datasets::speed_check::PLAUSIBLE_RATIO`]: most likely a
/// joint in the wrong unit. A warning, never a silent fix.
fn check_speed_units(steps: &[Vec<LogStep>]) -> Option<f64> {
    let ratio = median_speed_ratio(steps);
    if let Some(warning) = ratio.and_then(unit_warning) {
        tracing::warn!("{warning} (the training runs)");
    }
    ratio
}

/// The median ratio of the motion model's translational speed to the
/// ground truth's over the moving seconds of `logs` (the unit check a run
/// makes before it fits anything; `gpodo import --rover`); `None` when the
/// logs never move.
///
/// # Errors
/// [`PipelineError`] when the model cannot be built or a log does not fit
/// its rover.
pub fn speed_ratio(
    spec: &MotionModelSpec,
    logs: &[RoverLog],
) -> Result<Option<f64>, PipelineError> {
    let (model, rover) = motion_model(spec)?;
    let radius = rover.as_ref().map_or(0.0, |r| r.wheel_radius_m);
    let steps = in_rover_order(logs, rover.as_ref())?
        .iter()
        .map(|log| log_steps(log, model.as_ref(), radius))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(median_speed_ratio(&steps))
}

/// `logs` with their joints in `rover`'s order (models read joints by
/// position); without a rover, logs must have no wheel joints.
pub(crate) fn in_rover_order(
    logs: &[RoverLog],
    rover: Option<&RoverDescription>,
) -> Result<Vec<RoverLog>, gpodo_datasets::DatasetError> {
    match rover {
        Some(rover) => logs
            .iter()
            .map(|l| {
                l.with_joint_order(
                    &rover.wheel_names(),
                    &rover.steer_names(),
                    &rover.bogie_names(),
                )
            })
            .collect(),
        None => match logs.iter().find(|l| !l.wheel_names.is_empty()) {
            Some(l) => Err(gpodo_datasets::DatasetError::InvalidLog {
                log: l.name.clone(),
                sample: None,
                detail: format!(
                    "the log has wheel joints {:?}: give the motion model a `rover:` \
                     description so that their speeds can be put in m/s",
                    l.wheel_names
                ),
            }),
            None => Ok(logs.to_vec()),
        },
    }
}

fn summarize(log: &RoverLog) -> RunSummary {
    RunSummary {
        name: log.name.clone(),
        samples: log.samples.len(),
        duration_secs: log.duration_secs(),
        path_length_m: log.path_length_m(),
    }
}

/// The motion model of `spec` and the rover it describes (none for the
/// reported odometry without a description).
fn motion_model(
    spec: &MotionModelSpec,
) -> Result<(Box<dyn MotionModel>, Option<RoverDescription>), PipelineError> {
    Ok(spec.build()?)
}

/// Train/test rows plus what the report says about where they came from.
pub(crate) struct PreparedData {
    pub(crate) train: ResidualDataset,
    pub(crate) test: ResidualDataset,
    /// The windows the test rows are scored on, when they are not the
    /// rows themselves.
    pub(crate) test_windows: Option<StepWindows>,
    pub(crate) summary: DatasetSummary,
    pub(crate) motion_model: Option<String>,
    pub(crate) dead_reckoning: Vec<(String, DeadReckoning)>,
    /// The test runs (in the rover's joint order), the motion model and the
    /// wheel radius, for the front end.
    pub(crate) test_logs: Vec<RoverLog>,
    pub(crate) model: Option<(Box<dyn MotionModel>, f64)>,
    /// Visual odometry recorded with the test runs (a bag's `vo` topic),
    /// by test run name.
    pub(crate) recorded_vo: BTreeMap<String, Vec<StampedPose>>,
    /// Per recording (log name), its stereo camera's frames, when the
    /// topic map names a `camera:`.
    pub(crate) recorded_cameras:
        BTreeMap<String, std::sync::Arc<gpodo_datasets::bags::frames::BagFrames>>,
    /// Where each soil lies (a simulated testbed only), for the simulated
    /// tracker's feature supply.
    pub(crate) soils: Option<gpodo_testbed::sim::soil::SoilMap>,
    /// The simulated testbed's terrain and seed, for the rendered camera.
    pub(crate) terrain: Option<(gpodo_testbed::sim::terrain::Terrain, u64)>,
    /// The gyro bias the simulator drew from (rad/s), for the odometry's
    /// covariance when the experiment leaves it unset.
    pub(crate) gyro_bias_radps: Option<f64>,
}

/// Where the motion model's roll and pitch come from for these logs: the
/// IMU when every run has one, else as `spec` says for a robot without.
///
/// # Errors
/// [`PipelineError`] when some runs have an IMU and others do not.
fn attitude_source(
    spec: &MotionModelSpec,
    train: &[RoverLog],
    test: &[RoverLog],
) -> Result<Attitude, PipelineError> {
    let has_imu = |l: &RoverLog| l.samples.first().is_some_and(|s| s.imu.is_some());
    let logs: Vec<&RoverLog> = train.iter().chain(test).collect();
    let with = logs.iter().find(|l| has_imu(l));
    let without = logs.iter().find(|l| !has_imu(l));
    match (with, without) {
        (_, None) => Ok(Attitude::Imu),
        (Some(a), Some(b)) => Err(PipelineError::Inconsistent(format!(
            "run `{}` has an IMU and run `{}` has none: the regressors need the same inputs in every run",
            a.name, b.name
        ))),
        (None, Some(_)) => Ok(match spec {
            MotionModelSpec::WeightedJacobian {
                attitude_without_imu: AttitudeWithoutImu::GroundTruth,
                ..
            } => Attitude::GroundTruth,
            MotionModelSpec::WeightedJacobian {
                attitude_without_imu: AttitudeWithoutImu::Level,
                ..
            }
            | MotionModelSpec::SkidSteer { .. }
            | MotionModelSpec::ReportedOdometry { .. } => Attitude::Level,
        }),
    }
}

/// Where a motion model without a gyro takes its yaw rate from.
fn yaw_rate_source(spec: &MotionModelSpec) -> &'static str {
    match spec {
        MotionModelSpec::WeightedJacobian { .. } => {
            "the wheels (solved with the slip, as an unknown of the weighted Jacobian)"
        }
        MotionModelSpec::SkidSteer { .. } => "the wheel speed difference (`yaw: wheels`)",
        MotionModelSpec::ReportedOdometry { .. } => "the robot's reported odometry",
    }
}

/// Whether any ground-truth pose of `train` or `test` is tilted: a GNSS
/// ground truth has no orientation, and gpodo stores it level.
fn ground_truth_has_attitude(train: &[RoverLog], test: &[RoverLog]) -> bool {
    train
        .iter()
        .chain(test)
        .flat_map(|l| &l.ground_truth)
        .any(|pose| {
            let (roll, pitch, _) = pose.rotation.euler_angles();
            roll != 0.0 || pitch != 0.0
        })
}

/// Sets every sample's off-board roll and pitch to its ground truth's.
fn with_ground_truth_attitude(log: &mut RoverLog) {
    for (sample, pose) in log.samples.iter_mut().zip(&log.ground_truth) {
        let (roll, pitch, _) = pose.rotation.euler_angles();
        sample.attitude_rad = Some([roll, pitch]);
    }
}

fn refs(logs: &[RoverLog]) -> Vec<&RoverLog> {
    logs.iter().collect()
}

/// The motion model of a spec and the logs as it reads them.
struct LogsForModel {
    model: Box<dyn MotionModel>,
    /// The rover's wheel radius (0 without a rover).
    radius: f64,
    train: Vec<RoverLog>,
    test: Vec<RoverLog>,
    /// Where the roll and pitch come from.
    attitude: Attitude,
}

/// Builds the motion model of `spec` and puts the logs in its rover's
/// joint order, with the off-board roll and pitch it reads where there is
/// no IMU.
fn logs_for_model(
    spec: &MotionModelSpec,
    train: &[RoverLog],
    test: &[RoverLog],
) -> Result<LogsForModel, PipelineError> {
    let (model, rover) = motion_model(spec)?;
    let (mut train, mut test) = (
        in_rover_order(train, rover.as_ref())?,
        in_rover_order(test, rover.as_ref())?,
    );
    let mut attitude = attitude_source(spec, &train, &test)?;
    if attitude == Attitude::GroundTruth && !ground_truth_has_attitude(&train, &test) {
        tracing::warn!(
            "`attitude_without_imu: ground_truth`, but the ground truth carries no roll or pitch (a GNSS fix has none): the ground is taken as level"
        );
        attitude = Attitude::Level;
    }
    if attitude == Attitude::GroundTruth {
        for log in train.iter_mut().chain(test.iter_mut()) {
            with_ground_truth_attitude(log);
        }
    }
    Ok(LogsForModel {
        model,
        radius: rover.as_ref().map_or(0.0, |r| r.wheel_radius_m),
        train,
        test,
        attitude,
    })
}

/// The residual rows of `logs` (concatenated in order) as an experiment
/// with this `motion_model:` and `residuals:` computes its training rows.
///
/// # Errors
/// [`PipelineError`] when the model cannot be built, a log does not fit
/// its rover, or the residuals cannot be computed.
pub fn residual_rows(
    spec: &MotionModelSpec,
    residuals: &ResidualConfig,
    logs: &[RoverLog],
) -> Result<ResidualDataset, PipelineError> {
    let prepared = logs_for_model(spec, logs, &[])?;
    let steps = prepared
        .train
        .iter()
        .map(|log| {
            log.validate()?;
            log_steps(log, prepared.model.as_ref(), prepared.radius)
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(residual_dataset_from_steps(
        &refs(&prepared.train),
        &steps,
        residuals,
    )?)
}

fn from_logs(
    config: &ExperimentConfig,
    train_logs: &[RoverLog],
    test_logs: &[RoverLog],
    source: String,
    terrain_max_slope_deg: Option<f64>,
) -> Result<PreparedData, PipelineError> {
    let LogsForModel {
        model,
        radius,
        train: train_logs,
        test: test_logs,
        attitude,
    } = logs_for_model(&config.motion_model, train_logs, test_logs)?;
    let (train_logs, test_logs) = (&train_logs, &test_logs);
    let steps_of = |logs: &[RoverLog]| {
        logs.iter()
            .map(|log| {
                log.validate()?;
                log_steps(log, model.as_ref(), radius)
            })
            .collect::<Result<Vec<_>, _>>()
    };
    let train_steps = steps_of(train_logs)?;
    let speed_ratio = check_speed_units(&train_steps);
    let train = residual_dataset_from_steps(&refs(train_logs), &train_steps, &config.residuals)?;
    let test_steps = steps_of(test_logs)?;
    let test = residual_dataset_from_steps(&refs(test_logs), &test_steps, &config.residuals)?;
    let test_windows = match (
        config.residuals.window_secs,
        config.residuals.score_window_secs,
    ) {
        (None, Some(window)) => Some(StepWindows::new(&test_steps, window)?),
        _ => None,
    };
    let dead_reckoning = test_logs
        .iter()
        .map(|log| Ok((log.name.clone(), dead_reckoning(log, model.as_ref())?)))
        .collect::<Result<_, PipelineError>>()?;
    let test_logs = test_logs.clone();
    Ok(PreparedData {
        summary: DatasetSummary {
            source,
            train_runs: train_logs.iter().map(summarize).collect(),
            test_runs: test_logs.iter().map(summarize).collect(),
            n_train: train.len(),
            n_test: test.len(),
            input_names: train.input_names.clone(),
            target_names: train.target_names.clone(),
            terrain_max_slope_deg,
            attitude,
            yaw_rate_without_imu: (attitude != Attitude::Imu)
                .then(|| yaw_rate_source(&config.motion_model).to_string()),
            speed_ratio,
        },
        train,
        test,
        test_windows,
        motion_model: Some(model.name().to_string()),
        dead_reckoning,
        test_logs,
        model: Some((model, radius)),
        recorded_vo: BTreeMap::new(),
        recorded_cameras: BTreeMap::new(),
        soils: None,
        terrain: None,
        gyro_bias_radps: None,
    })
}

pub(crate) fn prepare(config: &ExperimentConfig) -> Result<PreparedData, PipelineError> {
    match &config.dataset {
        DatasetSpec::Simulated {
            preset,
            seed,
            training_runs,
            training_run_secs,
            test_max_secs,
            route,
            mocap_jitter_m,
            camera_rate_hz,
            slip_bursts,
        } => {
            let mut sim = SimulatorConfig::preset(*preset, *seed);
            sim.route = *route;
            sim.slip.bursts.clone_from(slip_bursts);
            if let Some(n) = training_runs {
                sim.training_runs = *n;
            }
            if let Some(s) = training_run_secs {
                sim.training_run_secs = *s;
            }
            if let Some(s) = test_max_secs {
                sim.test_max_secs = *s;
            }
            if let Some(j) = mocap_jitter_m {
                sim.sensors.mocap_jitter_m = *j;
            }
            if let Some(r) = camera_rate_hz {
                if !(r.is_finite() && *r > 0.0) {
                    return Err(gpodo_frontends::FrontendError::InvalidConfig {
                        field: "dataset.camera_rate_hz".into(),
                        expected: format!("a positive rate in Hz, not {r}"),
                    }
                    .into());
                }
                sim.camera_rate_hz = *r;
            }
            tracing::info!(seed, "simulating the testbed");
            let testbed = sim.simulate()?;
            let source = format!("simulated `{}` testbed, seed {seed}", preset.name());
            let mut prepared = from_logs(
                config,
                &testbed.train,
                &testbed.test,
                source,
                Some(testbed.terrain.max_slope_deg()),
            )?;
            prepared.soils = Some(testbed.soils);
            prepared.terrain = Some((testbed.terrain, *seed));
            prepared.gyro_bias_radps = Some(sim.sensors.gyro_bias_sigma_radps());
            Ok(prepared)
        }
        DatasetSpec::Logs { train, test } => {
            let read = |paths: &[PathBuf]| {
                paths
                    .iter()
                    .map(|p| read_log_csv(&p.clone()))
                    .collect::<Result<Vec<_>, _>>()
            };
            let (train, test) = (read(train)?, read(test)?);
            from_logs(config, &train, &test, "rover logs".into(), None)
        }
        DatasetSpec::Bags {
            train,
            test,
            train_fraction,
            topics,
        } => prepare_bags(config, train, test, *train_fraction, topics),
        DatasetSpec::ResidualTable {
            path,
            inputs,
            targets,
            train_fraction,
        } => prepare_table(path, inputs.as_deref(), targets, *train_fraction),
    }
}

/// A `bags` dataset: each recording imported through the topic map, with
/// its recorded VO and camera; a training recording cut at
/// `train_fraction` gives its held-out part to the tests.
fn prepare_bags(
    config: &ExperimentConfig,
    train: &[PathBuf],
    test: &[PathBuf],
    train_fraction: Option<f64>,
    topics: &TopicMap,
) -> Result<PreparedData, PipelineError> {
    let imported = std::cell::RefCell::new(Vec::new());
    let vo = std::cell::RefCell::new(BTreeMap::new());
    let cameras = std::cell::RefCell::new(BTreeMap::new());
    let read = |paths: &[PathBuf]| {
        paths
            .iter()
            .map(|p| {
                let path = p.clone();
                let name = path
                    .file_stem()
                    .map_or_else(|| "recording".into(), |s| s.to_string_lossy().into_owned());
                let (mut log, report) = gpodo_datasets::bags::import::import_bag(&path, &name, topics)?;
                if let Some(camera) = &topics.camera {
                    let frames = recorded_camera(&path, camera, topics.skip_damaged, &report, &mut log)?;
                    cameras.borrow_mut().insert(name.clone(), std::sync::Arc::new(frames));
                }
                tracing::info!(bag = %path.display(), rows = report.rows, dropped = report.rows_dropped, "bag imported");
                imported.borrow_mut().push(import_summary(&name, &report));
                if !report.vo_poses.is_empty() {
                    let poses = report
                        .vo_poses
                        .iter()
                        .map(|&(time_secs, pose)| StampedPose { time_secs, pose })
                        .collect();
                    vo.borrow_mut().insert(name.clone(), poses);
                }
                Ok(log)
            })
            .collect::<Result<Vec<_>, PipelineError>>()
    };
    let (mut train, mut test) = (read(train)?, read(test)?);
    let mut vo = vo.into_inner();
    let mut cameras = cameras.into_inner();
    if let Some(fraction) = train_fraction {
        // A held-out part replays its recording's VO and reads its
        // recording's camera.
        for log in &train {
            if let Some(poses) = vo.get(&log.name).cloned() {
                vo.insert(format!("{}-test", log.name), poses);
            }
            if let Some(frames) = cameras.get(&log.name).cloned() {
                cameras.insert(format!("{}-test", log.name), frames);
            }
        }
        let (mut kept, mut held_out) = (Vec::new(), Vec::new());
        for log in &train {
            let (a, b) = log.split_in_time(fraction)?;
            kept.push(a);
            held_out.push(b);
        }
        held_out.append(&mut test);
        (train, test) = (kept, held_out);
    }
    let split = train_fraction.map_or_else(String::new, |f| {
        format!(
            ", each training recording cut at {:.0} % of its duration (the rest tests)",
            100.0 * f
        )
    });
    let source = format!(
        "ROS bags at {} Hz, at most {} s bridged{split} ({})",
        topics.rate_hz,
        topics.max_gap_secs,
        imported.into_inner().join("; ")
    );
    let mut prepared = from_logs(config, &train, &test, source, None)?;
    prepared.recorded_vo = vo;
    prepared.recorded_cameras = cameras;
    Ok(prepared)
}

/// A residual table: its rows split at `train_fraction`, with no logs
/// behind them.
fn prepare_table(
    path: &Path,
    inputs: Option<&[String]>,
    targets: &[String],
    train_fraction: f64,
) -> Result<PreparedData, PipelineError> {
    let spec = TableSpec {
        inputs: inputs.map(<[String]>::to_vec),
        targets: targets.to_vec(),
    };
    let data = read_residual_table(path, &spec)?;
    let (train, test) = split_fraction(&data, train_fraction)?;
    Ok(PreparedData {
        summary: DatasetSummary {
            source: format!("residual table {}", path.display()),
            train_runs: Vec::new(),
            test_runs: Vec::new(),
            n_train: train.len(),
            n_test: test.len(),
            input_names: train.input_names.clone(),
            target_names: train.target_names.clone(),
            terrain_max_slope_deg: None,
            attitude: Attitude::Imu,
            yaw_rate_without_imu: None,
            speed_ratio: None,
        },
        train,
        test,
        test_windows: None,
        motion_model: None,
        dead_reckoning: Vec::new(),
        test_logs: Vec::new(),
        model: None,
        recorded_vo: BTreeMap::new(),
        recorded_cameras: BTreeMap::new(),
        soils: None,
        terrain: None,
        gyro_bias_radps: None,
    })
}

/// The stereo camera of the bag at `path` as frames for the stereo VO, on
/// the clock of its imported `log`, whose camera frames become the pairs'
/// stamps within it (placed by their header stamps).
pub(crate) fn recorded_camera(
    path: &std::path::Path,
    camera: &gpodo_datasets::bags::images::CameraTopics,
    skip_damaged: bool,
    report: &gpodo_datasets::bags::import::ImportReport,
    log: &mut RoverLog,
) -> Result<gpodo_datasets::bags::frames::BagFrames, PipelineError> {
    use gpodo_datasets::bags::OnDamage;
    let on_damage = if skip_damaged {
        OnDamage::Skip
    } else {
        OnDamage::Stop
    };
    let recording = gpodo_datasets::bags::images::read_stereo(path, camera, on_damage)
        .map_err(gpodo_datasets::bags::import::ImportError::from)?;
    let frames =
        gpodo_datasets::bags::frames::BagFrames::new(recording, report.start_epoch_ns, 1e-3);
    let (first, last) = match (log.samples.first(), log.samples.last()) {
        (Some(a), Some(b)) => (a.time_secs, b.time_secs),
        _ => (0.0, 0.0),
    };
    log.camera_times_secs = frames
        .times_secs()
        .into_iter()
        .filter(|t| *t >= first && *t <= last)
        .collect();
    tracing::info!(
        bag = %path.display(),
        pairs = log.camera_times_secs.len(),
        "camera frames from the recorded images"
    );
    Ok(frames)
}

pub(crate) fn reference_statistics(
    config: &ExperimentConfig,
) -> Option<(String, ResidualStatistics)> {
    let reference = config.compare_with.as_ref()?;
    let path = reference.path.clone();
    let spec = TableSpec {
        inputs: None,
        targets: reference.targets.clone(),
    };
    match read_residual_table(&path, &spec) {
        Ok(table) => Some((
            reference.path.display().to_string(),
            residual_statistics(&table),
        )),
        Err(e) => {
            tracing::warn!("reference table not used: {e}");
            None
        }
    }
}

pub(crate) fn model_rows(data: &PreparedData) -> Result<(ModelRows, Standardizer), PipelineError> {
    if data.train.input_names != data.test.input_names
        || data.train.target_names != data.test.target_names
    {
        return Err(PipelineError::Inconsistent(format!(
            "training columns {:?} → {:?}, test columns {:?} → {:?}",
            data.train.input_names,
            data.train.target_names,
            data.test.input_names,
            data.test.target_names
        )));
    }
    let scaler = Standardizer::fit(&data.train.inputs)?;
    let mut train = data.train.clone().with_standardized_inputs(true);
    train.inputs = scaler.transform(&data.train.inputs)?;
    let mut test = data.test.clone().with_standardized_inputs(true);
    test.inputs = scaler.transform(&data.test.inputs)?;
    Ok((
        ModelRows {
            train,
            test,
            test_windows: data.test_windows.clone(),
        },
        scaler,
    ))
}

/// One line on what importing a bag did: rows kept and dropped, each
/// stream's counts, and what a GNSS ground truth was made into.
fn import_summary(name: &str, r: &gpodo_datasets::bags::import::ImportReport) -> String {
    let mut parts = vec![
        r.streams
            .iter()
            .map(|s| s.to_string())
            .collect::<Vec<_>>()
            .join(", "),
    ];
    parts.extend(r.gnss_notes());
    if !r.damage.is_empty() {
        parts.push(r.damage.to_string());
    }
    format!(
        "{name}: {} rows, {} dropped in gaps; {}",
        r.rows,
        r.rows_dropped,
        parts.join("; ")
    )
}

/// The data of `config` as the regressors see them, and where they came
/// from (for benchmarks that time the regressors alone).
///
/// # Errors
/// [`PipelineError`] saying which stage failed.
pub fn prepare_model_rows(
    config: &ExperimentConfig,
) -> Result<(ModelRows, DatasetSummary), PipelineError> {
    let data = prepare(config)?;
    Ok((model_rows(&data)?.0, data.summary))
}

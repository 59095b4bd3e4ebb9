//! `gpodo simulate`: a seeded testbed of a preset written as rover-log CSV
//! files or as ROS 2 MCAP bags with the topic map that imports them; with
//! a camera, the rendered stereo pairs go into the bags (`Image` and
//! `CameraInfo` messages) or, as PNG, into a folder per log.

use std::path::{Path, PathBuf};

use gpodo_datasets::bags::write::{WheelUnits, write_mcap_with_camera, written_topic_map_in};
use gpodo_datasets::bags::write_camera::written_camera_topics;
use gpodo_datasets::bags::write_camera::{intrinsics, projection};
use gpodo_datasets::log::{RoverLog, write_log_csv};
use gpodo_testbed::camera::traverse::{camera_stream, frame_times, pose_at};
use gpodo_testbed::camera::{GroundMaps, SceneSpec, SensorSpec, StereoRenderer};
use gpodo_testbed::sim::preset::{Preset, SimulatedTestbed, SimulatorConfig};
use gpodo_traits::CameraParams;
use gpodo_vision::png_io::write_png_gray;

use crate::error::PipelineError;

/// What a simulated testbed is written as.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimulateFormat {
    /// Rover-log CSV (the `logs` dataset) and each log's camera times.
    Csv,
    /// ROS 2 MCAP bags (the `bags` dataset) and `topics.yaml`.
    Mcap,
    /// Rover-log CSV and, per log, a folder of the camera's PNG pairs with
    /// their times and calibration (needs a camera).
    Png,
}

/// The rendered camera's settings for `gpodo simulate --camera`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraOutput {
    /// Fraction of ExoTeR's Bumblebee2 resolution (1024 × 768).
    pub scale: f64,
    /// Frames per second.
    pub fps: f64,
    /// MCAP only: a VO trajectory on `/vo/pose` too, the ground truth at
    /// each frame (a stand-in for the SLAM a gated replay answers
    /// forwarded pairs with; `gpodo live --gate --replay`).
    pub vo_ground_truth: bool,
}

/// The settings of one `gpodo simulate`.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulateOptions {
    /// The simulator preset.
    pub preset: Preset,
    /// The seed of every random draw.
    pub seed: u64,
    /// Training runs instead of the preset's number.
    pub training_runs: Option<usize>,
    /// Seconds per training run instead of the preset's.
    pub training_run_secs: Option<f64>,
    /// The test traverse cut after this many seconds (default: the
    /// preset's whole route).
    pub test_max_secs: Option<f64>,
    /// The file format.
    pub format: SimulateFormat,
    /// The units of the bags' wheel rates (MCAP only).
    pub units: WheelUnits,
    /// Whether the logs keep their IMU samples (off: a robot without one).
    pub imu: bool,
    /// The rendered stereo camera, when asked for (MCAP and PNG).
    pub camera: Option<CameraOutput>,
}

/// One file `gpodo simulate` wrote.
#[derive(Debug, Clone, PartialEq)]
pub enum Written {
    /// A rover log and its camera times.
    Log {
        /// The CSV log.
        csv: PathBuf,
        /// The camera-times file beside it.
        camera: PathBuf,
        /// Samples of the log.
        samples: usize,
        /// Ground-truth path length (m).
        path_length_m: f64,
    },
    /// A ROS 2 bag.
    Bag {
        /// The MCAP file.
        path: PathBuf,
        /// Messages in it.
        messages: u64,
        /// Its size (bytes).
        bytes: u64,
        /// Ground-truth path length (m).
        path_length_m: f64,
    },
    /// The topic map that imports the bags.
    TopicMap {
        /// The YAML file.
        path: PathBuf,
    },
    /// A folder of a log's rendered stereo pairs.
    Frames {
        /// The folder.
        dir: PathBuf,
        /// Stereo pairs in it.
        pairs: usize,
        /// Its size (bytes).
        bytes: u64,
    },
}

impl std::fmt::Display for Written {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Log {
                csv,
                camera,
                samples,
                path_length_m,
            } => write!(
                f,
                "wrote {} ({samples} samples, {path_length_m:.1} m) and {}",
                csv.display(),
                camera.display()
            ),
            Self::Bag {
                path,
                messages,
                bytes,
                path_length_m,
            } => write!(
                f,
                "wrote {} ({messages} messages, {:.1} MB, {path_length_m:.1} m)",
                path.display(),
                *bytes as f64 / 1e6
            ),
            Self::TopicMap { path } => {
                write!(
                    f,
                    "wrote {} (the topic map that imports them)",
                    path.display()
                )
            }
            Self::Frames { dir, pairs, bytes } => write!(
                f,
                "wrote {} ({pairs} stereo pairs, {:.1} MB, with times.csv, left.yaml and right.yaml)",
                dir.display(),
                *bytes as f64 / 1e6
            ),
        }
    }
}

/// The median sample rate of `log` (Hz), to a micro-hertz (12.5 Hz for the
/// ExoTeR preset); `None` with fewer than two samples.
pub fn median_rate_hz(log: &RoverLog) -> Option<f64> {
    let mut dts: Vec<f64> = log
        .samples
        .windows(2)
        .map(|w| w[1].time_secs - w[0].time_secs)
        .collect();
    dts.sort_by(f64::total_cmp);
    dts.get(dts.len() / 2).map(|dt| (1e6 / dt).round() / 1e6)
}

/// The error of an I/O failure on `path`, for `map_err`.
fn io(path: &Path) -> impl FnOnce(std::io::Error) -> PipelineError {
    let path = path.to_path_buf();
    move |source| PipelineError::Io { path, source }
}

/// Whether the camera's settings fit the format: PNG needs the camera, a
/// CSV log has no images, and the scale and rate are in range.
///
/// # Errors
/// [`PipelineError::Inconsistent`] naming the setting.
fn check_camera(options: &SimulateOptions) -> Result<(), PipelineError> {
    let wrong = |m: String| Err(PipelineError::Inconsistent(m));
    match (options.format, options.camera) {
        (SimulateFormat::Png, None) => wrong("format png writes the camera's frames: ask for the camera (`--camera`)".into()),
        (SimulateFormat::Csv, Some(_)) => wrong(
            "a camera writes into format mcap (Image and CameraInfo messages) or png; a rover-log CSV has no images".into(),
        ),
        (_, Some(c)) if !(c.scale.is_finite() && c.scale > 0.0 && c.scale <= 1.0) => {
            wrong(format!("camera scale {}: expected a fraction in (0, 1]", c.scale))
        }
        (_, Some(c)) if !(c.fps.is_finite() && c.fps > 0.0 && c.fps <= 30.0) => {
            wrong(format!("camera fps {}: expected a rate in (0, 30] Hz", c.fps))
        }
        (SimulateFormat::Png, Some(c)) if c.vo_ground_truth => {
            wrong("a VO trajectory goes into format mcap (`/vo/pose`); a PNG folder has none".into())
        }
        _ => Ok(()),
    }
}

/// Simulates the testbed of `options` and writes its training runs, then
/// its test runs, into `out` (created if missing). Returns what it wrote,
/// in order.
///
/// # Errors
/// [`PipelineError::Inconsistent`] when the camera does not fit the
/// format; [`PipelineError::Dataset`] when the simulation or a log fails;
/// [`PipelineError::Io`] naming the file that could not be written.
pub fn simulate_to(options: &SimulateOptions, out: &Path) -> Result<Vec<Written>, PipelineError> {
    check_camera(options)?;
    let testbed = simulate_testbed(options)?;
    write_testbed(options, &testbed, out)
}

/// The training and test runs of the testbed of `options`, in memory (the
/// logs `gpodo simulate` writes; the camera and format are not used).
///
/// # Errors
/// [`PipelineError::Dataset`] when the simulation fails.
pub fn simulate_logs(
    options: &SimulateOptions,
) -> Result<(Vec<RoverLog>, Vec<RoverLog>), PipelineError> {
    let testbed = simulate_testbed(options)?;
    Ok((testbed.train, testbed.test))
}

/// The simulated testbed of `options`, without its IMU when asked.
fn simulate_testbed(options: &SimulateOptions) -> Result<SimulatedTestbed, PipelineError> {
    let mut config = SimulatorConfig::preset(options.preset, options.seed);
    if let Some(n) = options.training_runs {
        config.training_runs = n;
    }
    if let Some(s) = options.training_run_secs {
        config.training_run_secs = s;
    }
    if let Some(s) = options.test_max_secs {
        config.test_max_secs = s;
    }
    let mut testbed = config.simulate()?;
    if !options.imu {
        for log in testbed.train.iter_mut().chain(testbed.test.iter_mut()) {
            for sample in &mut log.samples {
                sample.imu = None;
            }
        }
    }
    Ok(testbed)
}

/// Writes the simulated `testbed` as `options` ask.
fn write_testbed(
    options: &SimulateOptions,
    testbed: &SimulatedTestbed,
    out: &Path,
) -> Result<Vec<Written>, PipelineError> {
    std::fs::create_dir_all(out).map_err(io(out))?;
    let ground = match options.camera {
        Some(_) => Some(GroundMaps::build(
            &testbed.terrain,
            &testbed.soils,
            &SceneSpec::default(),
            options.seed,
        )?),
        None => None,
    };
    let renderer = match (options.camera, &ground) {
        (Some(c), Some(ground)) => Some(StereoRenderer::new(
            CameraParams::exoter_bumblebee2().scaled(c.scale),
            ground,
            SensorSpec::default(),
            options.seed,
        )?),
        _ => None,
    };
    let logs: Vec<&RoverLog> = testbed.train.iter().chain(&testbed.test).collect();
    let mut written = Vec::new();
    match options.format {
        SimulateFormat::Csv | SimulateFormat::Png => {
            for log in logs {
                let (csv, camera) = write_log_csv(log, out)?;
                written.push(Written::Log {
                    csv,
                    camera,
                    samples: log.samples.len(),
                    path_length_m: log.path_length_m(),
                });
                if let (SimulateFormat::Png, Some(renderer), Some(c)) =
                    (options.format, &renderer, options.camera)
                {
                    let dir = out.join(format!("{}.frames", log.name));
                    written.push(write_frames(renderer, log, c.fps, &dir)?);
                }
            }
        }
        SimulateFormat::Mcap => {
            for log in &logs {
                let mut stream = match (&renderer, options.camera) {
                    (Some(renderer), Some(c)) => Some(camera_stream(renderer, log, c.fps)),
                    _ => None,
                };
                let vo: Vec<_> = match options.camera {
                    Some(c) if c.vo_ground_truth => frame_times(log, c.fps)
                        .into_iter()
                        .filter_map(|t| Some((t, pose_at(log, t)?)))
                        .collect(),
                    _ => Vec::new(),
                };
                let bag = write_mcap_with_camera(log, out, &vo, options.units, stream.as_mut())?;
                written.push(Written::Bag {
                    path: bag.path,
                    messages: bag.messages,
                    bytes: bag.bytes,
                    path_length_m: log.path_length_m(),
                });
            }
            if let Some(first) = logs.first() {
                let rate_hz = median_rate_hz(first).unwrap_or(10.0);
                let mut map = written_topic_map_in(first, rate_hz, options.units);
                if options.camera.is_some() {
                    map.camera = Some(written_camera_topics());
                }
                let path = out.join("topics.yaml");
                let text = serde_saphyr::to_string(&map).map_err(|e| PipelineError::Io {
                    path: path.clone(),
                    source: std::io::Error::other(e.to_string()),
                })?;
                std::fs::write(&path, text).map_err(io(&path))?;
                written.push(Written::TopicMap { path });
            }
        }
    }
    Ok(written)
}

/// A camera's calibration in ROS's `camera_info` YAML (what
/// `camera_calibration_parsers` reads): rectified, no distortion, the
/// right camera's projection carrying `−f b`.
pub fn camera_info_yaml(camera: &CameraParams, index: usize) -> String {
    let [width, height] = camera.image_size_px;
    let p = projection(camera, index);
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    format!(
        "image_width: {width}\nimage_height: {height}\ncamera_name: {}\n\
         camera_matrix:\n  rows: 3\n  cols: 3\n  data: [{}]\n\
         distortion_model: plumb_bob\n\
         distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [0, 0, 0, 0, 0]\n\
         rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n\
         projection_matrix:\n  rows: 3\n  cols: 4\n  data: [{}]\n",
        ["left", "right"][index.min(1)],
        list(&intrinsics(camera)),
        list(&p),
    )
}

/// Writes `log`'s frames at `fps` into `dir`: `left/NNNNNN.png`,
/// `right/NNNNNN.png`, `times.csv` (frame, time on the log's clock) and
/// each camera's `camera_info` YAML.
fn write_frames(
    renderer: &StereoRenderer<'_>,
    log: &RoverLog,
    fps: f64,
    dir: &Path,
) -> Result<Written, PipelineError> {
    let mut stream = camera_stream(renderer, log, fps);
    let mut bytes = 0;
    let mut times = String::from("frame,time_s\n");
    for side in ["left", "right"] {
        std::fs::create_dir_all(dir.join(side)).map_err(io(&dir.join(side)))?;
    }
    let frame_times = stream.times_secs.clone();
    for (k, &t) in frame_times.iter().enumerate() {
        let (left, right) = (stream.frames)(k, t)?;
        for (side, image) in [("left", &left), ("right", &right)] {
            let path = dir.join(side).join(format!("{k:06}.png"));
            write_png_gray(&path, image).map_err(gpodo_datasets::DatasetError::from)?;
            bytes += std::fs::metadata(&path).map_err(io(&path))?.len();
        }
        times.push_str(&format!("{k},{t}\n"));
    }
    let camera = renderer.camera();
    for (path, text) in [
        (dir.join("times.csv"), times),
        (dir.join("left.yaml"), camera_info_yaml(camera, 0)),
        (dir.join("right.yaml"), camera_info_yaml(camera, 1)),
    ] {
        std::fs::write(&path, text).map_err(io(&path))?;
    }
    Ok(Written::Frames {
        dir: dir.to_path_buf(),
        pairs: frame_times.len(),
        bytes,
    })
}

//! `gpodo simulate`: a seeded testbed of a preset written as rover-log CSV
//! files or as ROS 2 MCAP bags with the topic map that imports them.

use std::path::{Path, PathBuf};

use gpodo_datasets::bags::write::{WheelUnits, write_mcap_with, written_topic_map_in};
use gpodo_datasets::log::{RoverLog, write_log_csv};
use gpodo_datasets::sim::preset::{Preset, SimulatorConfig};

use crate::error::PipelineError;

/// What a simulated testbed is written as.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimulateFormat {
    /// Rover-log CSV (the `logs` dataset) and each log's camera times.
    Csv,
    /// ROS 2 MCAP bags (the `bags` dataset) and `topics.yaml`.
    Mcap,
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
    /// The file format.
    pub format: SimulateFormat,
    /// The units of the bags' wheel rates (MCAP only).
    pub units: WheelUnits,
    /// Whether the logs keep their IMU samples (off: a robot without one).
    pub imu: bool,
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

/// Simulates the testbed of `options` and writes its training runs, then
/// its test runs, into `out` (created if missing). Returns what it wrote,
/// in order.
///
/// # Errors
/// [`PipelineError::Dataset`] when the simulation or a log fails,
/// [`PipelineError::Io`] naming the file that could not be written.
pub fn simulate_to(options: &SimulateOptions, out: &Path) -> Result<Vec<Written>, PipelineError> {
    let mut config = SimulatorConfig::preset(options.preset, options.seed);
    if let Some(n) = options.training_runs {
        config.training_runs = n;
    }
    if let Some(s) = options.training_run_secs {
        config.training_run_secs = s;
    }
    let mut testbed = config.simulate()?;
    if !options.imu {
        for log in testbed.train.iter_mut().chain(testbed.test.iter_mut()) {
            for sample in &mut log.samples {
                sample.imu = None;
            }
        }
    }
    std::fs::create_dir_all(out).map_err(|source| PipelineError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    let logs: Vec<&RoverLog> = testbed.train.iter().chain(&testbed.test).collect();
    let mut written = Vec::new();
    match options.format {
        SimulateFormat::Csv => {
            for log in logs {
                let (csv, camera) = write_log_csv(log, out)?;
                written.push(Written::Log {
                    csv,
                    camera,
                    samples: log.samples.len(),
                    path_length_m: log.path_length_m(),
                });
            }
        }
        SimulateFormat::Mcap => {
            for log in &logs {
                let bag = write_mcap_with(log, out, &[], options.units)?;
                written.push(Written::Bag {
                    path: bag.path,
                    messages: bag.messages,
                    bytes: bag.bytes,
                    path_length_m: log.path_length_m(),
                });
            }
            if let Some(first) = logs.first() {
                let rate_hz = median_rate_hz(first).unwrap_or(10.0);
                let map = written_topic_map_in(first, rate_hz, options.units);
                let path = out.join("topics.yaml");
                let text = serde_saphyr::to_string(&map).map_err(|e| PipelineError::Io {
                    path: path.clone(),
                    source: std::io::Error::other(e.to_string()),
                })?;
                std::fs::write(&path, text).map_err(|source| PipelineError::Io {
                    path: path.clone(),
                    source,
                })?;
                written.push(Written::TopicMap { path });
            }
        }
    }
    Ok(written)
}

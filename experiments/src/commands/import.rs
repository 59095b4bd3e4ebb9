//! `gpodo import`: ROS bags read through a topic map into rover-log CSV
//! files (and the recorded visual odometry into TUM files), with the unit
//! check of the robot's motion model against the ground truth.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use gpodo_datasets::bags::import::{ImportReport, TopicMap, import_bag};
use gpodo_datasets::log::{RoverLog, write_log_csv};
use gpodo_frontends::tum::{StampedPose, format_tum};

use crate::config::MotionModelSpec;
use crate::error::{ConfigError, PipelineError};

/// Reads a topic map (YAML).
///
/// # Errors
/// [`ConfigError::Io`] when the file cannot be read, [`ConfigError::Parse`]
/// with the parser's position when it does not match the schema.
pub fn read_topic_map(path: &Path) -> Result<TopicMap, ConfigError> {
    let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    serde_saphyr::from_str(&text).map_err(|e| ConfigError::Parse {
        path: path.to_path_buf(),
        detail: e.to_string(),
    })
}

/// The name of the log of `file`: its stem (`recording` without one).
pub fn log_name(file: &Path) -> String {
    file.file_stem().map_or_else(
        || "recording".to_string(),
        |s| s.to_string_lossy().into_owned(),
    )
}

/// One imported recording: its log, the import's report and the files
/// written.
#[derive(Debug, Clone)]
pub struct Imported {
    /// The bag.
    pub source: PathBuf,
    /// The rover log read from it.
    pub log: RoverLog,
    /// What the import found (streams, gaps, damage, visual odometry).
    pub report: ImportReport,
    /// The CSV log written.
    pub csv: PathBuf,
    /// The recorded visual odometry as a TUM file, when the map names it.
    pub vo_tum: Option<PathBuf>,
}

/// Imports every bag of `files` through `map` into `out` (created if
/// missing): `NAME.csv` per bag, and `NAME.vo.tum` when the map names a
/// visual-odometry topic. `on_imported` sees each recording as soon as it
/// is written, so what was written is reported even when a later bag fails.
///
/// # Errors
/// [`PipelineError::Inconsistent`] when two inputs share a stem (their
/// logs would overwrite each other), before anything is written;
/// [`PipelineError::Bag`] when a bag cannot be imported;
/// [`PipelineError::Io`] naming a file that cannot be written.
pub fn import_bags(
    files: &[PathBuf],
    map: &TopicMap,
    out: &Path,
    mut on_imported: impl FnMut(&Imported),
) -> Result<Vec<Imported>, PipelineError> {
    let mut stems = BTreeSet::new();
    for file in files {
        let stem = log_name(file);
        if !stems.insert(stem.clone()) {
            return Err(PipelineError::Inconsistent(format!(
                "two inputs are named `{stem}`; their logs would overwrite each other (rename one)"
            )));
        }
    }
    std::fs::create_dir_all(out).map_err(|source| PipelineError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    let mut imported = Vec::new();
    for file in files {
        let name = log_name(file);
        let (log, report) = import_bag(file, &name, map)?;
        let (csv, _) = write_log_csv(&log, out)?;
        let vo_tum = if report.vo_poses.is_empty() {
            None
        } else {
            let poses: Vec<StampedPose> = report
                .vo_poses
                .iter()
                .map(|&(time_secs, pose)| StampedPose { time_secs, pose })
                .collect();
            let path = out.join(format!("{name}.vo.tum"));
            let comment = format!(
                "visual odometry of {} ({}), on the log's clock",
                file.display(),
                map.vo.as_deref().unwrap_or("vo")
            );
            std::fs::write(&path, format_tum(&comment, &poses)).map_err(|source| {
                PipelineError::Io {
                    path: path.clone(),
                    source,
                }
            })?;
            Some(path)
        };
        let one = Imported {
            source: file.clone(),
            log,
            report,
            csv,
            vo_tum,
        };
        on_imported(&one);
        imported.push(one);
    }
    Ok(imported)
}

/// The unit check of an import: the median, over the moving seconds, of
/// the speed of the weighted-Jacobian model of `rover` (a robot
/// description) over the ground truth's; `None` when fewer than
/// [`gpodo_datasets::speed_check::MIN_MOVING_WINDOWS`] seconds drive
/// faster than [`gpodo_datasets::speed_check::MOVING_SPEED_MPS`].
///
/// # Errors
/// As the motion model's construction and the residuals' computation.
pub fn unit_check(logs: &[RoverLog], rover: &Path) -> Result<Option<f64>, PipelineError> {
    let spec = MotionModelSpec::WeightedJacobian {
        rover: Some(rover.to_path_buf()),
        config: Default::default(),
        attitude_without_imu: Default::default(),
    };
    crate::execute::data::speed_ratio(&spec, logs)
}

//! Reading a rover log and its camera file (format: see the parent module).

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

use super::columns::LogLayout;
use super::{QUATERNION_NORM_TOLERANCE, RoverLog};
use crate::DatasetError;
use crate::table::{NumericRows, column_index, read_numeric_csv};

/// A quaternion whose norm is within this of 1 is unit up to rounding and
/// kept as it is, so that writing and reading a log is bit-exact.
const ROUNDING_SLACK: f64 = 1e-12;

/// Reads the log at `path` (named after the file stem) and, when the sibling
/// `<stem>.camera.csv` exists, its camera frame times.
///
/// # Errors
/// An error naming the file and, where it applies, the line (header = 1) and
/// column: [`DatasetError::MissingColumn`], [`DatasetError::UnknownColumn`],
/// [`DatasetError::DuplicateColumn`], [`DatasetError::NotANumber`],
/// [`DatasetError::NonFinite`], [`DatasetError::NonIncreasingTime`],
/// [`DatasetError::Shape`], [`DatasetError::NotAUnitQuaternion`],
/// [`DatasetError::Empty`], [`DatasetError::Csv`], [`DatasetError::Io`].
pub fn read_log_csv(path: &Path) -> Result<RoverLog, DatasetError> {
    let (rows, layout) = read_numeric_csv(path, |header| {
        let layout = LogLayout::from_header(path, header)?;
        let indices = layout
            .column_names()
            .iter()
            .map(|c| column_index(path, header, c))
            .collect::<Result<_, _>>()?;
        Ok((indices, layout))
    })?;
    let rows = rows.require_rows()?;
    check_increasing(&rows, 0)?;
    let mut samples = Vec::with_capacity(rows.len());
    let mut ground_truth = Vec::with_capacity(rows.len());
    for i in 0..rows.len() {
        let (sample, translation, quaternion) = layout.decode(rows.row(i));
        let rotation = unit_rotation(path, rows.lines[i], quaternion)?;
        samples.push(sample);
        ground_truth.push(Isometry3::from_parts(
            Translation3::from(translation),
            rotation,
        ));
    }
    let stem = file_stem(path);
    let camera_times_secs = read_camera_times(&camera_path(path, &stem))?;
    let [wheel_names, steer_names, bogie_names] = layout.into_joint_names();
    Ok(RoverLog {
        name: stem,
        wheel_names,
        steer_names,
        bogie_names,
        samples,
        ground_truth,
        camera_times_secs,
    })
}

/// The camera file beside a log: `<dir>/<stem>.camera.csv`.
pub(super) fn camera_path(log_path: &Path, stem: &str) -> PathBuf {
    log_path.with_file_name(format!("{stem}.camera.csv"))
}

/// The file stem of `path` (lossy UTF-8), the log's name.
fn file_stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Camera frame times from `path`, or none when the file does not exist.
fn read_camera_times(path: &Path) -> Result<Vec<f64>, DatasetError> {
    let exists = path.try_exists().map_err(|source| DatasetError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if !exists {
        return Ok(Vec::new());
    }
    let (rows, ()) = read_numeric_csv(path, |header| {
        if let Some(column) = header
            .iter()
            .find(|h| *h != "time_s" && !h.starts_with("x_"))
        {
            return Err(DatasetError::UnknownColumn {
                path: path.to_path_buf(),
                column: column.clone(),
                hint: "a camera file has the single column `time_s` (and optional `x_` extras)"
                    .to_string(),
            });
        }
        Ok((vec![column_index(path, header, "time_s")?], ()))
    })?;
    check_increasing(&rows, 0)?;
    Ok(rows.values)
}

/// Fails at the first row whose selected column `j` (a time) does not
/// exceed the row before.
fn check_increasing(rows: &NumericRows, j: usize) -> Result<(), DatasetError> {
    for i in 1..rows.len() {
        let (previous, found) = (rows.row(i - 1)[j], rows.row(i)[j]);
        if found <= previous {
            return Err(DatasetError::NonIncreasingTime {
                path: rows.path.clone(),
                line: rows.lines[i],
                previous,
                found,
            });
        }
    }
    Ok(())
}

/// The rotation of a ground-truth quaternion: rejected when far from unit
/// norm, kept when unit up to rounding, normalised otherwise.
fn unit_rotation(
    path: &Path,
    line: u64,
    q: Quaternion<f64>,
) -> Result<UnitQuaternion<f64>, DatasetError> {
    let norm = q.norm();
    let error = (norm - 1.0).abs();
    if error > QUATERNION_NORM_TOLERANCE {
        return Err(DatasetError::NotAUnitQuaternion {
            path: path.to_path_buf(),
            line,
            norm,
            tolerance: QUATERNION_NORM_TOLERANCE,
        });
    }
    if error <= ROUNDING_SLACK {
        return Ok(UnitQuaternion::new_unchecked(q));
    }
    Ok(UnitQuaternion::new_normalize(q))
}

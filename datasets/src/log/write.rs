//! Writing a rover log and its camera file (format: see the parent module),
//! losslessly and atomically.

use std::fmt::Write as _;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Write as _};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::RoverLog;
use super::columns::LogLayout;
use super::read::camera_path;
use crate::DatasetError;

/// Writes `<dir>/<name>.csv` and `<dir>/<name>.camera.csv` (the camera file
/// has a header only when the log has no camera frames) and returns their
/// paths, log first.
///
/// Each file is first written in full to a temporary file in `dir`, then
/// renamed over its target, so a file is replaced whole or not at all. Both
/// files are staged before either is renamed; only if the second rename
/// fails has the first file already been replaced.
///
/// # Errors
/// [`DatasetError::InvalidLog`] when [`RoverLog::validate`] fails or the name
/// cannot be a file stem (empty, starting with `.`, holding a path separator
/// or a control character); [`DatasetError::Io`] when writing fails (nothing
/// is left behind but what was there before).
pub fn write_log_csv(log: &RoverLog, dir: &Path) -> Result<(PathBuf, PathBuf), DatasetError> {
    log.validate()?;
    check_file_stem(log)?;
    let log_path = dir.join(format!("{}.csv", log.name));
    let staged_log = StagedFile::stage(&log_path, log_text(log).as_bytes())?;
    let staged_camera = StagedFile::stage(
        &camera_path(&log_path, &log.name),
        camera_text(&log.camera_times_secs).as_bytes(),
    )?;
    Ok((staged_log.commit()?, staged_camera.commit()?))
}

/// Fails when the log's name cannot be used as a file stem.
fn check_file_stem(log: &RoverLog) -> Result<(), DatasetError> {
    let name = &log.name;
    let bad = name.is_empty()
        || name.starts_with('.')
        || name
            .chars()
            .any(|c| c == '/' || c == '\\' || c == ':' || c.is_control());
    if bad {
        return Err(DatasetError::InvalidLog {
            log: name.clone(),
            sample: None,
            detail: "the name must be a file stem: non-empty, not starting with `.`, \
                     without `/`, `\\`, `:` or control characters"
                .to_string(),
        });
    }
    Ok(())
}

/// The columns of the log's CSV and its rows, as `<name>.csv` holds them
/// (for a table in memory, such as a pandas DataFrame).
pub fn log_table(log: &RoverLog) -> (Vec<String>, Vec<Vec<f64>>) {
    let layout = LogLayout::of_log(log);
    let rows = log
        .samples
        .iter()
        .zip(&log.ground_truth)
        .map(|(sample, pose)| layout.encode(sample, pose))
        .collect();
    (layout.column_names(), rows)
}

/// The text of `<name>.csv`.
fn log_text(log: &RoverLog) -> String {
    let layout = LogLayout::of_log(log);
    let mut text = layout.column_names().join(",");
    text.push('\n');
    for (sample, pose) in log.samples.iter().zip(&log.ground_truth) {
        push_row(&mut text, &layout.encode(sample, pose));
    }
    text
}

/// The text of `<name>.camera.csv`.
fn camera_text(times: &[f64]) -> String {
    let mut text = String::from("time_s\n");
    for &t in times {
        push_row(&mut text, &[t]);
    }
    text
}

/// Appends `values`, comma separated, and a newline.
fn push_row(text: &mut String, values: &[f64]) {
    for (j, &x) in values.iter().enumerate() {
        if j > 0 {
            text.push(',');
        }
        push_f64(text, x);
    }
    text.push('\n');
}

/// Appends `x` in the shortest decimal form that parses back to the same
/// bits: plain notation for magnitudes in `[1e-5, 1e16)` and zero, exponent
/// notation otherwise (so `1e-300` is not written with 300 zeros).
fn push_f64(text: &mut String, x: f64) {
    let magnitude = x.abs();
    // Writing to a `String` cannot fail.
    let _ = if magnitude == 0.0 || (1e-5..1e16).contains(&magnitude) {
        write!(text, "{x}")
    } else {
        write!(text, "{x:e}")
    };
}

/// A file written in full under a temporary name beside its target; renamed
/// onto the target by [`StagedFile::commit`], removed if dropped uncommitted.
pub(crate) struct StagedFile {
    temp: PathBuf,
    target: PathBuf,
    committed: bool,
}

impl StagedFile {
    /// Writes `contents` to a new temporary file beside `target` and syncs it.
    pub(crate) fn stage(target: &Path, contents: &[u8]) -> Result<Self, DatasetError> {
        let (temp, mut file) = create_temp_beside(target)?;
        let staged = Self {
            temp,
            target: target.to_path_buf(),
            committed: false,
        };
        file.write_all(contents)
            .and_then(|()| file.sync_all())
            .map_err(|source| DatasetError::Io {
                path: staged.temp.clone(),
                source,
            })?;
        Ok(staged)
    }

    /// Renames the temporary file onto the target.
    pub(crate) fn commit(mut self) -> Result<PathBuf, DatasetError> {
        fs::rename(&self.temp, &self.target).map_err(|source| DatasetError::Io {
            path: self.target.clone(),
            source,
        })?;
        self.committed = true;
        Ok(self.target.clone())
    }
}

impl Drop for StagedFile {
    fn drop(&mut self) {
        if !self.committed {
            // Best effort: the temporary file is hidden and uniquely named.
            let _ = fs::remove_file(&self.temp);
        }
    }
}

/// Creates a new, uniquely named hidden file in the directory of `target`.
fn create_temp_beside(target: &Path) -> Result<(PathBuf, File), DatasetError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let file_name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut last_error = None;
    for _ in 0..64 {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let temp = target.with_file_name(format!(".{file_name}.{}.{n}.tmp", std::process::id()));
        match OpenOptions::new().write(true).create_new(true).open(&temp) {
            Ok(file) => return Ok((temp, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => last_error = Some(e),
            Err(source) => return Err(DatasetError::Io { path: temp, source }),
        }
    }
    Err(DatasetError::Io {
        path: target.to_path_buf(),
        source: last_error.unwrap_or_else(|| io::Error::other("no free temporary file name")),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_are_written_shortest_and_read_back_bit_exact() {
        let values = [
            0.1 + 0.2,
            1e-300,
            -0.0,
            0.0,
            5e-324,
            f64::MAX,
            f64::MIN_POSITIVE,
            -1.7347235e-18,
            123456.789,
            1e16 - 2.0,
            1e16,
            1e-5,
            9.99999e-6,
        ];
        for x in values {
            let mut text = String::new();
            push_f64(&mut text, x);
            let back: f64 = text.parse().unwrap();
            assert_eq!(back.to_bits(), x.to_bits(), "{x} written as {text}");
        }
        let mut text = String::new();
        push_f64(&mut text, 1e-300);
        assert_eq!(text, "1e-300");
    }
}

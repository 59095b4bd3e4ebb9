//! The error type of `gpodo-datasets`: everything that can go wrong while
//! reading, checking, writing or preparing rover data.
//!
//! Errors about a file name the file and, where they apply, the line
//! (1-based, the header being line 1) and the column, so a user can open the
//! file and fix it.

use std::path::PathBuf;

/// Why a dataset could not be read, written, checked or prepared.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DatasetError {
    /// An image could not be read or addressed.
    #[error(transparent)]
    Image(#[from] gpodo_vision::VisionError),
    /// Opening, reading, writing or renaming a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// What the operating system reported.
        #[source]
        source: std::io::Error,
    },
    /// The file is not well-formed CSV (invalid UTF-8, a bad header, ...).
    #[error("{}, line {line}: {detail}", path.display())]
    Csv {
        /// The file concerned.
        path: PathBuf,
        /// 1-based line (the header is line 1); 0 when unknown.
        line: u64,
        /// What is wrong.
        detail: String,
    },
    /// A column the reader needs is not in the header.
    #[error("{}: missing column `{column}`", path.display())]
    MissingColumn {
        /// The file concerned.
        path: PathBuf,
        /// The name of the missing column.
        column: String,
    },
    /// The header holds a column the format does not know (a typo, usually).
    #[error("{}: unknown column `{column}` ({hint})", path.display())]
    UnknownColumn {
        /// The file concerned.
        path: PathBuf,
        /// The name of the unknown column.
        column: String,
        /// What would be accepted instead.
        hint: String,
    },
    /// Two header columns have the same name.
    #[error("{}: column `{column}` appears more than once in the header", path.display())]
    DuplicateColumn {
        /// The file concerned.
        path: PathBuf,
        /// The repeated name.
        column: String,
    },
    /// A cell does not parse as a number.
    #[error("{}, line {line}, column `{column}`: `{value}` is not a number", path.display())]
    NotANumber {
        /// The file concerned.
        path: PathBuf,
        /// 1-based line (the header is line 1).
        line: u64,
        /// The column's name.
        column: String,
        /// The cell's text.
        value: String,
    },
    /// A cell holds NaN or an infinity.
    #[error("{}, line {line}, column `{column}`: value is not finite", path.display())]
    NonFinite {
        /// The file concerned.
        path: PathBuf,
        /// 1-based line (the header is line 1).
        line: u64,
        /// The column's name.
        column: String,
    },
    /// A time stamp is not greater than the one before it.
    #[error(
        "{}, line {line}, column `time_s`: time {found} s does not increase on the previous {previous} s",
        path.display()
    )]
    NonIncreasingTime {
        /// The file concerned.
        path: PathBuf,
        /// 1-based line of the offending time stamp.
        line: u64,
        /// The time stamp on the line before (s).
        previous: f64,
        /// The offending time stamp (s).
        found: f64,
    },
    /// A ground-truth quaternion is too far from unit norm to be a rotation.
    #[error(
        "{}, line {line}, columns `gt_qw..gt_qz`: quaternion norm {norm} is not within {tolerance} of 1",
        path.display()
    )]
    NotAUnitQuaternion {
        /// The file concerned.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// The norm found.
        norm: f64,
        /// The largest accepted `|norm − 1|`.
        tolerance: f64,
    },
    /// The file has no header or no data rows.
    #[error("{}: no data (a header row and at least one data row are needed)", path.display())]
    Empty {
        /// The file concerned.
        path: PathBuf,
    },
    /// A line has a different number of fields from the header.
    #[error("{}, line {line}: expected {expected} fields (as in the header), found {found}", path.display())]
    Shape {
        /// The file concerned.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// Number of header columns.
        expected: usize,
        /// Number of fields on the line.
        found: usize,
    },
    /// An in-memory rover log is inconsistent (see `RoverLog::validate`).
    #[error("log `{log}`{}: {detail}", sample.map(|i| format!(", sample {i}")).unwrap_or_default())]
    InvalidLog {
        /// The log's name.
        log: String,
        /// 0-based index of the offending sample, when one is to blame.
        sample: Option<usize>,
        /// What is wrong.
        detail: String,
    },
    /// A setting or argument is out of its domain.
    #[error("invalid `{field}`: expected {expected}")]
    InvalidConfig {
        /// The setting's name.
        field: String,
        /// What would be accepted (may include the value found).
        expected: String,
    },
    /// A matrix has the wrong number of columns.
    #[error("{what}: expected {expected} columns, found {found}")]
    DimensionMismatch {
        /// What was being checked.
        what: String,
        /// The number of columns needed.
        expected: usize,
        /// The number of columns given.
        found: usize,
    },
    /// A computation needs at least one sample and got none.
    #[error("{what}: no samples")]
    NoSamples {
        /// What needed the samples.
        what: String,
    },
    /// An in-memory matrix holds NaN or an infinity.
    #[error("{what}: entry at row {row}, column {column} (0-based) is not finite")]
    NonFiniteEntry {
        /// What was being checked.
        what: String,
        /// 0-based row.
        row: usize,
        /// 0-based column.
        column: usize,
    },
    /// A gpodo data type rejected what it was given.
    #[error(transparent)]
    Model(#[from] gpodo_traits::Error),
}

impl From<gpodo_traits::InvalidCameraField> for DatasetError {
    fn from(e: gpodo_traits::InvalidCameraField) -> Self {
        Self::InvalidConfig {
            field: e.field,
            expected: e.expected,
        }
    }
}

//! The errors of reading an experiment ([`ConfigError`]) and of running
//! one ([`PipelineError`]). Later stages (runner, records, reports) keep
//! their own error types beside their code.

use std::path::PathBuf;

/// Why an experiment file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The YAML is malformed or does not match the schema.
    #[error("{}: {detail}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// The parser's message, with line and column.
        detail: String,
    },
    /// A field has an invalid value.
    #[error("{}: {detail}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Which field and what was expected.
        detail: String,
    },
    /// A value at a known place is not acceptable.
    #[error("{problem} at {}:{line}:{column}; expected {expected}", file.display())]
    Located {
        /// The file that holds the value.
        file: PathBuf,
        /// Line (from 1; 0 when unknown).
        line: usize,
        /// Column (from 1; 0 when unknown).
        column: usize,
        /// Path of the value (`regressors[1].kernel`).
        path: String,
        /// What is wrong.
        problem: String,
        /// What would be accepted.
        expected: String,
    },
    /// The file describes several runs where one experiment is needed.
    #[error("{}: a sweep of {runs} runs; expected a single experiment here", path.display())]
    NotSingle {
        /// The file.
        path: PathBuf,
        /// How many runs it expands to.
        runs: usize,
    },
}

/// Why an experiment failed.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// Reading or preparing data failed.
    #[error(transparent)]
    Dataset(#[from] gpodo_datasets::DatasetError),
    /// Simulating the testbed or rendering its camera failed.
    #[error(transparent)]
    Testbed(#[from] gpodo_testbed::TestbedError),
    /// A ROS bag could not be imported.
    #[error(transparent)]
    Bag(#[from] gpodo_datasets::bags::import::ImportError),
    /// The rover description or motion model is invalid.
    #[error(transparent)]
    Kinematics(#[from] gpodo_kinematics::KinematicsError),
    /// A regressor's fit would need more memory than the machine has.
    #[error(
        "regressor `{label}`: a fit on {rows} rows would need about {needed} at its peak; {available} are available (fewer rows, a sparse GP, or a larger machine)"
    )]
    TooLarge {
        /// The regressor.
        label: String,
        /// Its training rows.
        rows: usize,
        /// What the fit would need.
        needed: String,
        /// What is available.
        available: String,
    },
    /// A regressor failed.
    #[error("regressor `{label}`: {source}")]
    Regressor {
        /// The regressor.
        label: String,
        /// What failed.
        source: gpodo_traits::Error,
    },
    /// A regressor's fit failed (in the work shared by the runs that use
    /// it); the runs that need it fail with this, the others go on.
    #[error("regressor `{label}` could not be fitted: {reason}")]
    FitFailed {
        /// The regressor.
        label: String,
        /// The fit's error.
        reason: String,
    },
    /// Building or scoring a regressor failed.
    #[error(transparent)]
    Spec(#[from] gpodo_regressors::RegressorError),
    /// A model failed on a sample.
    #[error(transparent)]
    Model(#[from] gpodo_traits::Error),
    /// Training and test rows do not have the same columns, or a scheme
    /// refers to something that is not there.
    #[error("inconsistent experiment: {0}")]
    Inconsistent(String),
    /// The visual front end failed.
    #[error(transparent)]
    Frontend(#[from] gpodo_frontends::FrontendError),
    /// A file or folder could not be written, or an input not read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A configuration file (a topic map, say) could not be read.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A scheme of Table II failed.
    #[error("scheme `{label}`: {source}")]
    Scheme {
        /// The scheme.
        label: String,
        /// What failed.
        source: Box<PipelineError>,
    },
}

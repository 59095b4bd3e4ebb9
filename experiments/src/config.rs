//! The experiment file: what data, which motion model, how residuals are
//! formed, which regressors. Unknown fields are errors, and every error names
//! the file, line and column.
//!
//! ```yaml
//! name: paper
//! dataset: { kind: simulated, preset: exoter-prl, seed: 7 }
//! motion_model: { kind: weighted_jacobian }
//! residuals: { window_secs: 1.0 }
//! regressors:
//!   - kind: zero
//! ```

use std::path::{Path, PathBuf};

use gpodo_datasets::residuals::ResidualConfig;
use gpodo_datasets::sim::preset::Preset;
use gpodo_kinematics::{WeightedJacobianConfig, YawSource};
use gpodo_regressors::RegressorSpec;

use crate::bench::BenchSettings;
use crate::schemes::SchemeSpec;
use gpodo_frontends::FrontendParams;
use serde::{Deserialize, Serialize};

/// A whole experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExperimentConfig {
    /// Name; results go to `results/<name>/` unless told otherwise.
    pub name: String,
    /// Free text shown at the top of the report.
    #[serde(default)]
    pub description: Option<String>,
    /// Where the data come from.
    pub dataset: DatasetSpec,
    /// The parametric motion model (ignored for residual tables).
    #[serde(default)]
    pub motion_model: MotionModelSpec,
    /// How log steps become residual rows (ignored for residual tables).
    #[serde(default)]
    pub residuals: ResidualConfig,
    /// Regressors to train and evaluate, in report order.
    pub regressors: Vec<RegressorSpec>,
    /// A residual table (e.g. the authors' real ExoTeR data) whose
    /// statistics the report shows beside this experiment's, to judge how
    /// close a simulated testbed is to the real rover. Skipped with a warning
    /// when the file is missing.
    #[serde(default)]
    pub compare_with: Option<ReferenceTable>,
    /// Settings of `gpodo bench` (ignored by `gpodo run`).
    #[serde(default)]
    pub bench: BenchSettings,
    /// The visual front end of Table II (visual odometry, keyframes, back
    /// end); every field has a default.
    #[serde(default)]
    pub frontend: FrontendParams,
    /// The SLAM schemes of Table II, run on every test run (needs rover
    /// logs: `simulated` or `logs` data).
    #[serde(default)]
    pub schemes: Vec<SchemeSpec>,
}

/// A reference residual table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceTable {
    /// CSV file (relative to the experiment file).
    pub path: PathBuf,
    /// Its target columns.
    pub targets: Vec<String>,
}

/// Where the data come from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum DatasetSpec {
    /// The built-in simulated testbed.
    Simulated {
        /// Preset (`exoter-prl`).
        preset: Preset,
        /// Seed of every random draw.
        seed: u64,
        /// Override of the preset's number of training runs.
        #[serde(default)]
        training_runs: Option<usize>,
        /// Override of the preset's training run duration (s).
        #[serde(default)]
        training_run_secs: Option<f64>,
        /// Override of the longest the test traverse may take (s); a shorter
        /// value cuts the traverse (quick runs, tests).
        #[serde(default)]
        test_max_secs: Option<f64>,
    },
    /// Rover logs in gpodo's trajectory CSV format (paths relative to the
    /// experiment file).
    Logs {
        /// Training runs.
        train: Vec<PathBuf>,
        /// Test runs.
        test: Vec<PathBuf>,
    },
    /// A residual table (features and targets already computed), split in
    /// time order.
    ResidualTable {
        /// CSV file (relative to the experiment file).
        path: PathBuf,
        /// Input columns; omitted, every column that is not a target.
        #[serde(default)]
        inputs: Option<Vec<String>>,
        /// Target columns.
        targets: Vec<String>,
        /// Fraction of rows (the first ones) used for training.
        train_fraction: f64,
    },
}

/// The parametric motion model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum MotionModelSpec {
    /// The weighted Jacobian model of §III.
    WeightedJacobian {
        /// Rover description YAML (relative to the experiment file);
        /// omitted, the built-in ExoTeR-like rover.
        #[serde(default)]
        rover: Option<PathBuf>,
        /// Model settings.
        #[serde(default)]
        config: WeightedJacobianConfig,
    },
    /// The ideal skid-steer model.
    SkidSteer {
        /// Rover description YAML; omitted, the ExoTeR-like rover.
        #[serde(default)]
        rover: Option<PathBuf>,
        /// Angular rate source.
        #[serde(default)]
        yaw: YawSource,
    },
}

impl Default for MotionModelSpec {
    fn default() -> Self {
        Self::WeightedJacobian {
            rover: None,
            config: WeightedJacobianConfig::default(),
        }
    }
}

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

impl ExperimentConfig {
    /// Reads and validates an experiment file that describes one run (a
    /// file with `base:` is fine; one with `sweep:` or several `seeds:` is
    /// not).
    ///
    /// # Errors
    /// [`ConfigError`] naming the file, line and column.
    pub fn from_path(path: &Path) -> Result<Self, ConfigError> {
        let plan = crate::sweep::load_plan(path)?;
        let runs = plan.runs.len();
        match <[crate::sweep::RunSpec; 1]>::try_from(plan.runs) {
            Ok([run]) => Ok(run.config),
            Err(_) => Err(ConfigError::NotSingle {
                path: path.to_path_buf(),
                runs,
            }),
        }
    }

    /// Checks values that the schema alone cannot.
    ///
    /// # Errors
    /// The first [`Issue`], with the path of the offending value.
    pub fn validate(&self) -> Result<(), Issue> {
        if self.name.is_empty()
            || !self
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return Err(Issue::new(
                "name",
                format!("invalid name `{}`", self.name),
                "letters, digits, `-` or `_` (it names the results folder)",
            ));
        }
        if self.regressors.is_empty() {
            return Err(Issue::new(
                "regressors",
                "no regressor",
                "at least one regressor",
            ));
        }
        for (i, r) in self.regressors.iter().enumerate() {
            r.validate()
                .map_err(|e| Issue::from_regressor(&format!("regressors[{i}]"), e))?;
        }
        self.residuals
            .validate()
            .map_err(|e| Issue::from_dataset("", e))?;
        self.bench
            .validate(self.regressors.len())
            .map_err(|(field, expected)| {
                Issue::new(
                    &format!("bench.{field}"),
                    format!("invalid `bench.{field}`"),
                    expected,
                )
            })?;
        if let MotionModelSpec::WeightedJacobian { config, .. } = &self.motion_model {
            config.validate().map_err(|e| match e {
                gpodo_kinematics::KinematicsError::InvalidConfig { field, expected } => Issue::new(
                    &format!("motion_model.config.{field}"),
                    format!("invalid `motion_model.config.{field}`"),
                    expected,
                ),
                other => Issue::new("motion_model.config", other.to_string(), "a valid model"),
            })?;
        }
        self.validate_schemes()?;
        match &self.dataset {
            DatasetSpec::ResidualTable { train_fraction, .. }
                if !(*train_fraction > 0.0 && *train_fraction < 1.0) =>
            {
                Err(Issue::new(
                    "dataset.train_fraction",
                    format!("training fraction {train_fraction}"),
                    "a fraction in (0, 1)",
                ))
            }
            DatasetSpec::Logs { train, test } if train.is_empty() || test.is_empty() => {
                Err(Issue::new(
                    "dataset",
                    "no training or no test log",
                    "at least one `train` and one `test` log",
                ))
            }
            _ => Ok(()),
        }
    }
}

/// A value of an experiment file that is not acceptable, by path
/// (`regressors[1].kernel`); the loader turns the path into a file, line
/// and column.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Issue {
    /// Path of the offending value.
    pub path: String,
    /// What is wrong.
    pub problem: String,
    /// What would be accepted.
    pub expected: String,
}

impl Issue {
    /// An issue at `path`.
    pub fn new(path: &str, problem: impl Into<String>, expected: impl Into<String>) -> Self {
        Self {
            path: path.to_string(),
            problem: problem.into(),
            expected: expected.into(),
        }
    }

    /// A regressor's invalid setting, under `prefix` (`regressors[1]`).
    pub fn from_regressor(prefix: &str, e: gpodo_regressors::RegressorError) -> Self {
        match e {
            gpodo_regressors::RegressorError::InvalidSpec {
                regressor,
                field,
                expected,
            } => Self::new(
                &format!("{prefix}.{field}"),
                format!("invalid `{field}` of {regressor}"),
                expected,
            ),
            other => Self::new(prefix, other.to_string(), "a valid regressor"),
        }
    }

    /// A front-end component's invalid setting, under `prefix`
    /// (`schemes[2].selector` for selectors, `frontend` for settings).
    pub fn from_frontend(prefix: &str, e: gpodo_frontends::FrontendError) -> Self {
        match e {
            gpodo_frontends::FrontendError::InvalidSpec {
                selector,
                field,
                expected,
            } => Self::new(
                &format!("{prefix}.{field}"),
                format!("invalid `{field}` of selector {selector}"),
                expected,
            ),
            gpodo_frontends::FrontendError::InvalidConfig { field, expected } => Self::new(
                &format!("frontend.{field}"),
                format!("invalid `{field}`"),
                expected,
            ),
            other => Self::new(prefix, other.to_string(), "a valid setting"),
        }
    }

    /// A dataset setting, under `prefix` (empty for top-level sections).
    pub fn from_dataset(prefix: &str, e: gpodo_datasets::DatasetError) -> Self {
        match e {
            gpodo_datasets::DatasetError::InvalidConfig { field, expected } => {
                let path = if prefix.is_empty() {
                    field.clone()
                } else {
                    format!("{prefix}.{field}")
                };
                Self::new(&path, format!("invalid `{field}`"), expected)
            }
            other => Self::new(prefix, other.to_string(), "a valid setting"),
        }
    }
}

impl std::fmt::Display for Issue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "field `{}`: {}; expected {}",
            self.path, self.problem, self.expected
        )
    }
}

impl ExperimentConfig {
    /// The labels of the regressors, as reports print them.
    pub fn regressor_labels(&self) -> Vec<String> {
        self.regressors.iter().map(RegressorSpec::label).collect()
    }

    fn validate_schemes(&self) -> Result<(), Issue> {
        if self.schemes.is_empty() {
            return Ok(());
        }
        if matches!(self.dataset, DatasetSpec::ResidualTable { .. }) {
            return Err(Issue::new(
                "schemes",
                "schemes on a residual table",
                "rover logs (`dataset.kind: simulated` or `logs`); a residual table has no trajectory or camera frames",
            ));
        }
        self.frontend
            .validate()
            .map_err(|e| Issue::from_frontend("frontend", e))?;
        let labels = self.regressor_labels();
        let mut seen = std::collections::HashSet::new();
        for (i, scheme) in self.schemes.iter().enumerate() {
            let at = |field: &str| format!("schemes[{i}].{field}");
            if scheme.label.trim().is_empty() {
                return Err(Issue::new(
                    &at("label"),
                    "empty label",
                    "a non-empty row label",
                ));
            }
            if !seen.insert(scheme.label.as_str()) {
                return Err(Issue::new(
                    &at("label"),
                    format!("duplicate label `{}`", scheme.label),
                    "a label no other scheme has",
                ));
            }
            scheme
                .selector
                .validate()
                .map_err(|e| Issue::from_frontend(&at("selector"), e))?;
            match (&scheme.online, &scheme.regressor) {
                (Some(_), Some(_)) => {
                    return Err(Issue::new(
                        &at("online"),
                        "both `regressor` and `online`",
                        "either `regressor` (trained offline) or `online`, not both",
                    ));
                }
                (Some(online), None) => {
                    online
                        .regressor
                        .validate()
                        .map_err(|e| Issue::from_regressor(&at("online.regressor"), e))?;
                    if online.refit_every == Some(0) || online.min_targets == 0 {
                        return Err(Issue::new(
                            &at("online.refit_every"),
                            "zero targets",
                            "refit_every and min_targets of at least 1",
                        ));
                    }
                }
                (None, _) => {
                    scheme
                        .regressor_index(&labels)
                        .map_err(|(problem, expected)| {
                            Issue::new(&at("regressor"), problem, expected)
                        })?;
                }
            }
            if let Some(oracle) = scheme.selector.oracle()
                && let Some(other) = &oracle.same_as
            {
                let found = self
                    .schemes
                    .iter()
                    .any(|s| &s.label == other && s.selector.oracle().is_none());
                if !found {
                    return Err(Issue::new(
                        &at("selector.same_as"),
                        format!("no scheme `{other}`"),
                        "the label of a scheme that is not an oracle",
                    ));
                }
            }
        }
        if self.residuals.window_secs.is_none() {
            return Err(Issue::new(
                "residuals.window_secs",
                "per-step rows with schemes",
                "a window length (the front end predicts once per window)",
            ));
        }
        Ok(())
    }
}

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
}

impl ExperimentConfig {
    /// Reads and validates an experiment file.
    ///
    /// # Errors
    /// [`ConfigError`] naming the file (and line and column for YAML errors).
    pub fn from_path(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_yaml_str(&text, path)
    }

    /// Parses and validates experiment YAML; `path` is used in messages.
    ///
    /// # Errors
    /// [`ConfigError::Parse`] or [`ConfigError::Invalid`].
    pub fn from_yaml_str(text: &str, path: &Path) -> Result<Self, ConfigError> {
        let config: Self = serde_saphyr::from_str(text).map_err(|e| ConfigError::Parse {
            path: path.to_path_buf(),
            detail: e.to_string(),
        })?;
        config.validate().map_err(|detail| ConfigError::Invalid {
            path: path.to_path_buf(),
            detail,
        })?;
        Ok(config)
    }

    /// Checks values that the schema alone cannot.
    fn validate(&self) -> Result<(), String> {
        if self.name.is_empty()
            || !self
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return Err(format!(
                "field `name`: expected letters, digits, `-` or `_` (it names the results folder), found `{}`",
                self.name
            ));
        }
        if self.regressors.is_empty() {
            return Err("field `regressors`: expected at least one regressor".into());
        }
        for (i, r) in self.regressors.iter().enumerate() {
            r.validate().map_err(|e| format!("regressors[{i}]: {e}"))?;
        }
        self.residuals.validate().map_err(|e| e.to_string())?;
        self.bench.validate(self.regressors.len())?;
        if let MotionModelSpec::WeightedJacobian { config, .. } = &self.motion_model {
            config.validate().map_err(|e| e.to_string())?;
        }
        self.validate_schemes()?;
        match &self.dataset {
            DatasetSpec::ResidualTable { train_fraction, .. }
                if !(*train_fraction > 0.0 && *train_fraction < 1.0) =>
            {
                Err("field `dataset.train_fraction`: expected a fraction in (0, 1)".into())
            }
            DatasetSpec::Logs { train, test } if train.is_empty() || test.is_empty() => {
                Err("field `dataset`: expected at least one `train` and one `test` log".into())
            }
            _ => Ok(()),
        }
    }
}

impl ExperimentConfig {
    /// The labels of the regressors, as reports print them.
    pub fn regressor_labels(&self) -> Vec<String> {
        self.regressors.iter().map(RegressorSpec::label).collect()
    }

    fn validate_schemes(&self) -> Result<(), String> {
        if self.schemes.is_empty() {
            return Ok(());
        }
        if matches!(self.dataset, DatasetSpec::ResidualTable { .. }) {
            return Err(
                "field `schemes`: expected rover logs (`dataset.kind: simulated` or `logs`); a residual table has no trajectory or camera frames".into(),
            );
        }
        self.frontend
            .validate()
            .map_err(|e| format!("field `frontend`: {e}"))?;
        let labels = self.regressor_labels();
        let mut seen = std::collections::HashSet::new();
        for (i, scheme) in self.schemes.iter().enumerate() {
            let at = |e: String| format!("schemes[{i}] (`{}`): {e}", scheme.label);
            if scheme.label.trim().is_empty() {
                return Err(format!(
                    "schemes[{i}]: field `label`: expected a non-empty row label"
                ));
            }
            if !seen.insert(scheme.label.as_str()) {
                return Err(at(
                    "field `label`: expected a label no other scheme has".into()
                ));
            }
            scheme.selector.validate().map_err(|e| at(e.to_string()))?;
            match (&scheme.online, &scheme.regressor) {
                (Some(_), Some(_)) => {
                    return Err(at(
                        "expected either `regressor` (trained offline) or `online`, not both"
                            .into(),
                    ));
                }
                (Some(online), None) => {
                    online
                        .regressor
                        .validate()
                        .map_err(|e| at(format!("online.regressor: {e}")))?;
                    if online.refit_every == Some(0) || online.min_targets == 0 {
                        return Err(at(
                            "online: expected refit_every and min_targets of at least 1".into(),
                        ));
                    }
                }
                (None, _) => {
                    scheme.regressor_index(&labels).map_err(at)?;
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
                    return Err(at(format!(
                        "selector.same_as: expected the label of a scheme that is not an oracle, found `{other}`"
                    )));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(yaml: &str) -> Result<ExperimentConfig, ConfigError> {
        ExperimentConfig::from_yaml_str(yaml, Path::new("exp.yaml"))
    }

    #[test]
    fn minimal_simulated_experiment_parses_with_defaults() {
        let c = parse(
            "name: t\ndataset: {kind: simulated, preset: exoter-prl, seed: 7}\nregressors:\n  - kind: zero\n",
        )
        .unwrap();
        assert_eq!(c.motion_model, MotionModelSpec::default());
        assert_eq!(c.residuals.window_secs, Some(1.0));
    }

    #[test]
    fn unknown_field_names_file_and_position() {
        let err = parse(
            "name: t\ndataset: {kind: simulated, preset: exoter-prl, seed: 7}\nregresors:\n  - kind: zero\n",
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("exp.yaml") && err.contains("regresors"),
            "{err}"
        );
        assert!(err.contains('3'), "line number expected: {err}");
    }

    #[test]
    fn unknown_regressor_kind_is_an_error() {
        let err = parse(
            "name: t\ndataset: {kind: simulated, preset: exoter-prl, seed: 7}\nregressors:\n  - kind: exactgp\n",
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("exactgp"), "{err}");
    }

    #[test]
    fn invalid_values_name_the_field() {
        let err = parse(
            "name: t\ndataset: {kind: residual_table, path: x.csv, targets: [a], train_fraction: 1.5}\nregressors:\n  - kind: zero\n",
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("train_fraction"), "{err}");
        let err = parse(
            "name: t\ndataset: {kind: simulated, preset: exoter-prl, seed: 7}\nregressors:\n  - kind: zero\n    variance: -1\n",
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("regressors[0]") && err.contains("variance"),
            "{err}"
        );
    }
}

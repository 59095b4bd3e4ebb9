//! Checks of an experiment that the schema alone cannot make, each failure
//! an [`Issue`] at the path of the offending value.

use super::{DatasetSpec, ExperimentConfig, MotionModelSpec};

impl ExperimentConfig {
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
        for (i, r) in self.absolute_regressors.iter().enumerate() {
            r.validate()
                .map_err(|e| Issue::from_regressor(&format!("absolute_regressors[{i}]"), e))?;
        }
        self.residuals
            .validate()
            .map_err(|e| Issue::from_dataset("", e))?;
        if self.residuals.score_window_secs.is_some() {
            if matches!(self.dataset, DatasetSpec::ResidualTable { .. }) {
                return Err(Issue::new(
                    "residuals.score_window_secs",
                    "scoring windows on a residual table",
                    "no `score_window_secs`: a table's rows are scored as they are",
                ));
            }
            if !self.absolute_regressors.is_empty() {
                return Err(Issue::new(
                    "residuals.score_window_secs",
                    "scoring windows with `absolute_regressors`",
                    "no `score_window_secs`, or no |residual| regressors (the mean of absolute step residuals is not the absolute window mean)",
                ));
            }
        }
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
        if let Some(rules) = &self.verdict {
            let curves: Vec<(String, bool, String)> = self
                .schemes
                .iter()
                .filter_map(|s| {
                    let name = s.curve.clone()?;
                    let fixed =
                        matches!(s.selector, gpodo_frontends::SelectorSpec::FixedRate { .. });
                    Some((name, fixed, s.back_end(self)))
                })
                .fold(Vec::new(), |mut acc, (name, fixed, back_end)| {
                    match acc.iter_mut().find(|(n, ..)| *n == name) {
                        Some(c) => c.1 &= fixed,
                        None => acc.push((name, fixed, back_end)),
                    }
                    acc
                });
            rules.validate(&curves)?;
        }
        if let Some(margin) = self.equivalence_margin_m
            && !(margin.is_finite() && margin > 0.0)
        {
            return Err(Issue::new(
                "equivalence_margin_m",
                format!("invalid equivalence margin {margin}"),
                "a positive margin in metres",
            ));
        }
        if let gpodo_frontends::params::VoSpec::Replay(p) = &self.frontend.vo {
            let recorded =
                matches!(&self.dataset, DatasetSpec::Bags { topics, .. } if topics.vo.is_some());
            if p.path.as_os_str().is_empty() && !recorded && !self.schemes.is_empty() {
                return Err(Issue::new(
                    "frontend.vo.path",
                    "a replayed VO without a `path`",
                    "a TUM trajectory file, or a `bags` dataset whose topic map has a `vo` topic",
                ));
            }
        }
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
            DatasetSpec::Bags {
                train_fraction: Some(f),
                ..
            } if !(*f > 0.0 && *f < 1.0) => Err(Issue::new(
                "dataset.train_fraction",
                format!("training fraction {f}"),
                "a fraction in (0, 1)",
            )),
            DatasetSpec::Bags {
                train,
                train_fraction: Some(_),
                ..
            } if train.is_empty() => Err(Issue::new(
                "dataset.train",
                "no training recording",
                "at least one recording to cut at `train_fraction`",
            )),
            DatasetSpec::Bags {
                train_fraction: Some(_),
                ..
            } => Ok(()),
            DatasetSpec::Logs { train, test } | DatasetSpec::Bags { train, test, .. }
                if train.is_empty() || test.is_empty() =>
            {
                Err(Issue::new(
                    "dataset",
                    "no training or no test log",
                    "at least one `train` and one `test` log",
                ))
            }
            DatasetSpec::Simulated {
                slip_bursts: Some(bursts),
                ..
            } => bursts.validate().map_err(|e| match e {
                gpodo_testbed::TestbedError::InvalidConfig { field, expected } => Issue::new(
                    &field.replacen("slip.bursts", "dataset.slip_bursts", 1),
                    "out of range",
                    expected,
                ),
                other => Issue::new("dataset.slip_bursts", other.to_string(), "valid settings"),
            }),
            DatasetSpec::Simulated { .. }
            | DatasetSpec::Logs { .. }
            | DatasetSpec::Bags { .. }
            | DatasetSpec::ResidualTable { .. } => Ok(()),
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
        let absolute_labels = self.absolute_regressor_labels();
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
            if let Some(rescale) = &scheme.rescale_keyframes {
                rescale
                    .validate()
                    .map_err(|e| Issue::from_frontend(&at("rescale_keyframes"), e))?;
            }
            match (&scheme.online, &scheme.regressor, &scheme.odometry) {
                (Some(_), Some(_), _) => {
                    return Err(Issue::new(
                        &at("online"),
                        "both `regressor` and `online`",
                        "either `regressor` (trained offline) or `online`, not both",
                    ));
                }
                (Some(_), None, Some(_)) => {
                    return Err(Issue::new(
                        &at("odometry"),
                        "`odometry` on an online scheme",
                        "no `odometry`: an online learner's mean corrects the odometry and its variance sets the covariance",
                    ));
                }
                (None, Some(_), Some(_)) => {
                    return Err(Issue::new(
                        &at("odometry"),
                        "both `regressor` and `odometry`",
                        "either `regressor` (its mean and variance) or `odometry` (naming both regressors), not both",
                    ));
                }
                (Some(online), None, None) => {
                    online
                        .regressor
                        .validate()
                        .map_err(|e| Issue::from_regressor(&at("online.regressor"), e))?;
                    if online.refit_every == Some(0) || online.min_targets == 0 {
                        let field = if online.refit_every == Some(0) {
                            "online.refit_every"
                        } else {
                            "online.min_targets"
                        };
                        return Err(Issue::new(
                            &at(field),
                            "zero targets",
                            "refit_every and min_targets of at least 1",
                        ));
                    }
                    online.mode().map_err(|(field, expected)| {
                        Issue::new(
                            &at(&field),
                            "both `refit_every` and `batch_secs`",
                            &expected,
                        )
                    })?;
                    if let Some(secs) = online.batch_secs
                        && !(secs.is_finite() && secs > 0.0)
                    {
                        return Err(Issue::new(
                            &at("online.batch_secs"),
                            format!("a batch of {secs} s"),
                            "a positive, finite number of seconds",
                        ));
                    }
                    // Without refits, the learner learns row by row or in
                    // batches, which a batch-only regressor cannot.
                    if online.refit_every.is_none()
                        && let Ok(model) = online.regressor.build()
                        && !model.supports_online_update()
                    {
                        return Err(Issue::new(
                            &at("online.regressor.kind"),
                            format!("`{}`, which cannot learn online", model.name()),
                            "a regressor that learns online (ilgr, sparse_spectrum, streaming_sparse_gp), or `refit_every` for one that is refitted",
                        ));
                    }
                }
                (None, _, _) => {}
            }
            let mode = scheme
                .resolve_odometry(&labels, &absolute_labels)
                .map_err(|(field, problem, expected)| Issue::new(&at(field), problem, expected))?
                .map(|r| r.mode)
                .unwrap_or_default();
            scheme
                .selector
                .for_odometry(&mode)
                .map_err(|e| Issue::from_frontend(&at("selector"), e))?;
            if scheme.selector.oracle().is_some() && scheme.online.is_some() {
                return Err(Issue::new(
                    &at("online"),
                    "an oracle that learns online",
                    "a trained `regressor` (the oracle plans with its predictions)",
                ));
            }
            if let Some(other) = scheme.selector.same_as() {
                let found = self
                    .schemes
                    .iter()
                    .any(|s| &s.label == other && s.selector.same_as().is_none());
                if !found {
                    return Err(Issue::new(
                        &at("selector.same_as"),
                        format!("no scheme `{other}`"),
                        "the label of a scheme that takes no other's frames",
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

//! One regressor fitted on the training rows and scored on the test rows.

use std::path::Path;

use gpodo_regressors::RegressorSpec;
use gpodo_regressors::metrics::evaluate;
use gpodo_traits::{ResidualDataset, ResidualRegressor};

use crate::error::PipelineError;
use crate::execute::results::RegressorResult;

/// Builds the runtime regressor of `spec`, with an external regressor's
/// relative paths resolved against `base` (the experiment file's folder).
///
/// # Errors
/// As [`RegressorSpec::build`].
pub(crate) fn build_regressor(
    spec: &RegressorSpec,
    base: &Path,
) -> Result<Box<dyn ResidualRegressor>, gpodo_regressors::RegressorError> {
    match spec {
        RegressorSpec::External(p) => {
            RegressorSpec::External(p.clone().resolved_against(base)).build()
        }
        other => other.build(),
    }
}

/// Fits one regressor on the training rows and scores it on the test rows.
pub(crate) fn fit_and_score(
    spec: &RegressorSpec,
    base: &Path,
    train: &ResidualDataset,
    test: &ResidualDataset,
    progress: Option<std::sync::Arc<dyn gpodo_traits::FitProgress>>,
) -> Result<(RegressorResult, Box<dyn ResidualRegressor>), PipelineError> {
    let label = spec.label();
    tracing::info!(regressor = %label, n = train.len(), "fitting");
    let mut model = build_regressor(spec, base)?;
    model.set_progress(progress);
    let wrap = |source| PipelineError::Regressor {
        label: label.clone(),
        source,
    };
    let fit = model.fit(train).map_err(wrap)?;
    let predictions = model.predict(&test.inputs).map_err(wrap)?;
    let evaluation = evaluate(&predictions, &test.targets)?;
    tracing::info!(regressor = %label, secs = fit.duration_secs, "fitted");
    Ok((
        RegressorResult {
            label,
            spec: spec.clone(),
            fit,
            evaluation,
        },
        model,
    ))
}

//! One regressor fitted on the training rows and scored on the test rows.

use gpodo_regressors::RegressorSpec;
use gpodo_regressors::metrics::evaluate;
use gpodo_traits::{ResidualDataset, ResidualRegressor};

use crate::error::PipelineError;
use crate::execute::results::RegressorResult;

/// Fits one regressor on the training rows and scores it on the test rows.
pub(crate) fn fit_and_score(
    spec: &RegressorSpec,
    train: &ResidualDataset,
    test: &ResidualDataset,
    progress: Option<std::sync::Arc<dyn gpodo_traits::FitProgress>>,
) -> Result<(RegressorResult, Box<dyn ResidualRegressor>), PipelineError> {
    let label = spec.label();
    tracing::info!(regressor = %label, n = train.len(), "fitting");
    let mut model = spec.build()?;
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

//! One regressor fitted on the training rows and scored on the test rows.

use gpodo_regressors::RegressorSpec;
use gpodo_traits::{ResidualDataset, ResidualRegressor};

use crate::error::PipelineError;
use crate::execute::results::{ModelRows, RegressorResult};

/// Fits one regressor on the training rows and scores it on the test rows.
pub(crate) fn fit_and_score(
    spec: &RegressorSpec,
    rows: &ModelRows,
    progress: Option<std::sync::Arc<dyn gpodo_traits::FitProgress>>,
) -> Result<(RegressorResult, Box<dyn ResidualRegressor>), PipelineError> {
    let (label, train) = (spec.label(), &rows.train);
    check_memory(spec, &label, train, crate::util::memory::available_bytes())?;
    tracing::info!(regressor = %label, n = train.len(), "fitting");
    let mut model = spec.build()?;
    model.set_progress(progress);
    let wrap = |source| PipelineError::Regressor {
        label: label.clone(),
        source,
    };
    let fit = model.fit(train).map_err(wrap)?;
    let predictions = model.predict(&rows.test.inputs).map_err(wrap)?;
    let evaluation = rows.score(&predictions)?;
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

/// Refuses a fit of `spec` on `train` whose peak memory
/// ([`RegressorSpec::fit_memory_bytes`]) exceeds what is `available`.
///
/// # Errors
/// [`PipelineError::TooLarge`] with both sizes.
pub(crate) fn check_memory(
    spec: &RegressorSpec,
    label: &str,
    train: &ResidualDataset,
    available: Option<u64>,
) -> Result<(), PipelineError> {
    let (n, d, p) = (train.len(), train.inputs.ncols(), train.targets.ncols());
    match (spec.fit_memory_bytes(n, d, p), available) {
        (Some(needed), Some(available)) if needed > available => Err(PipelineError::TooLarge {
            label: label.to_string(),
            rows: n,
            needed: crate::util::memory::show_bytes(needed),
            available: crate::util::memory::show_bytes(available),
        }),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use gpodo_traits::SampleMatrix;

    use super::*;

    fn rows(n: usize) -> ResidualDataset {
        ResidualDataset::new(
            SampleMatrix::zeros(n, 2),
            SampleMatrix::zeros(n, 1),
            vec!["a".into(), "b".into()],
            vec!["y".into()],
        )
        .unwrap()
    }

    #[test]
    fn a_fit_larger_than_the_memory_is_refused_with_both_sizes() {
        let exact: RegressorSpec = serde_json::from_str(r#"{"kind": "exact_gp"}"#).unwrap();
        // 1000 rows: five 1000 × 1000 matrices, 40 MB and a little.
        let e = check_memory(&exact, "exact GP: rbf", &rows(1000), Some(10_000_000)).unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains("1000 rows")
                && text.contains("about 40.1 MB")
                && text.contains("10.0 MB are available"),
            "{text}"
        );
        assert!(check_memory(&exact, "x", &rows(1000), Some(100_000_000)).is_ok());
        assert!(check_memory(&exact, "x", &rows(1000), None).is_ok());
        let ilgr: RegressorSpec = serde_json::from_str(r#"{"kind": "ilgr"}"#).unwrap();
        assert!(check_memory(&ilgr, "ILGR", &rows(1000), Some(1)).is_ok());
    }
}

//! What the GP regressors share around their numerics: checking training
//! and query data, z-scoring inputs and outputs with training statistics,
//! and mapping predictions back to target units (mean × std + mean,
//! variance × std²).

use faer::{Mat, MatRef};
use gpodo_traits::Standardizer;
use gpodo_traits::{Error, ResidualDataset, SampleMatrix};

use crate::RegressorError;
use crate::dense::{from_faer, to_faer};

/// Predictions with the latent variance kept apart from the noise.
#[derive(Debug, Clone, PartialEq)]
pub struct GpPredictions {
    /// Predictive mean, target units.
    pub mean: SampleMatrix,
    /// Variance of the latent function, target units.
    pub latent_variance: SampleMatrix,
    /// Variance of a noisy target (latent + noise), target units.
    pub variance: SampleMatrix,
}

/// Fails on the first non-finite value, naming its row and column.
///
/// # Errors
/// [`RegressorError::InvalidData`].
pub fn check_finite(what: &str, m: &SampleMatrix) -> Result<(), RegressorError> {
    for (i, row) in m.rows().enumerate() {
        if let Some(j) = row.iter().position(|v| !v.is_finite()) {
            return Err(RegressorError::InvalidData {
                detail: format!("{what}: non-finite value at row {i}, column {j}"),
            });
        }
    }
    Ok(())
}

/// Training data after the checks and the optional z-scoring.
pub struct ScaledTraining {
    /// Input scaling (None when standardisation is off).
    pub input_scaler: Option<Standardizer>,
    /// Output scaling (None when standardisation is off).
    pub output_scaler: Option<Standardizer>,
    /// Scaled inputs.
    pub x: SampleMatrix,
    /// Scaled targets.
    pub y: SampleMatrix,
}

impl ScaledTraining {
    /// Checks `data` (non-empty, finite) and z-scores it when `standardize`
    /// (the targets, and the inputs unless
    /// [`ResidualDataset::inputs_standardized`]).
    ///
    /// # Errors
    /// [`RegressorError::InvalidData`] or a standardisation error.
    pub fn new(data: &ResidualDataset, standardize: bool) -> Result<Self, RegressorError> {
        let (n, d, p) = (data.len(), data.inputs.ncols(), data.targets.ncols());
        if n == 0 || d == 0 || p == 0 {
            return Err(RegressorError::InvalidData {
                detail: format!(
                    "need samples, inputs and outputs; got {n} × {d} inputs, {p} outputs"
                ),
            });
        }
        check_finite("inputs", &data.inputs)?;
        check_finite("targets", &data.targets)?;
        if !standardize {
            return Ok(Self {
                input_scaler: None,
                output_scaler: None,
                x: data.inputs.clone(),
                y: data.targets.clone(),
            });
        }
        // Inputs an experiment z-scored already are not z-scored again.
        let si = if data.inputs_standardized {
            None
        } else {
            Some(Standardizer::fit(&data.inputs)?)
        };
        let so = Standardizer::fit(&data.targets)?;
        Ok(Self {
            x: match &si {
                Some(si) => si.transform(&data.inputs)?,
                None => data.inputs.clone(),
            },
            y: so.transform(&data.targets)?,
            input_scaler: si,
            output_scaler: Some(so),
        })
    }
}

/// Checks query inputs (width `d`, finite) and scales them like the
/// training inputs.
///
/// # Errors
/// [`Error::DimensionMismatch`], [`Error::InvalidInput`].
pub fn scale_queries(
    model: &str,
    inputs: &SampleMatrix,
    d: usize,
    scaler: Option<&Standardizer>,
) -> Result<Mat<f64>, Error> {
    if inputs.ncols() != d {
        return Err(Error::DimensionMismatch {
            what: format!("{model} inputs"),
            expected: d,
            found: inputs.ncols(),
        });
    }
    check_finite("prediction inputs", inputs).map_err(|e| Error::InvalidInput(e.to_string()))?;
    Ok(match scaler {
        Some(s) => to_faer(&s.transform(inputs)?),
        None => to_faer(inputs),
    })
}

/// Maps scaled predictive moments back to target units.
///
/// # Errors
/// [`Error::DimensionMismatch`] when the moments do not have the scaler's
/// width.
pub fn unscale_predictions(
    mean: MatRef<'_, f64>,
    latent: MatRef<'_, f64>,
    noisy: MatRef<'_, f64>,
    scaler: Option<&Standardizer>,
) -> Result<GpPredictions, Error> {
    let (mean, latent, noisy) = (from_faer(mean), from_faer(latent), from_faer(noisy));
    Ok(match scaler {
        Some(s) => GpPredictions {
            mean: s.inverse_transform_mean(&mean)?,
            latent_variance: s.inverse_transform_variance(&latent)?,
            variance: s.inverse_transform_variance(&noisy)?,
        },
        None => GpPredictions {
            mean,
            latent_variance: latent,
            variance: noisy,
        },
    })
}

/// The [`ResidualRegressor`](gpodo_traits::ResidualRegressor) impl the
/// Gaussian processes share: `fit` through the model's `fit_impl`
/// (a [`RegressorError`] becomes a backend error), `predict` through its
/// `predict_full` (dropping the latent variance), and the optimiser's
/// progress sink in its `progress` field.
macro_rules! gp_residual_regressor {
    ($model:ty, $name:literal) => {
        impl gpodo_traits::ResidualRegressor for $model {
            fn name(&self) -> &str {
                $name
            }

            fn fit(
                &mut self,
                data: &gpodo_traits::ResidualDataset,
            ) -> Result<gpodo_traits::FitReport, gpodo_traits::Error> {
                self.fit_impl(data).map_err(gpodo_traits::Error::from)
            }

            fn set_progress(
                &mut self,
                progress: Option<std::sync::Arc<dyn gpodo_traits::FitProgress>>,
            ) {
                self.progress = $crate::hyperopt::ProgressSink(progress);
            }

            fn predict(
                &self,
                inputs: &gpodo_traits::SampleMatrix,
            ) -> Result<gpodo_traits::Predictions, gpodo_traits::Error> {
                let full = self.predict_full(inputs)?;
                Ok(gpodo_traits::Predictions {
                    mean: full.mean,
                    variance: full.variance,
                })
            }
        }
    };
}
pub(crate) use gp_residual_regressor;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inputs_an_experiment_standardised_are_not_scaled_again() -> Result<(), RegressorError> {
        let x =
            SampleMatrix::from_row_major(4, 2, vec![1.0, 10.0, 2.0, 30.0, 4.0, 20.0, 5.0, 0.0])?;
        let y = SampleMatrix::from_row_major(4, 1, vec![0.1, 0.3, 0.2, 0.6])?;
        let names = |p: &str, n: usize| (0..n).map(|i| format!("{p}{i}")).collect();
        let data = ResidualDataset::new(x.clone(), y, names("x", 2), names("y", 1))?;
        let raw = ScaledTraining::new(&data, true)?;
        assert!(raw.input_scaler.is_some());
        assert!(raw.x.column(0).iter().sum::<f64>().abs() < 1e-12);
        let marked = ScaledTraining::new(&data.with_standardized_inputs(true), true)?;
        assert!(marked.input_scaler.is_none());
        assert_eq!(marked.x, x);
        assert_eq!(marked.y, raw.y);
        assert!(marked.output_scaler.is_some());
        Ok(())
    }
}

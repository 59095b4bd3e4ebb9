//! The "parametric model only" regressor: it predicts that the motion model
//! is right (zero residual), with a variance that is either fixed or the
//! training residuals' mean square per output (the error variance of a
//! zero-mean predictor). Every later regressor must beat it.

use std::time::Instant;

use gpodo_traits::{
    Error, FitReport, Predictions, ResidualDataset, ResidualRegressor, SampleMatrix,
};

/// Predicts a zero residual with a fixed or training variance.
#[derive(Debug, Clone, PartialEq)]
pub struct ZeroResidual {
    fixed_variance: Option<f64>,
    variance: Option<Vec<f64>>,
    n_inputs: Option<usize>,
}

impl ZeroResidual {
    /// With `fixed_variance = Some(v)` every output's variance is `v` and no
    /// fit is needed; with `None` `fit` learns each output's mean square.
    pub fn new(fixed_variance: Option<f64>) -> Self {
        Self {
            fixed_variance,
            variance: None,
            n_inputs: None,
        }
    }
}

impl ResidualRegressor for ZeroResidual {
    fn name(&self) -> &str {
        "zero"
    }

    fn fit(&mut self, data: &ResidualDataset) -> Result<FitReport, Error> {
        let start = Instant::now();
        if data.is_empty() {
            return Err(Error::InvalidInput("cannot fit on an empty dataset".into()));
        }
        let n = data.len() as f64;
        let variance = (0..data.targets.ncols())
            .map(|j| {
                self.fixed_variance
                    .unwrap_or_else(|| data.targets.rows().map(|r| r[j] * r[j]).sum::<f64>() / n)
            })
            .collect();
        self.variance = Some(variance);
        self.n_inputs = Some(data.inputs.ncols());
        Ok(FitReport {
            n_samples: data.len(),
            duration_secs: start.elapsed().as_secs_f64(),
            ..Default::default()
        })
    }

    fn predict(&self, inputs: &SampleMatrix) -> Result<Predictions, Error> {
        let (Some(variance), Some(d)) = (&self.variance, self.n_inputs) else {
            return Err(Error::NotFitted {
                model: self.name().into(),
            });
        };
        if inputs.ncols() != d {
            return Err(Error::DimensionMismatch {
                what: "input columns".into(),
                expected: d,
                found: inputs.ncols(),
            });
        }
        let o = variance.len();
        let rows = vec![variance.clone(); inputs.nrows()];
        Ok(Predictions {
            mean: SampleMatrix::zeros(inputs.nrows(), o),
            variance: SampleMatrix::from_rows(o, &rows)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data() -> ResidualDataset {
        let x = SampleMatrix::from_rows(2, &[[0.0, 1.0], [1.0, 0.0]]).unwrap();
        let y = SampleMatrix::from_rows(3, &[[0.1, -0.2, 0.0], [-0.3, 0.2, 0.0]]).unwrap();
        ResidualDataset::new(
            x,
            y,
            vec!["a".into(), "b".into()],
            vec!["x".into(), "y".into(), "z".into()],
        )
        .unwrap()
    }

    #[test]
    fn predicts_zero_mean_and_training_mean_square_variance() {
        let mut m = ZeroResidual::new(None);
        let d = data();
        m.fit(&d).unwrap();
        let p = m.predict(&d.inputs).unwrap();
        assert!(p.mean.as_slice().iter().all(|&v| v == 0.0));
        assert!((p.variance.get(0, 0) - (0.01 + 0.09) / 2.0).abs() < 1e-15);
        assert!((p.variance.get(1, 1) - 0.04).abs() < 1e-15);
        assert_eq!(p.variance.get(1, 2), 0.0);
    }

    #[test]
    fn fixed_variance_is_used_as_given() {
        let mut m = ZeroResidual::new(Some(2.5e-5));
        let d = data();
        m.fit(&d).unwrap();
        let p = m.predict(&d.inputs).unwrap();
        assert!(p.variance.as_slice().iter().all(|&v| v == 2.5e-5));
    }

    #[test]
    fn predict_before_fit_and_wrong_width_are_errors() {
        let m = ZeroResidual::new(None);
        let d = data();
        assert!(matches!(m.predict(&d.inputs), Err(Error::NotFitted { .. })));
        let mut m = m;
        m.fit(&d).unwrap();
        let wide = SampleMatrix::zeros(1, 3);
        assert!(matches!(
            m.predict(&wide),
            Err(Error::DimensionMismatch { .. })
        ));
        assert!(m.update(&[0.0, 0.0], &[0.0; 3]).is_err());
    }
}

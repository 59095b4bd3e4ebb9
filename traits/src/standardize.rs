//! Per-column z-scoring of inputs and targets, as the authors did before
//! fitting their GP (inputs and outputs "normalised", paper §IV and the
//! authors' model on the ExoTeR table): `z = (x − mean) / std`.
//!
//! A regressor fits a [`Standardizer`] on its training data, transforms
//! inputs before learning and predicting, and maps predictions back with
//! [`Standardizer::inverse_transform_mean`] and
//! [`Standardizer::inverse_transform_variance`].

use serde::{Deserialize, Serialize};

use crate::{Error, SampleMatrix};

/// Population standard deviations at or below this count as zero: such a
/// column is constant up to rounding noise (the ExoTeR table holds columns of
/// `0` and `±1.7e-18`), and scaling it up would turn that noise into a
/// feature. Its scale is set to 1.
pub const MIN_STD: f64 = 1e-12;

/// Column means and standard deviations learned from training data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Standardizer {
    /// Mean of each column.
    pub mean: Vec<f64>,
    /// Scale of each column: its population standard deviation, or 1 for a
    /// constant column (std ≤ [`MIN_STD`]), which then maps to 0 instead of
    /// NaN.
    pub std: Vec<f64>,
}

impl Standardizer {
    /// Learns the mean and population standard deviation (divisor `n`) of
    /// each column of `data`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a matrix without rows, or naming the row
    /// and column of a NaN or an infinity.
    pub fn fit(data: &SampleMatrix) -> Result<Self, Error> {
        let what = "standardizer fit";
        if data.nrows() == 0 {
            return Err(Error::InvalidInput(format!("{what}: no samples")));
        }
        check_finite(what, data)?;
        let n = data.nrows() as f64;
        let (mean, std) = (0..data.ncols())
            .map(|j| {
                let column = data.column(j);
                let mean = column.iter().sum::<f64>() / n;
                let var = column.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
                let std = var.sqrt();
                (mean, if std <= MIN_STD { 1.0 } else { std })
            })
            .unzip();
        Ok(Self { mean, std })
    }

    /// Number of columns this standardizer was fitted on.
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// `(x − mean) / std` for each column.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] when `data` has a different
    /// number of columns from the training data.
    pub fn transform(&self, data: &SampleMatrix) -> Result<SampleMatrix, Error> {
        self.map_columns("standardizer transform", data, |x, mean, std| {
            (x - mean) / std
        })
    }

    /// Maps standardized values (e.g. a predictive mean) back to original
    /// units: `z · std + mean`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] as for [`Self::transform`].
    pub fn inverse_transform_mean(&self, data: &SampleMatrix) -> Result<SampleMatrix, Error> {
        self.map_columns("standardizer inverse (mean)", data, |z, mean, std| {
            z * std + mean
        })
    }

    /// Maps variances of standardized values back to original units:
    /// `var · std²` (the mean shift does not change a variance).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] as for [`Self::transform`].
    pub fn inverse_transform_variance(
        &self,
        variance: &SampleMatrix,
    ) -> Result<SampleMatrix, Error> {
        self.map_columns("standardizer inverse (variance)", variance, |v, _, std| {
            v * std * std
        })
    }

    /// Applies `f(value, mean_j, std_j)` to every entry of column `j`.
    fn map_columns(
        &self,
        what: &str,
        data: &SampleMatrix,
        f: impl Fn(f64, f64, f64) -> f64,
    ) -> Result<SampleMatrix, Error> {
        if data.ncols() != self.dim() {
            return Err(Error::DimensionMismatch {
                what: what.to_string(),
                expected: self.dim(),
                found: data.ncols(),
            });
        }
        let mut out = data.clone();
        for i in 0..out.nrows() {
            for (j, x) in out.row_mut(i).iter_mut().enumerate() {
                *x = f(*x, self.mean[j], self.std[j]);
            }
        }
        Ok(out)
    }
}

/// Fails on the first entry of `data` that is NaN or infinite.
fn check_finite(what: &str, data: &SampleMatrix) -> Result<(), Error> {
    for (row, values) in data.rows().enumerate() {
        if let Some(column) = values.iter().position(|x| !x.is_finite()) {
            return Err(Error::InvalidInput(format!(
                "{what}: row {row}, column {column} is not finite"
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use approx::assert_relative_eq;

    use super::*;

    fn training() -> SampleMatrix {
        SampleMatrix::from_rows(
            3,
            &[
                [1.0, 10.0, 5.0],
                [2.0, -20.0, 5.0],
                [4.0, 30.0, 5.0],
                [9.0, 0.5, 5.0],
            ],
        )
        .unwrap()
    }

    #[test]
    fn transformed_training_data_has_zero_mean_and_unit_std() {
        let s = Standardizer::fit(&training()).unwrap();
        let z = s.transform(&training()).unwrap();
        for j in 0..2 {
            let col = z.column(j);
            let mean = col.iter().sum::<f64>() / 4.0;
            let var = col.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 4.0;
            assert_relative_eq!(mean, 0.0, epsilon = 1e-12);
            assert_relative_eq!(var.sqrt(), 1.0, epsilon = 1e-12);
        }
    }

    #[test]
    fn constant_column_gets_unit_scale_and_maps_to_zero() {
        let s = Standardizer::fit(&training()).unwrap();
        assert_eq!(s.std[2], 1.0);
        assert_eq!(s.transform(&training()).unwrap().column(2), [0.0; 4]);
    }

    #[test]
    fn uses_population_std() {
        let s = Standardizer::fit(&training()).unwrap();
        // Column 0: mean 4, squared deviations 9 + 4 + 0 + 25 = 38, n = 4.
        assert_relative_eq!(s.mean[0], 4.0);
        assert_relative_eq!(s.std[0], (38.0_f64 / 4.0).sqrt());
    }

    #[test]
    fn inverse_transform_of_mean_round_trips() {
        let s = Standardizer::fit(&training()).unwrap();
        let back = s
            .inverse_transform_mean(&s.transform(&training()).unwrap())
            .unwrap();
        for (a, b) in back.as_slice().iter().zip(training().as_slice()) {
            assert_relative_eq!(a, b, epsilon = 1e-12);
        }
    }

    #[test]
    fn variance_scales_by_std_squared() {
        let s = Standardizer {
            mean: vec![100.0, -3.0],
            std: vec![2.0, 0.5],
        };
        let var = SampleMatrix::from_rows(2, &[[1.0, 1.0], [0.25, 4.0]]).unwrap();
        let back = s.inverse_transform_variance(&var).unwrap();
        assert_eq!(back.as_slice(), &[4.0, 0.25, 1.0, 1.0]);
    }

    #[test]
    fn rejects_matrix_of_other_width() {
        let s = Standardizer::fit(&training()).unwrap();
        let err = s.transform(&SampleMatrix::zeros(2, 4)).unwrap_err();
        assert!(matches!(
            err,
            Error::DimensionMismatch {
                expected: 3,
                found: 4,
                ..
            }
        ));
        assert!(
            s.inverse_transform_variance(&SampleMatrix::zeros(1, 2))
                .is_err()
        );
    }

    #[test]
    fn fit_rejects_empty_and_non_finite_data() {
        let empty = Standardizer::fit(&SampleMatrix::zeros(0, 2)).unwrap_err();
        assert!(matches!(empty, Error::InvalidInput(_)), "{empty}");
        let nan = SampleMatrix::from_rows(2, &[[0.0, 1.0], [f64::NAN, 2.0]]).unwrap();
        let err = Standardizer::fit(&nan).unwrap_err();
        assert!(
            matches!(&err, Error::InvalidInput(m) if m.contains("row 1, column 0")),
            "{err}"
        );
    }
}

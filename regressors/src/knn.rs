//! [`Knn`]: k-nearest-neighbour regression of the residual, the worked
//! example of adding a regressor to gpodo (`experiments/README.md`, "Adding
//! your own regressor"). The prediction at `x` is the mean of the targets
//! of the `k` training rows nearest to `x` (Euclidean distance on the
//! standardised inputs the pipeline hands over), and the variance is their
//! sample variance plus the variance of that mean: `s²(1 + 1/k)`, floored
//! at `min_variance`. Fitting stores the rows; a query costs `O(n d)`.

use std::time::Instant;

use gpodo_traits::{
    Error, FitReport, Predictions, ResidualDataset, ResidualRegressor, SampleMatrix,
};
use serde::{Deserialize, Serialize};

use crate::RegressorError;

/// Settings of [`Knn`] (`kind: knn`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct KnnParams {
    /// Number of neighbours (default 10).
    pub k: usize,
    /// Smallest predictive variance per output, target units squared
    /// (default 1e-8).
    pub min_variance: f64,
}

impl Default for KnnParams {
    fn default() -> Self {
        Self {
            k: 10,
            min_variance: 1e-8,
        }
    }
}

impl KnnParams {
    /// Checks every field.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the field.
    pub fn check(&self) -> Result<(), RegressorError> {
        let bad = |field: &str, expected: &str| {
            Err(RegressorError::InvalidSpec {
                regressor: "knn".into(),
                field: field.into(),
                expected: expected.into(),
            })
        };
        if self.k == 0 {
            return bad("k", "at least 1 neighbour");
        }
        if !(self.min_variance.is_finite() && self.min_variance > 0.0) {
            return bad("min_variance", "a positive variance");
        }
        Ok(())
    }
}

/// The k-nearest-neighbour regressor.
#[derive(Debug, Clone)]
pub struct Knn {
    params: KnnParams,
    data: Option<ResidualDataset>,
}

impl Knn {
    /// A regressor with checked settings.
    ///
    /// # Errors
    /// As [`KnnParams::check`].
    pub fn new(params: KnnParams) -> Result<Self, RegressorError> {
        params.check()?;
        Ok(Self { params, data: None })
    }
}

impl ResidualRegressor for Knn {
    fn name(&self) -> &str {
        "knn"
    }

    fn fit(&mut self, data: &ResidualDataset) -> Result<FitReport, Error> {
        let start = Instant::now();
        if data.is_empty() {
            return Err(Error::InvalidInput(
                "k-NN needs at least one training row".into(),
            ));
        }
        if self.params.k > data.len() {
            tracing::warn!(
                asked = self.params.k,
                used = data.len(),
                "k-NN: more neighbours asked than training rows: every row is one"
            );
        }
        for (i, row) in data.inputs.rows().chain(data.targets.rows()).enumerate() {
            if row.iter().any(|v| !v.is_finite()) {
                return Err(Error::InvalidInput(format!(
                    "k-NN: non-finite value in training row {}",
                    i % data.len()
                )));
            }
        }
        self.data = Some(data.clone());
        Ok(FitReport {
            n_samples: data.len(),
            duration_secs: start.elapsed().as_secs_f64(),
            // The neighbours actually used.
            parameters: vec![("k".into(), self.params.k.min(data.len()) as f64)],
            ..FitReport::default()
        })
    }

    fn predict(&self, inputs: &SampleMatrix) -> Result<Predictions, Error> {
        let Some(data) = &self.data else {
            return Err(Error::NotFitted {
                model: self.name().into(),
            });
        };
        let (d, o) = (data.inputs.ncols(), data.targets.ncols());
        if inputs.ncols() != d {
            return Err(Error::DimensionMismatch {
                what: "k-NN input columns".into(),
                expected: d,
                found: inputs.ncols(),
            });
        }
        let k = self.params.k.min(data.len());
        let mut mean = SampleMatrix::zeros(inputs.nrows(), o);
        let mut variance = SampleMatrix::zeros(inputs.nrows(), o);
        let mut distances: Vec<(f64, usize)> = Vec::with_capacity(data.len());
        for (q, x) in inputs.rows().enumerate() {
            distances.clear();
            distances.extend(data.inputs.rows().enumerate().map(|(i, row)| {
                let d2: f64 = row.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum();
                (d2, i)
            }));
            // Ties broken by row index, so predictions are deterministic.
            let nearest =
                |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
            if k < distances.len() {
                distances.select_nth_unstable_by(k - 1, nearest);
            }
            let chosen = &distances[..k];
            for out in 0..o {
                let ys: Vec<f64> = chosen
                    .iter()
                    .map(|(_, i)| data.targets.get(*i, out))
                    .collect();
                let m = ys.iter().sum::<f64>() / k as f64;
                let s2 = if k > 1 {
                    ys.iter().map(|y| (y - m) * (y - m)).sum::<f64>() / (k - 1) as f64
                } else {
                    0.0
                };
                mean.row_mut(q)[out] = m;
                variance.row_mut(q)[out] =
                    (s2 * (1.0 + 1.0 / k as f64)).max(self.params.min_variance);
            }
        }
        Ok(Predictions { mean, variance })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data() -> ResidualDataset {
        let x = SampleMatrix::from_row_major(5, 1, vec![0.0, 1.0, 2.0, 3.0, 10.0]).unwrap();
        let y = SampleMatrix::from_row_major(5, 1, vec![1.0, 2.0, 3.0, 4.0, 100.0]).unwrap();
        ResidualDataset::new(x, y, vec!["x".into()], vec!["y".into()]).unwrap()
    }

    #[test]
    fn predicts_the_mean_and_spread_of_the_nearest_targets() {
        let mut m = Knn::new(KnnParams {
            k: 3,
            min_variance: 1e-8,
        })
        .unwrap();
        m.fit(&data()).unwrap();
        let q = SampleMatrix::from_row_major(1, 1, vec![1.1]).unwrap();
        let p = m.predict(&q).unwrap();
        // Neighbours 1, 2 and 0 (x = 1, 2, 0): targets 2, 3, 1.
        assert_eq!(p.mean.get(0, 0), 2.0);
        assert!((p.variance.get(0, 0) - 1.0 * (1.0 + 1.0 / 3.0)).abs() < 1e-12);
        let far = SampleMatrix::from_row_major(1, 1, vec![50.0]).unwrap();
        let p = m.predict(&far).unwrap();
        assert_eq!(p.mean.get(0, 0), (100.0 + 4.0 + 3.0) / 3.0);
    }

    #[test]
    fn more_neighbours_than_rows_uses_every_row_and_says_so() {
        let rows = data().len();
        let mut all = Knn::new(KnnParams {
            k: rows,
            min_variance: 1e-8,
        })
        .unwrap();
        let mut more = Knn::new(KnnParams {
            k: 1_000_000,
            min_variance: 1e-8,
        })
        .unwrap();
        all.fit(&data()).unwrap();
        let report = more.fit(&data()).unwrap();
        assert_eq!(report.parameters, vec![("k".to_string(), rows as f64)]);
        let q = SampleMatrix::from_row_major(1, 1, vec![1.1]).unwrap();
        let (a, b) = (all.predict(&q).unwrap(), more.predict(&q).unwrap());
        assert_eq!(a.mean.get(0, 0), b.mean.get(0, 0));
        assert_eq!(a.variance.get(0, 0), b.variance.get(0, 0));
    }

    #[test]
    fn errors_before_fit_and_for_bad_settings() {
        let m = Knn::new(KnnParams::default()).unwrap();
        let q = SampleMatrix::from_row_major(1, 1, vec![0.0]).unwrap();
        assert!(matches!(m.predict(&q), Err(Error::NotFitted { .. })));
        let err = Knn::new(KnnParams {
            k: 0,
            ..KnnParams::default()
        })
        .unwrap_err();
        assert!(
            err.to_string().contains("`k`") || err.to_string().contains("k"),
            "{err}"
        );
    }
}

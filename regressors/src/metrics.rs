//! How well predicted residuals match the true ones on held-out data:
//! RMSE and MAE (paper Table I), per output and over all outputs, plus the
//! negative log predictive density (NLPD) and the coverage of the central
//! 95 % interval, which say whether the predicted variance can be trusted
//! (the frame selectors rely on it).

use gpodo_traits::{Predictions, SampleMatrix};
use serde::{Deserialize, Serialize};

use crate::RegressorError;

/// Half-width of the central 95 % interval of a standard normal.
const Z95: f64 = 1.959_963_984_540_054;

/// Scores of one output (or of all outputs pooled).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Scores {
    /// Root mean square error (target units).
    pub rmse: f64,
    /// Mean absolute error (target units).
    pub mae: f64,
    /// Mean negative log predictive density under N(mean, variance) (nats).
    pub nlpd: f64,
    /// Fraction of targets inside mean ± 1.96·sd.
    pub coverage95: f64,
}

/// Scores per output and pooled over all outputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    /// Number of test samples.
    pub n_samples: usize,
    /// One entry per output, in target order.
    pub per_output: Vec<Scores>,
    /// All outputs pooled (Table I reports one RMSE and MAE per kernel).
    pub pooled: Scores,
}

#[derive(Default)]
struct Accumulator {
    n: usize,
    squared: f64,
    absolute: f64,
    nlpd: f64,
    covered: usize,
}

impl Accumulator {
    fn add(&mut self, y: f64, mean: f64, variance: f64) {
        let e = y - mean;
        self.n += 1;
        self.squared += e * e;
        self.absolute += e.abs();
        let v = variance.max(f64::MIN_POSITIVE);
        self.nlpd += 0.5 * ((2.0 * std::f64::consts::PI * v).ln() + e * e / v);
        if e.abs() <= Z95 * v.sqrt() {
            self.covered += 1;
        }
    }

    fn scores(&self) -> Scores {
        let n = self.n as f64;
        Scores {
            rmse: (self.squared / n).sqrt(),
            mae: self.absolute / n,
            nlpd: self.nlpd / n,
            coverage95: self.covered as f64 / n,
        }
    }
}

/// Scores `predictions` against `targets` (same `n × o` shape).
///
/// # Errors
/// [`RegressorError::ShapeMismatch`] or [`RegressorError::EmptyTestSet`].
pub fn evaluate(
    predictions: &Predictions,
    targets: &SampleMatrix,
) -> Result<Evaluation, RegressorError> {
    let shape = |m: &SampleMatrix| (m.nrows(), m.ncols());
    if shape(&predictions.mean) != shape(targets) || shape(&predictions.variance) != shape(targets)
    {
        return Err(RegressorError::ShapeMismatch {
            predicted: shape(&predictions.mean),
            targets: shape(targets),
        });
    }
    if targets.nrows() == 0 || targets.ncols() == 0 {
        return Err(RegressorError::EmptyTestSet);
    }
    let mut per_output: Vec<Accumulator> = (0..targets.ncols())
        .map(|_| Accumulator::default())
        .collect();
    let mut pooled = Accumulator::default();
    for i in 0..targets.nrows() {
        let (y, m, v) = (
            targets.row(i),
            predictions.mean.row(i),
            predictions.variance.row(i),
        );
        for j in 0..targets.ncols() {
            per_output[j].add(y[j], m[j], v[j]);
            pooled.add(y[j], m[j], v[j]);
        }
    }
    Ok(Evaluation {
        n_samples: targets.nrows(),
        per_output: per_output.iter().map(Accumulator::scores).collect(),
        pooled: pooled.scores(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scores_match_a_hand_computation() {
        let targets = SampleMatrix::from_rows(2, &[[1.0, 0.0], [-1.0, 2.0]]).unwrap();
        let predictions = Predictions {
            mean: SampleMatrix::from_rows(2, &[[0.0, 0.0], [0.0, 0.0]]).unwrap(),
            variance: SampleMatrix::from_rows(2, &[[1.0, 1.0], [1.0, 1.0]]).unwrap(),
        };
        let e = evaluate(&predictions, &targets).unwrap();
        // Output 0: errors 1, −1. Output 1: errors 0, 2.
        assert_eq!(e.per_output[0].rmse, 1.0);
        assert_eq!(e.per_output[0].mae, 1.0);
        assert_eq!(e.per_output[1].rmse, 2f64.sqrt());
        assert_eq!(e.per_output[1].mae, 1.0);
        assert_eq!(e.pooled.rmse, (6.0f64 / 4.0).sqrt());
        assert_eq!(e.pooled.mae, 1.0);
        // |e| ≤ 1.96 for 1, 1, 0 but not 2.
        assert_eq!(e.pooled.coverage95, 0.75);
        let half_log_2pi = 0.5 * (2.0 * std::f64::consts::PI).ln();
        assert!((e.per_output[1].nlpd - (half_log_2pi + 0.5 * 4.0 / 2.0)).abs() < 1e-15);
    }

    #[test]
    fn mismatched_shapes_and_empty_sets_are_errors() {
        let t = SampleMatrix::zeros(2, 3);
        let p = Predictions {
            mean: SampleMatrix::zeros(2, 2),
            variance: SampleMatrix::zeros(2, 2),
        };
        assert!(matches!(
            evaluate(&p, &t),
            Err(RegressorError::ShapeMismatch { .. })
        ));
        let empty = SampleMatrix::zeros(0, 3);
        let p = Predictions {
            mean: empty.clone(),
            variance: empty.clone(),
        };
        assert!(matches!(
            evaluate(&p, &empty),
            Err(RegressorError::EmptyTestSet)
        ));
    }
}

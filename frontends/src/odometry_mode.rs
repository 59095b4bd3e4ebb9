//! How a scheme's wheel odometry uses the residual predictions: whether
//! the predicted mean corrects the velocity, and what sets the velocity
//! covariance of the odometry edges.
//!
//! | mode | mean | covariance (per body axis) | drift a budget counts |
//! |---|---|---|---|
//! | (a) gpodo's default | corrected by `μ` | `σ²`, the predictive variance | `Σ σ²` |
//! | (b) the authors' | uncorrected | `â²`, `â` a \|residual\| regressor's prediction | `‖â‖² + Σ σ²_â` |
//! | (c) both | corrected by `μ` | `â²` | `Σ â²` |
//!
//! The authors trained their GP on |residual| and wrote its prediction
//! into the odometry's velocity covariance (`cov_velocity =
//! prediction.asDiagonal()`, `slam-orogen-gp_odometry`, `GpyTask.cpp`):
//! read as a standard deviation, `â` is the root-mean-square residual, so
//! the variance is `â²` ([`CovarianceSource::AbsoluteResidual`]). Their
//! code literally uses `â` (m/s) as a variance ((m/s)²), which is
//! dimensionally inconsistent; [`CovarianceSource::AbsoluteResidualAsVariance`]
//! reproduces it.
//!
//! The drift a budget counts is that of the odometry the graph uses: the
//! variance left after the correction in (a) and (c); the whole second
//! moment of the residual, `E[r²] = E[|r|]² + Var|r|`, in (b), where
//! nothing is corrected. A policy that reads the residual sees the
//! regressor that sets the covariance: the |residual| regressor in (b) and
//! (c), as the authors' schedule did.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::FrontendError;
use crate::prediction::ResidualPrediction;

/// What sets the velocity covariance of the odometry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CovarianceSource {
    /// The signed regressor's predictive variance `σ²`.
    #[default]
    PredictiveVariance,
    /// A |residual| regressor's prediction `â` as the standard deviation:
    /// variance `â²`.
    AbsoluteResidual,
    /// The authors' code read literally: `â` itself as the variance
    /// (dimensionally inconsistent: m/s taken as (m/s)²).
    AbsoluteResidualAsVariance,
}

impl CovarianceSource {
    /// Whether the covariance comes from a |residual| regressor.
    pub fn is_absolute(self) -> bool {
        !matches!(self, Self::PredictiveVariance)
    }
}

/// How a scheme's odometry uses the residual predictions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OdometryMode {
    /// Add the predicted mean to the odometry's velocity (eq. 12).
    pub correct_mean: bool,
    /// What sets the velocity covariance.
    pub covariance: CovarianceSource,
}

impl Default for OdometryMode {
    fn default() -> Self {
        Self::CORRECTED
    }
}

/// One regressor window's effect on the odometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowOdometry {
    /// Added to the body velocity (m/s).
    pub correction: Vector3<f64>,
    /// Velocity variance of the odometry per body axis ((m/s)²): the
    /// edges' covariance.
    pub variance: Vector3<f64>,
    /// Expected squared velocity error of the uncorrected odometry
    /// ((m/s)²).
    pub uncorrected_sq_error: f64,
}

impl WindowOdometry {
    /// Before any prediction: no correction, `variance` on each axis.
    pub fn uninformed(variance: f64) -> Self {
        Self {
            correction: Vector3::zeros(),
            variance: Vector3::repeat(variance),
            uncorrected_sq_error: 3.0 * variance,
        }
    }
}

impl OdometryMode {
    /// (a) gpodo's default: the mean corrects, the predictive variance is
    /// the covariance.
    pub const CORRECTED: Self = Self {
        correct_mean: true,
        covariance: CovarianceSource::PredictiveVariance,
    };

    /// (b) the authors': uncorrected, the covariance from a |residual|
    /// regressor.
    pub const AUTHORS: Self = Self {
        correct_mean: false,
        covariance: CovarianceSource::AbsoluteResidual,
    };

    /// Whether a drift budget counts the predicted mean² (the uncorrected
    /// odometry's error) rather than the variance alone.
    pub fn budget_counts_mean(&self) -> bool {
        !self.correct_mean
    }

    /// A short description for reports.
    pub fn label(&self) -> String {
        let mean = if self.correct_mean {
            "corrected"
        } else {
            "uncorrected"
        };
        let covariance = match self.covariance {
            CovarianceSource::PredictiveVariance => "predictive variance",
            CovarianceSource::AbsoluteResidual => "|residual|² covariance",
            CovarianceSource::AbsoluteResidualAsVariance => "|residual| as variance",
        };
        format!("{mean}, {covariance}")
    }

    /// The odometry of one window under this mode.
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] when the covariance comes from a
    /// |residual| regressor and `p` carries none.
    pub fn window(&self, p: &ResidualPrediction) -> Result<WindowOdometry, FrontendError> {
        let correction = if self.correct_mean {
            p.mean
        } else {
            Vector3::zeros()
        };
        if !self.covariance.is_absolute() {
            return Ok(WindowOdometry {
                correction,
                variance: p.variance,
                uncorrected_sq_error: p.expected_sq_error(),
            });
        }
        let a = p.absolute.ok_or_else(|| FrontendError::InvalidSpec {
            selector: "odometry".into(),
            field: "covariance".into(),
            expected: "a |residual| regressor's predictions for the covariance".into(),
        })?;
        let magnitude = a.mean.abs();
        let variance = match self.covariance {
            CovarianceSource::AbsoluteResidualAsVariance => magnitude,
            CovarianceSource::PredictiveVariance | CovarianceSource::AbsoluteResidual => {
                magnitude.component_mul(&magnitude)
            }
        };
        Ok(WindowOdometry {
            correction,
            variance,
            uncorrected_sq_error: magnitude.norm_squared() + a.variance.sum(),
        })
    }

    /// What a policy reading the residual sees: the regressor that sets the
    /// covariance (the |residual| regressor's prediction when there is
    /// one).
    pub fn policy_view(&self, p: &ResidualPrediction) -> ResidualPrediction {
        match (self.covariance.is_absolute(), p.absolute) {
            (true, Some(a)) => ResidualPrediction {
                mean: a.mean,
                variance: a.variance,
                absolute: None,
            },
            _ => ResidualPrediction {
                absolute: None,
                ..*p
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prediction::AbsolutePrediction;

    fn signed() -> ResidualPrediction {
        ResidualPrediction {
            mean: Vector3::new(0.003, -0.004, 0.0),
            variance: Vector3::new(1e-6, 2e-6, 3e-6),
            absolute: Some(AbsolutePrediction {
                mean: Vector3::new(0.005, 0.002, 0.001),
                variance: Vector3::new(4e-6, 0.0, 1e-6),
            }),
        }
    }

    #[test]
    fn the_three_modes_follow_the_table() {
        let p = signed();
        // (a)
        let a = OdometryMode::CORRECTED.window(&p).unwrap();
        assert_eq!(a.correction, p.mean);
        assert_eq!(a.variance, p.variance);
        // A corrected odometry's budget counts the variance.
        assert!(!OdometryMode::CORRECTED.budget_counts_mean());
        assert!((a.variance.sum() - 6e-6).abs() < 1e-18);
        // (b): σ = â, nothing corrected, the budget counts ‖â‖² + Σ σ²_â.
        let b = OdometryMode::AUTHORS.window(&p).unwrap();
        assert_eq!(b.correction, Vector3::zeros());
        assert_eq!(b.variance, Vector3::new(25e-6, 4e-6, 1e-6));
        let second_moment = 25e-6 + 4e-6 + 1e-6 + 5e-6;
        assert!(OdometryMode::AUTHORS.budget_counts_mean());
        assert!((b.uncorrected_sq_error - second_moment).abs() < 1e-18);
        // (c): corrected, â² covariance, the budget counts Σ â².
        let both = OdometryMode {
            correct_mean: true,
            covariance: CovarianceSource::AbsoluteResidual,
        };
        let c = both.window(&p).unwrap();
        assert_eq!(c.correction, p.mean);
        assert!(!both.budget_counts_mean());
        assert!((c.variance.sum() - 30e-6).abs() < 1e-18);
        // The literal reading: â itself is the variance.
        let literal = OdometryMode {
            correct_mean: false,
            covariance: CovarianceSource::AbsoluteResidualAsVariance,
        };
        assert_eq!(
            literal.window(&p).unwrap().variance,
            Vector3::new(0.005, 0.002, 0.001)
        );
    }

    #[test]
    fn policies_read_the_regressor_that_sets_the_covariance() {
        let p = signed();
        assert_eq!(OdometryMode::CORRECTED.policy_view(&p).mean, p.mean);
        let view = OdometryMode::AUTHORS.policy_view(&p);
        assert_eq!(view.mean, Vector3::new(0.005, 0.002, 0.001));
        assert_eq!(view.variance, Vector3::new(4e-6, 0.0, 1e-6));
    }

    #[test]
    fn an_absolute_covariance_without_a_regressor_is_an_error() {
        let p = ResidualPrediction::uninformed(1e-6);
        let err = OdometryMode::AUTHORS.window(&p).unwrap_err();
        assert!(err.to_string().contains("|residual|"), "{err}");
    }
}

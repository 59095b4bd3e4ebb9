//! Where a gating policy's knowledge of the wheels comes from: a
//! [`ResidualSource`] hands the front end a predicted residual (mean and
//! variance of the body-velocity error of the parametric odometry, §IV-C)
//! each time a regressor window completes, and may learn online from
//! visual-odometry targets (§VI).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::FrontendError;
use crate::traverse::TraverseWindow;

/// A predicted residual: the expected error of the parametric odometry's
/// body velocity and its variance, per body axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ResidualPrediction {
    /// Mean residual (m/s, body frame): added to the odometry's velocity.
    pub mean: Vector3<f64>,
    /// Variance of the residual ((m/s)², body frame): the odometry's
    /// velocity uncertainty.
    pub variance: Vector3<f64>,
    /// A regressor of |residual|'s prediction for the same window, when the
    /// scheme's odometry takes its covariance from one
    /// ([`crate::odometry_mode`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub absolute: Option<AbsolutePrediction>,
}

/// A regressor of |residual| (trained on the absolute residual, as the
/// authors' GP was): its prediction per body axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AbsolutePrediction {
    /// Predicted |residual| (m/s).
    pub mean: Vector3<f64>,
    /// Its predictive variance ((m/s)²).
    pub variance: Vector3<f64>,
}

impl ResidualPrediction {
    /// Zero mean with the same variance `variance` on each axis.
    pub fn uninformed(variance: f64) -> Self {
        Self {
            mean: Vector3::zeros(),
            variance: Vector3::repeat(variance),
            absolute: None,
        }
    }

    /// `‖mean‖² + Σ variance`: the expected squared velocity error (m²/s²).
    pub fn expected_sq_error(&self) -> f64 {
        self.mean.norm_squared() + self.variance.sum()
    }
}

/// Supplies residual predictions to a front-end run, window by window, and
/// optionally learns from visual odometry.
pub trait ResidualSource: Send {
    /// A short name for reports.
    fn name(&self) -> &str;

    /// Window `index` has just completed: the prediction the rover uses
    /// from `window.end_secs` on (made from that window's inputs).
    ///
    /// # Errors
    /// [`FrontendError::Regressor`] when the regressor fails.
    fn on_window(
        &mut self,
        index: usize,
        window: &TraverseWindow,
    ) -> Result<ResidualPrediction, FrontendError>;

    /// Whether [`ResidualSource::on_target`] learns.
    fn learns_online(&self) -> bool {
        false
    }

    /// A residual target measured by visual odometry: the mean body-velocity
    /// residual (m/s) over an interval ending at `time_secs` whose mean
    /// regressor inputs were `inputs`. Sources that do not learn ignore it.
    ///
    /// # Errors
    /// [`FrontendError::Regressor`] when the update fails.
    fn on_target(
        &mut self,
        inputs: &[f64],
        target: &Vector3<f64>,
        time_secs: f64,
    ) -> Result<(), FrontendError> {
        let _ = (inputs, target, time_secs);
        Ok(())
    }
}

/// Predictions computed beforehand, one per window (a regressor trained
/// offline, predicting on the traverse's windows in one batch).
#[derive(Debug, Clone, PartialEq)]
pub struct Precomputed {
    name: String,
    predictions: Vec<ResidualPrediction>,
}

impl Precomputed {
    /// One prediction per window of the traverse, in window order.
    pub fn new(name: impl Into<String>, predictions: Vec<ResidualPrediction>) -> Self {
        Self {
            name: name.into(),
            predictions,
        }
    }

    /// The predictions.
    pub fn predictions(&self) -> &[ResidualPrediction] {
        &self.predictions
    }
}

impl ResidualSource for Precomputed {
    fn name(&self) -> &str {
        &self.name
    }

    fn on_window(
        &mut self,
        index: usize,
        _window: &TraverseWindow,
    ) -> Result<ResidualPrediction, FrontendError> {
        self.predictions
            .get(index)
            .copied()
            .ok_or_else(|| FrontendError::InvalidTraverse {
                traverse: self.name.clone(),
                detail: format!(
                    "no precomputed prediction for window {index} ({} given)",
                    self.predictions.len()
                ),
            })
    }
}

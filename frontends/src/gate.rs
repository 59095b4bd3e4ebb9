//! What a frame selector reads, kept as the rover drives: the odometry
//! since the last processed frame and the residual prediction in force.
//! The offline front end ([`crate::run`]) and the live frame gate keep it
//! with this one type, so a policy sees the same [`FrameContext`] in both.
//!
//! Per stretch driven, [`GateState::drive`] integrates the motion model's
//! twist under the prediction in force; each new prediction (a regressor
//! window completed) starts a new block of fully correlated drift
//! ([`GateState::predict`]); a processed frame ends the interval
//! ([`GateState::processed`]), which the front end turns into its odometry
//! edge and the online learner's target interval.

use gpodo_traits::{BodyTwist, FrameContext};

use crate::FrontendError;
use crate::odometry::{OdometryIntegrator, OdometryInterval, OdometryNoise};
use crate::odometry_mode::{OdometryMode, WindowOdometry};
use crate::prediction::ResidualPrediction;

/// The odometry since the last processed frame and the prediction in
/// force.
#[derive(Debug, Clone)]
pub struct GateState {
    mode: OdometryMode,
    integrator: OdometryIntegrator,
    prediction: ResidualPrediction,
    window: WindowOdometry,
    epoch: usize,
    last_processed_secs: Option<f64>,
}

impl GateState {
    /// Before anything is driven or predicted: the odometry's `noise`,
    /// how the odometry uses predictions (`mode`), and the residual
    /// variance per axis of a model that knows nothing
    /// ([`crate::FrontendParams::initial_residual_variance`]).
    pub fn new(noise: OdometryNoise, mode: OdometryMode, initial_variance: f64) -> Self {
        Self {
            mode,
            integrator: OdometryIntegrator::new(noise),
            prediction: ResidualPrediction::uninformed(initial_variance),
            window: WindowOdometry::uninformed(initial_variance),
            epoch: 0,
            last_processed_secs: None,
        }
    }

    /// Drives `dt_secs` with the motion model's `twist` under the
    /// prediction in force, with the regressor inputs of the stretch's
    /// window, if any.
    pub fn drive(&mut self, twist: &BodyTwist, dt_secs: f64, inputs: Option<&[f64]>) {
        self.integrator
            .advance(twist, dt_secs, self.epoch, &self.window, inputs);
    }

    /// A new prediction is in force from now.
    ///
    /// # Errors
    /// What [`OdometryMode::window`] reports for a prediction the mode
    /// cannot use.
    pub fn predict(&mut self, prediction: ResidualPrediction) -> Result<(), FrontendError> {
        self.window = self.mode.window(&prediction)?;
        self.prediction = prediction;
        self.epoch += 1;
        Ok(())
    }

    /// What a selector reads for the frame at `time_secs`.
    pub fn context(&self, time_secs: f64, tracking_lost: bool) -> FrameContext {
        let view = self.mode.policy_view(&self.prediction);
        FrameContext {
            time_secs,
            last_processed_secs: self.last_processed_secs,
            distance_since_processed_m: self.integrator.distance_m(),
            rotation_since_processed_rad: self.integrator.rotation_rad(),
            residual_mean: view.mean.iter().copied().collect(),
            residual_variance: view.variance.iter().copied().collect(),
            drift_since_processed: self.integrator.drift_m2(),
            drift_variance_since_processed: self.integrator.drift_variance_m2(),
            tracking_lost,
        }
    }

    /// The frame at `time_secs` is processed: the odometry since the last
    /// one, and a new interval from here.
    pub fn processed(&mut self, time_secs: f64) -> OdometryInterval {
        self.last_processed_secs = Some(time_secs);
        self.integrator.take()
    }

    /// The prediction in force.
    pub fn prediction(&self) -> &ResidualPrediction {
        &self.prediction
    }

    /// What the prediction in force does to the odometry.
    pub fn window(&self) -> &WindowOdometry {
        &self.window
    }

    /// The number of the prediction in force (0 before the first).
    pub fn epoch(&self) -> usize {
        self.epoch
    }

    /// The odometry since the last processed frame.
    pub fn since_processed(&self) -> &OdometryIntegrator {
        &self.integrator
    }

    /// The time of the last processed frame (s).
    pub fn last_processed_secs(&self) -> Option<f64> {
        self.last_processed_secs
    }
}

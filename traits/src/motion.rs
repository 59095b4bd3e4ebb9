//! The parametric motion model interface (paper §III, `g` in eq. 11–12).

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::{Error, ProprioceptiveSample};

/// A body-frame velocity (twist): linear and angular velocity of the body
/// frame, expressed in the body frame.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct BodyTwist {
    /// Linear velocity (m/s).
    pub linear_mps: Vector3<f64>,
    /// Angular velocity (rad/s).
    pub angular_radps: Vector3<f64>,
}

impl BodyTwist {
    /// The pose change after moving with this constant twist for `dt_secs`:
    /// `prev_from_next` such that `world_from_next = world_from_prev * prev_from_next`.
    ///
    /// Rotation and translation are integrated separately (first order in the
    /// translation), which is what wheel odometry does at its sample rate.
    pub fn pose_delta(&self, dt_secs: f64) -> Isometry3<f64> {
        let rotation = UnitQuaternion::from_scaled_axis(self.angular_radps * dt_secs);
        let translation = Translation3::from(self.linear_mps * dt_secs);
        Isometry3::from_parts(translation, rotation)
    }
}

/// What a motion model estimates from one sample.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct MotionEstimate {
    /// The body twist.
    pub twist: BodyTwist,
    /// Per-contact slip velocity estimates (m/s, in each contact frame:
    /// longitudinal, lateral), empty if the model does not estimate slip.
    pub contact_slip_mps: Vec<[f64; 2]>,
    /// Weighted residual `eᵀ C e` of the model's fit (0 for models that do
    /// not solve an overdetermined system).
    pub weighted_residual: f64,
}

/// A parametric motion model: sensed quantities → body velocity.
///
/// Implementations are stateless (`&self`), so one instance serves every
/// sample of every run, in parallel.
///
/// ```
/// use gpodo_traits::{BodyTwist, Error, MotionEstimate, MotionModel, ProprioceptiveSample};
///
/// /// Reads the forward speed off the first wheel (radius 0.1 m).
/// struct OneWheel;
///
/// impl MotionModel for OneWheel {
///     fn name(&self) -> &str { "one_wheel" }
///     fn estimate(&self, s: &ProprioceptiveSample, _dt: f64) -> Result<MotionEstimate, Error> {
///         let wheel = s.wheels.first().ok_or(Error::DimensionMismatch {
///             what: "wheels".into(), expected: 1, found: 0,
///         })?;
///         let mut twist = BodyTwist::default();
///         twist.linear_mps.x = 0.1 * wheel.rate_radps;
///         twist.angular_radps = s.gyro_radps().unwrap_or_default();
///         Ok(MotionEstimate { twist, ..Default::default() })
///     }
/// }
///
/// let mut sample = ProprioceptiveSample::default();
/// sample.wheels.push(gpodo_traits::JointState { position_rad: 0.0, rate_radps: 2.0 });
/// let model: Box<dyn MotionModel> = Box::new(OneWheel);
/// assert_eq!(model.estimate(&sample, 0.08).unwrap().twist.linear_mps.x, 0.2);
/// ```
pub trait MotionModel: Send + Sync {
    /// A short name for reports (e.g. `"exoter_wjm"`).
    fn name(&self) -> &str;

    /// Estimates the body twist over the interval that starts at `sample`
    /// and lasts `dt_secs`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] when the sample does not match the
    /// model's rover, [`Error::Numerical`] when the solve fails.
    fn estimate(
        &self,
        sample: &ProprioceptiveSample,
        dt_secs: f64,
    ) -> Result<MotionEstimate, Error>;
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn pose_delta_of_a_pure_translation_is_velocity_times_time() {
        let twist = BodyTwist {
            linear_mps: Vector3::new(0.05, -0.01, 0.0),
            angular_radps: Vector3::zeros(),
        };
        let delta = twist.pose_delta(2.0);
        assert_relative_eq!(delta.translation.vector, Vector3::new(0.1, -0.02, 0.0));
        assert_relative_eq!(delta.rotation.angle(), 0.0);
    }

    #[test]
    fn pose_delta_rotation_is_the_exponential_of_the_rate() {
        let twist = BodyTwist {
            linear_mps: Vector3::zeros(),
            angular_radps: Vector3::new(0.0, 0.0, 0.5),
        };
        let delta = twist.pose_delta(0.2);
        assert_relative_eq!(delta.rotation.euler_angles().2, 0.1, epsilon = 1e-15);
    }
}

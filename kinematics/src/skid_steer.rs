//! An ideal skid-steer (differential-drive) model: the second implementation
//! of [`MotionModel`], to show that the trait is not tied to one chassis.
//!
//! Forward speed is the mean rolling speed of the left and right sides, yaw
//! rate their difference over the track width (or the gyro's, by default);
//! steering and bogie joints are ignored and lateral and vertical velocity
//! are zero.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use gpodo_traits::{BodyTwist, Error, MotionEstimate, MotionModel, ProprioceptiveSample};

use crate::{KinematicsError, RoverDescription};

/// Where the skid-steer model takes its angular velocity from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum YawSource {
    /// The IMU's gyros (all three axes).
    #[default]
    Gyro,
    /// The wheel speed difference (yaw only).
    Wheels,
}

/// The ideal differential-drive model.
#[derive(Debug, Clone)]
pub struct SkidSteerModel {
    wheel_radius_m: f64,
    track_width_m: f64,
    left: Vec<usize>,
    right: Vec<usize>,
    n_wheels: usize,
    yaw_source: YawSource,
}

impl SkidSteerModel {
    /// Builds the model from a description: wheels with a positive body y
    /// are on the left side, the others on the right; the track is the
    /// distance between the sides' mean y.
    ///
    /// # Errors
    /// [`KinematicsError::InvalidDescription`] if a side has no wheel.
    pub fn from_description(
        description: &RoverDescription,
        yaw_source: YawSource,
    ) -> Result<Self, KinematicsError> {
        description.validate()?;
        let (left, right): (Vec<usize>, Vec<usize>) =
            (0..description.wheels.len()).partition(|&i| description.wheels[i].center_m[1] > 0.0);
        if left.is_empty() || right.is_empty() {
            return Err(KinematicsError::InvalidDescription {
                field: "wheels".into(),
                expected: "wheels on both sides (positive and negative y) for skid steering".into(),
            });
        }
        let mean_y = |idx: &[usize]| {
            idx.iter()
                .map(|&i| description.wheels[i].center_m[1])
                .sum::<f64>()
                / idx.len() as f64
        };
        Ok(Self {
            wheel_radius_m: description.wheel_radius_m,
            track_width_m: mean_y(&left) - mean_y(&right),
            left,
            right,
            n_wheels: description.wheels.len(),
            yaw_source,
        })
    }

    /// Distance between the left and right wheel lines (m).
    pub fn track_width_m(&self) -> f64 {
        self.track_width_m
    }

    fn side_speed(&self, s: &ProprioceptiveSample, side: &[usize]) -> f64 {
        self.wheel_radius_m * side.iter().map(|&i| s.wheels[i].rate_radps).sum::<f64>()
            / side.len() as f64
    }
}

impl MotionModel for SkidSteerModel {
    fn name(&self) -> &str {
        "skid_steer"
    }

    fn estimate(&self, s: &ProprioceptiveSample, _dt_secs: f64) -> Result<MotionEstimate, Error> {
        if s.wheels.len() != self.n_wheels {
            return Err(Error::DimensionMismatch {
                what: "wheels".into(),
                expected: self.n_wheels,
                found: s.wheels.len(),
            });
        }
        let (v_left, v_right) = (
            self.side_speed(s, &self.left),
            self.side_speed(s, &self.right),
        );
        let angular_radps = match self.yaw_source {
            YawSource::Gyro => s.gyro_for("yaw: gyro", "yaw: wheels")?,
            YawSource::Wheels => Vector3::new(0.0, 0.0, (v_right - v_left) / self.track_width_m),
        };
        Ok(MotionEstimate {
            twist: BodyTwist {
                linear_mps: Vector3::new(0.5 * (v_left + v_right), 0.0, 0.0),
                angular_radps,
            },
            ..Default::default()
        })
    }
}

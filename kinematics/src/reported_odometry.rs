//! The robot's own odometry as the parametric model `g`: for a robot whose
//! kinematics gpodo does not model, or whose joint encoders were not
//! recorded (the shared Husky recording has only its drive controller's
//! `nav_msgs/Odometry`), the residual is learned against what the robot
//! itself reported.

use serde::{Deserialize, Serialize};

use gpodo_traits::{BodyTwist, Error, MotionEstimate, MotionModel, ProprioceptiveSample};

/// Where the reported-odometry model takes its angular velocity from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AngularSource {
    /// The odometry's own angular velocity.
    #[default]
    Odometry,
    /// The IMU's gyros (what the weighted Jacobian model uses too).
    Gyro,
}

/// The body twist the robot reported ([`ProprioceptiveSample::odometry`]),
/// taken as it is.
#[derive(Debug, Clone, Copy, Default)]
pub struct ReportedOdometryModel {
    angular: AngularSource,
}

impl ReportedOdometryModel {
    /// The model, with the angular velocity from `angular`.
    pub fn new(angular: AngularSource) -> Self {
        Self { angular }
    }
}

impl MotionModel for ReportedOdometryModel {
    fn name(&self) -> &str {
        "reported_odometry"
    }

    fn estimate(&self, s: &ProprioceptiveSample, _dt_secs: f64) -> Result<MotionEstimate, Error> {
        let Some(reported) = s.odometry else {
            return Err(Error::InvalidInput(format!(
                "the sample at {} s has no odometry: the `reported_odometry` model needs the \
                 robot's own odometry (`odom_*` columns of a rover log, or an `odometry` topic \
                 of a bag)",
                s.time_secs
            )));
        };
        let angular_radps = match self.angular {
            AngularSource::Odometry => reported.angular_radps,
            AngularSource::Gyro => s.gyro_for("angular: gyro", "angular: odometry")?,
        };
        Ok(MotionEstimate {
            twist: BodyTwist {
                linear_mps: reported.linear_mps,
                angular_radps,
            },
            ..Default::default()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn sample() -> ProprioceptiveSample {
        let mut s = ProprioceptiveSample {
            odometry: Some(BodyTwist {
                linear_mps: Vector3::new(0.8, 0.0, 0.0),
                angular_radps: Vector3::new(0.0, 0.0, 0.3),
            }),
            ..Default::default()
        };
        s.imu = Some(gpodo_traits::ImuSample {
            gyro_radps: Vector3::new(0.01, 0.02, 0.25),
            ..Default::default()
        });
        s
    }

    #[test]
    fn the_reported_twist_is_the_estimate() {
        let e = ReportedOdometryModel::default()
            .estimate(&sample(), 0.1)
            .unwrap();
        assert_eq!(e.twist, sample().odometry.unwrap());
    }

    #[test]
    fn the_angular_rate_can_come_from_the_gyros() {
        let e = ReportedOdometryModel::new(AngularSource::Gyro)
            .estimate(&sample(), 0.1)
            .unwrap();
        assert_eq!(e.twist.linear_mps, Vector3::new(0.8, 0.0, 0.0));
        assert_eq!(e.twist.angular_radps, Vector3::new(0.01, 0.02, 0.25));
        let mut no_imu = sample();
        no_imu.imu = None;
        let e = ReportedOdometryModel::new(AngularSource::Gyro)
            .estimate(&no_imu, 0.1)
            .unwrap_err();
        assert!(
            e.to_string()
                .contains("no IMU: `angular: gyro` needs its gyros; use `angular: odometry`"),
            "{e}"
        );
    }

    #[test]
    fn a_sample_without_odometry_is_refused_with_the_reason() {
        let mut s = sample();
        s.odometry = None;
        s.time_secs = 4.5;
        let e = ReportedOdometryModel::default()
            .estimate(&s, 0.1)
            .unwrap_err();
        assert!(e.to_string().contains("at 4.5 s has no odometry"), "{e}");
    }
}

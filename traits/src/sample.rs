//! Proprioceptive sensor samples: what a rover senses about itself at one
//! instant (joint encoders, potentiometers, IMU).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Position and rate of one joint.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct JointState {
    /// Joint angle (rad).
    pub position_rad: f64,
    /// Joint rate (rad/s), the mean over the sample interval.
    pub rate_radps: f64,
}

/// One IMU reading, expressed in the body frame (x forward, y left, z up).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ImuSample {
    /// Angular rate from the gyroscopes (rad/s).
    pub gyro_radps: Vector3<f64>,
    /// Specific force from the accelerometers (m/s², gravity included:
    /// a rover at rest on flat ground reads `+9.81` on z).
    pub accel_mps2: Vector3<f64>,
    /// Roll from the attitude filter (rad, rotation about body x).
    pub roll_rad: f64,
    /// Pitch from the attitude filter (rad, rotation about body y; positive
    /// pitch points the nose down, as with any right-handed z-up frame).
    pub pitch_rad: f64,
}

/// Everything a rover senses about itself at one time step.
///
/// Joint vectors follow the order of the rover description that produced
/// them (for the ExoTeR-like rover: wheels `fl, fr, ml, mr, rl, rr`, steering
/// `fl, fr, rl, rr`, bogies `left, right, rear`). A motion model checks the
/// lengths it needs and reports a [`crate::Error::DimensionMismatch`].
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ProprioceptiveSample {
    /// Time stamp (s).
    pub time_secs: f64,
    /// Wheel (rolling) joints.
    pub wheels: Vec<JointState>,
    /// Steering joints.
    pub steering: Vec<JointState>,
    /// Passive bogie joints.
    pub bogies: Vec<JointState>,
    /// Inertial measurement; `None` for a robot without an IMU.
    #[serde(default)]
    pub imu: Option<ImuSample>,
    /// Roll and pitch (rad) from off board, for a robot without an IMU:
    /// the ground truth's, when an experiment opts in. Motion models may
    /// use them for the contact geometry; they are never a regressor
    /// input, since the robot does not sense them.
    #[serde(default)]
    pub attitude_rad: Option<[f64; 2]>,
    /// Wheel–terrain contact angles (rad), one per wheel, when something
    /// measured or estimated them (a simulator does; a real rover usually
    /// does not, and models then assume 0).
    pub contact_angles_rad: Option<Vec<f64>>,
    /// The robot's own odometry over the interval that starts here, as its
    /// drive controller reports it (e.g. a ROS `nav_msgs/Odometry` twist in
    /// the body frame), for robots whose kinematics gpodo does not model;
    /// `None` when the log has none.
    #[serde(default)]
    pub odometry: Option<crate::BodyTwist>,
}

impl ProprioceptiveSample {
    /// Roll and pitch (rad) for the contact geometry: the IMU's, else the
    /// off-board [`Self::attitude_rad`], else level (0, 0).
    pub fn roll_pitch_rad(&self) -> (f64, f64) {
        match (&self.imu, self.attitude_rad) {
            (Some(imu), _) => (imu.roll_rad, imu.pitch_rad),
            (None, Some([roll, pitch])) => (roll, pitch),
            (None, None) => (0.0, 0.0),
        }
    }

    /// The body angular rate the gyros measured (rad/s), if the robot has
    /// an IMU.
    pub fn gyro_radps(&self) -> Option<Vector3<f64>> {
        self.imu.as_ref().map(|imu| imu.gyro_radps)
    }

    /// The gyros' body angular rate, for a setting that needs it.
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] naming the sample's time, the
    /// `setting` and `instead`, the setting that does without.
    pub fn gyro_for(&self, setting: &str, instead: &str) -> Result<Vector3<f64>, crate::Error> {
        self.gyro_radps().ok_or_else(|| {
            crate::Error::InvalidInput(format!(
                "the sample at {} s has no IMU: `{setting}` needs its gyros; use `{instead}`",
                self.time_secs
            ))
        })
    }
}

//! Which parametric motion model a run uses, as an experiment file's
//! `motion_model:` block (or a saved model's row recipe) says, and the
//! model it builds from its rover description.

use std::path::PathBuf;

use gpodo_traits::MotionModel;
use serde::{Deserialize, Serialize};

use crate::{
    AngularSource, KinematicsError, ReportedOdometryModel, RoverDescription, SkidSteerModel,
    WeightedJacobianConfig, WeightedJacobianModel, YawSource,
};

/// Where a robot without an IMU gets the roll and pitch its motion model
/// uses (the weighted-Jacobian model's normal-force weighting).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AttitudeWithoutImu {
    /// Level ground: roll and pitch 0.
    #[default]
    Level,
    /// The ground truth's roll and pitch: off board, so opt-in, said in the
    /// report, and never a regressor input.
    GroundTruth,
}

/// The parametric motion model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum MotionModelSpec {
    /// The weighted Jacobian model of §III.
    WeightedJacobian {
        /// Rover description YAML (relative to the experiment file);
        /// omitted, the built-in ExoTeR-like rover.
        #[serde(default)]
        rover: Option<PathBuf>,
        /// Model settings.
        #[serde(default)]
        config: WeightedJacobianConfig,
        /// For a robot without an IMU, where the roll and pitch of the
        /// contact geometry come from (default: level ground).
        #[serde(default)]
        attitude_without_imu: AttitudeWithoutImu,
    },
    /// The ideal skid-steer model.
    SkidSteer {
        /// Rover description YAML; omitted, the ExoTeR-like rover.
        #[serde(default)]
        rover: Option<PathBuf>,
        /// Angular rate source.
        #[serde(default)]
        yaw: YawSource,
    },
    /// The robot's own odometry (a log's `odom_*` columns, a bag's
    /// `odometry` topic) as the model, for a robot whose kinematics gpodo
    /// does not model.
    ReportedOdometry {
        /// Rover description YAML, needed only when the logs also hold
        /// wheel joints (for the wheel radius and the joint order).
        #[serde(default)]
        rover: Option<PathBuf>,
        /// Angular rate source (default: the odometry's own).
        #[serde(default)]
        angular: AngularSource,
    },
}

impl Default for MotionModelSpec {
    fn default() -> Self {
        Self::WeightedJacobian {
            rover: None,
            config: WeightedJacobianConfig::default(),
            attitude_without_imu: AttitudeWithoutImu::Level,
        }
    }
}

impl MotionModelSpec {
    /// The rover description it names, if any.
    pub fn rover(&self) -> Option<&PathBuf> {
        match self {
            Self::WeightedJacobian { rover, .. }
            | Self::SkidSteer { rover, .. }
            | Self::ReportedOdometry { rover, .. } => rover.as_ref(),
        }
    }

    /// The same model with its rover description at `path`.
    #[must_use]
    pub fn with_rover(mut self, path: PathBuf) -> Self {
        match &mut self {
            Self::WeightedJacobian { rover, .. }
            | Self::SkidSteer { rover, .. }
            | Self::ReportedOdometry { rover, .. } => *rover = Some(path),
        }
        self
    }

    /// The motion model, and the rover description it was built from (the
    /// built-in ExoTeR-like rover where a kinematic model names none; none
    /// for the reported odometry without one).
    ///
    /// # Errors
    /// [`KinematicsError`] for a rover description that cannot be read or
    /// a model that cannot be built from it.
    pub fn build(
        &self,
    ) -> Result<(Box<dyn MotionModel>, Option<RoverDescription>), KinematicsError> {
        let load = |rover: &Option<PathBuf>| match rover {
            Some(p) => RoverDescription::from_path(p),
            None => Ok(RoverDescription::exoter()),
        };
        Ok(match self {
            Self::WeightedJacobian { rover, config, .. } => {
                let d = load(rover)?;
                (
                    Box::new(WeightedJacobianModel::new(d.clone(), *config)?),
                    Some(d),
                )
            }
            Self::SkidSteer { rover, yaw } => {
                let d = load(rover)?;
                (
                    Box::new(SkidSteerModel::from_description(&d, *yaw)?),
                    Some(d),
                )
            }
            Self::ReportedOdometry { rover, angular } => {
                let d = match rover {
                    Some(p) => Some(RoverDescription::from_path(p)?),
                    None => None,
                };
                (Box::new(ReportedOdometryModel::new(*angular)), d)
            }
        })
    }
}

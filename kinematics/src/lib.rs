//! Parametric 3D odometry (paper §III): the weighted Jacobian motion model
//! of a wheeled rover with passive bogies, and a skid-steer model, both
//! behind [`gpodo_traits::MotionModel`].
//!
//! * [`description`]: rover geometry from YAML (default: ExoTeR-like;
//!   `rovers/` also holds a differential-drive, a Husky-like skid-steer and
//!   a mecanum platform: wheels on bogies or rigidly mounted, ordinary or
//!   mecanum);
//! * [`chain`]: forward kinematics body → bogie → steer → wheel → contact;
//! * [`jacobian`]: the contact Jacobian of eq. (1);
//! * [`loads`]: static normal forces, the weights `C` of eq. (5);
//! * [`weighted_jacobian`]: eq. (2)–(5), weighted least squares;
//! * [`qp`]: the same problem with bounds, as a QP (Clarabel);
//! * [`skid_steer`]: the ideal differential-drive model;
//! * [`reported_odometry`]: the robot's own odometry as the model, for
//!   robots without modelled kinematics;
//! * [`spec`]: which of them a run uses, as configured, and building it.

pub mod chain;
pub mod description;
mod error;
pub mod jacobian;
pub mod loads;
pub mod qp;
pub mod reported_odometry;
pub mod skid_steer;
pub mod spec;
pub mod weighted_jacobian;

pub use description::RoverDescription;
pub use error::KinematicsError;
pub use reported_odometry::{AngularSource, ReportedOdometryModel};
pub use skid_steer::{SkidSteerModel, YawSource};
pub use weighted_jacobian::{
    ContactAngleSource, SolveBounds, WeightedJacobianConfig, WeightedJacobianModel, Weighting,
};

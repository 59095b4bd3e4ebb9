//! gpodo on the robot: a saved residual model queried live.
//!
//! The paper's GP ran on board, trained offline and queried as the rover
//! drove, its prediction fed to SLAM as the odometry's covariance. This
//! crate is that loop without ROS in it:
//!
//! * [`rows`]: the model's input rows made from samples as they arrive,
//!   averaged over the trailing window the model was trained with;
//! * [`pipeline`]: per sample, the rover's motion model, the saved
//!   regressor's prediction, the corrected twist with its covariance, and
//!   the pose integrated from it;
//! * [`feed`]: joint-state and IMU messages made into samples, each joint
//!   state with the IMU reading of its time;
//! * [`diagnostics`]: latency, the last input's age, and warnings;
//! * [`checkpoint`]: the online learner's model written atomically, with
//!   what it must match to be resumed;
//! * [`learner`]: frontends' online learner run live on the gate's VO
//!   targets, resumed from and written to checkpoints; live, on a worker
//!   thread ([`learner_worker`]) the odometry path never waits for;
//! * [`gate`]: the live frame gate in front of any stereo VO, and the
//!   residual targets its poses give an online learner;
//! * `ros2` (with the `ros2` feature): the node on ROS 2 over DDS;
//! * [`replay`]: a recording fed through it, the odometry written to an
//!   MCAP and the rows to a CSV that `gpodo predict` reads.
//!
//! A model is accepted only when its file says how its rows were made
//! (model files of version 3 fitted on logs, bags or the simulator) and
//! this robot gives every column it reads.

pub mod checkpoint;
pub mod covariance;
pub mod diagnostics;
pub mod error;
pub mod feed;
pub mod gate;
pub mod learner;
pub mod learner_worker;
pub mod pipeline;
pub mod replay;
#[cfg(feature = "ros2")]
pub mod ros2;
pub mod rows;

pub use error::NodeError;
pub use pipeline::{LiveModel, LiveOutput, LiveSettings, OdometryMode};
pub use rows::LiveRows;

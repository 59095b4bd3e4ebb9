//! Rover data for gpodo: the simulated ExoTeR-like testbed (the embedded
//! default dataset), loaders for logged rover runs and residual tables, and
//! the residual dataset of the paper's §IV-C built from logs and a motion
//! model; and ROS bags (MCAP and ROS 1) read by their magic bytes
//! ([`bags`]).

pub mod bags;
pub mod camera;
mod error;
pub mod log;
pub mod real_images;
pub mod residuals;
pub mod sim;
pub mod speed_check;
pub mod table;

pub use error::DatasetError;

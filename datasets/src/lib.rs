//! Rover data for gpodo: loaders for logged rover runs and residual tables,
//! the residual dataset of the paper's §IV-C built from logs and a motion
//! model, and ROS bags (MCAP and ROS 1) read by their magic bytes
//! ([`bags`]). The simulated testbed that writes such logs is
//! `gpodo-testbed`.

pub mod bags;
mod error;
pub mod log;
pub mod residuals;
pub mod speed_check;
pub mod table;

pub use error::DatasetError;

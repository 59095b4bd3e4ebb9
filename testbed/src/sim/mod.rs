//! The deterministic simulator of the ExoTeR-like rover in ESA's Planetary Robotics Lab testbed.

pub mod chassis;
pub mod driver;
pub mod manoeuvre;
pub mod noise;
pub mod preset;
pub mod route;
pub mod rover;
pub mod sensors;
pub mod slip;
pub mod soil;
pub mod terrain;

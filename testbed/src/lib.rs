//! The paper's testbed, simulated: a seeded 9 × 9 m Mars-like area with
//! 20° slopes and patches of sand, gravel and compact soil, an ExoTeR-like
//! rover driven over it with slip that depends on soil and slope
//! ([`sim`]), and the rover's stereo camera rendered over the same ground
//! ([`camera`]), whose soils are calibrated against real images of
//! ExoTeR's lab ([`real_images`]).
//!
//! The simulator writes [`gpodo_datasets::log::RoverLog`]s, the same
//! rover logs a recording is imported as, so everything downstream reads
//! simulated and real runs alike.

pub mod camera;
mod error;
pub mod real_images;
pub mod sim;

pub use error::TestbedError;

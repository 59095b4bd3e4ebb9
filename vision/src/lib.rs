//! Image primitives for gpodo's camera: 8-bit grey images ([`GrayImage`]),
//! PNG reading and writing ([`png_io`]), the FAST corner detector as
//! ORB-SLAM and OpenCV run it ([`fast`]), and the statistics a rendered
//! soil is calibrated by ([`stats`]).
//!
//! The crate depends on nothing of gpodo's, so the simulator (which
//! renders and calibrates images) and the front end (which tracks
//! features in them) share one implementation.

mod error;
pub mod fast;
mod image;
pub mod png_io;
pub mod stats;

pub use error::VisionError;
pub use image::{GrayImage, PixelBox};

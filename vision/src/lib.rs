//! Image primitives for gpodo's camera: 8-bit grey images ([`GrayImage`]),
//! PNG reading and writing ([`png_io`]), the FAST corner detector as
//! ORB-SLAM and OpenCV run it ([`fast`]), scale pyramids and blur
//! ([`pyramid`]), ORB features as ORB-SLAM2 extracts them ([`orb`]),
//! their Hamming distances ([`hamming`]) and matches along a rectified
//! pair's rows ([`stereo`]), and the statistics a rendered soil is
//! calibrated by ([`stats`]).
//!
//! The crate depends on nothing of gpodo's, so the simulator (which
//! renders and calibrates images) and the front end (which tracks
//! features in them) share one implementation.

mod brief;
mod error;
pub mod fast;
pub mod hamming;
mod image;
pub mod orb;
pub mod png_io;
pub mod pyramid;
pub mod stats;
pub mod stereo;

pub use error::VisionError;
pub use image::{GrayImage, PixelBox};

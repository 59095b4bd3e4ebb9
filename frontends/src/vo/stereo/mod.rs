//! A stereo visual odometry on images: ORB features matched along the
//! pair's rows ([`gpodo_vision::stereo`]), map points from disparity,
//! PnP with RANSAC from a minimal solver ([`p3p`]) and a robust
//! motion-only refinement ([`pose`]).

pub mod bundle;
pub mod frames;
mod grid;
pub mod p3p;
pub mod pose;
pub mod tracker;

pub use frames::{FrameFeatures, StereoFrames};
pub use tracker::{LocalMapPlacement, OverlapDenominator, StereoVo, StereoVoParams};

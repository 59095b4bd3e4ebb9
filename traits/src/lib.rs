//! The interfaces of gpodo and the data types that flow between its crates.
//!
//! The pipeline of the paper (Hidalgo-Carrió et al., "Gaussian Process
//! Estimation of Odometry Errors for Localization and Mapping") has three
//! exchangeable parts, each a trait here:
//!
//! * [`MotionModel`]: sensed proprioceptive quantities → body velocity
//!   (the parametric model `g(s(k), u̇(k))` of eq. 11–12, §III);
//! * [`ResidualRegressor`]: learns the residual `y_k = s(k+1) − s(k) − g(·)`
//!   (eq. 12, §IV-C) and predicts its mean and variance;
//! * [`FrameSelector`]: decides whether a camera frame is processed (§V-B).
//!
//! All three are object safe, so an experiment configuration chooses the
//! implementations at run time (`Box<dyn MotionModel>` and so on). This crate
//! depends on nothing else of gpodo's but `gpodo-vision`, the leaf crate of
//! image primitives, for the [`gpodo_vision::GrayImage`] a frame source
//! gives.
//!
//! Beside the traits: [`SampleMatrix`] (rows of samples), [`ResidualDataset`]
//! and [`Standardizer`], the one z-scoring of inputs and targets every crate
//! uses, [`CameraParams`], the one camera that the rendered stereo pair
//! and the front end's tracker share, and [`StereoFrameSource`], the seam
//! through which the rendered or recorded images reach the stereo VO.

pub mod camera;
mod error;
mod frames;
mod matrix;
mod motion;
mod regressor;
mod sample;
mod selector;
mod standardize;

pub use camera::{CameraParams, InvalidCameraField};
pub use error::Error;
pub use frames::{FrameRef, StereoFrameSource};
pub use matrix::SampleMatrix;
pub use motion::{BodyTwist, MotionEstimate, MotionModel};
pub use regressor::{
    FitProgress, FitReport, Predictions, ResidualDataset, ResidualRegressor, StartRecord,
};
pub use sample::{ImuSample, JointState, ProprioceptiveSample};
pub use selector::{FrameContext, FrameDecision, FrameSelector};
pub use standardize::{MIN_STD, Standardizer};

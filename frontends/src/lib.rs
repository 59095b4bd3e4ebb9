//! The visual front end of gpodo (paper §V-B and §VI): which camera frames
//! to process, what visual odometry makes of them, and how wheel and
//! visual odometry are fused.
//!
//! * [`FrameSelector`](gpodo_traits::FrameSelector) policies: the paper's
//!   fixed-rate baselines ([`fixed_rate`]) and the residual-gated ones
//!   ([`gating`]);
//! * [`vo`]: visual odometry behind one interface, simulated or replayed;
//! * [`backend`]: the factrs pose graph;
//! * [`traverse`], [`prediction`], [`odometry`]: what a run reads;
//! * [`tum`]: trajectories in the TUM format;
//! * [`spec::SelectorSpec`]: the closed set of selector kinds an experiment
//!   may name.

pub mod backend;
mod error;
pub mod fixed_rate;
pub mod odometry;
pub mod prediction;
pub mod spec;
pub mod traverse;
pub mod tum;
pub mod vo;

pub use error::FrontendError;
pub use fixed_rate::FixedRate;
pub use spec::SelectorSpec;

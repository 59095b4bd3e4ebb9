//! The visual front end of gpodo (paper §V-B and §VI): which camera frames
//! to process, what visual odometry makes of them, and how wheel and
//! visual odometry are fused.
//!
//! * [`FrameSelector`](gpodo_traits::FrameSelector) policies: the paper's
//!   fixed-rate baselines ([`fixed_rate`]) and the residual-gated ones
//!   ([`gating`]);
//! * [`vo`]: visual odometry behind one interface, simulated or replayed;
//! * [`run::run_frontend`]: one run of a policy over a traverse — odometry,
//!   tracking, keyframes, loop closing, relocalisation, online learning,
//!   the optimised trajectory and Table II's metrics ([`metrics`]), with
//!   the measures a rover team reads ([`rover_measures`]);
//! * [`online`]: regressors learning from VO targets (§VI), formed by
//!   [`vo_target`] for the offline schemes and the live node alike;
//! * [`gate`]: what a selector reads, kept alike offline and live;
//! * [`backend`]: the factrs pose graph;
//! * [`traverse`], [`prediction`], [`odometry`]: what a run reads;
//!   [`odometry_mode`]: how a scheme's odometry uses the predictions;
//! * [`tum`]: trajectories in the TUM format;
//! * [`spec::SelectorSpec`]: the closed set of selector kinds an experiment
//!   may name.

pub mod backend;
mod error;
pub mod fixed_rate;
pub mod gate;
pub mod gating;
pub mod hindsight;
pub mod metrics;
pub mod odometry;
pub mod odometry_mode;
pub mod online;
pub mod oracle;
pub mod params;
pub mod prediction;
pub mod rover_measures;
pub mod run;
pub mod scheme;
pub mod spec;
pub mod traverse;
pub mod tum;
pub mod vo;
pub mod vo_target;

pub use error::FrontendError;
pub use fixed_rate::FixedRate;
pub use params::FrontendParams;
pub use run::{FrontendRun, run_frontend};
pub use spec::SelectorSpec;

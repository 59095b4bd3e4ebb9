//! Visual front-end policies (paper §V-B): which camera frames to process.
//!
//! Implemented here: [`fixed_rate::FixedRate`], the paper's fixed-rate
//! baselines (ORB-SLAM at 2.5 fps and 0.5 fps), and [`spec::SelectorSpec`],
//! the closed set of selector kinds an experiment may name. The GP-gated
//! policies, the simulated visual odometry and the pose-graph back-end join
//! this crate as `gating/`, `vo/` and `backend/` modules.

mod error;
pub mod fixed_rate;
pub mod spec;

pub use error::FrontendError;
pub use fixed_rate::FixedRate;
pub use spec::SelectorSpec;

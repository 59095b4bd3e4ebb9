//! Residual regressors behind [`gpodo_traits::ResidualRegressor`] (paper §IV),
//! their YAML specifications, and the metrics they are judged by.
//!
//! Implemented here:
//! * [`zero::ZeroResidual`]: "parametric model only", the baseline row of
//!   every table: predicts a zero residual with a fixed (or training) variance;
//! * [`metrics`]: RMSE and MAE per output (Table I), negative log predictive
//!   density and 95 % interval coverage;
//! * [`spec::RegressorSpec`]: the closed set of regressor kinds a YAML
//!   experiment may name, validated when the config is read.
//!
//! The exact GP with its kernels (§IV-A, §V-A), the sparse GP and the
//! incremental local Gaussian regression (§VI) join the same spec enum as
//! `kernels/`, `exact_gp/`, `sparse_gp/` and `ilgr/` modules.

pub mod dense;
mod error;
pub mod exact_gp;
pub mod hyperopt;
pub mod kernels;
pub mod metrics;
pub mod scaling;
pub mod sparse_gp;
pub mod spec;
pub mod zero;

pub use error::RegressorError;
pub use exact_gp::{ExactGp, ExactGpParams};
pub use kernels::{Kernel, KernelExpr};
pub use sparse_gp::{SparseGp, SparseGpParams};
pub use spec::RegressorSpec;
pub use zero::ZeroResidual;

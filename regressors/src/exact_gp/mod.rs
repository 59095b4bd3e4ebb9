//! The exact Gaussian process (paper §IV-A, eq. 7–9): Cholesky with faer
//! ([`cholesky`]), the log marginal likelihood and its gradient
//! ([`likelihood`]), hyperparameter learning with argmin ([`optimize`]), the
//! posterior ([`posterior`]) and the regressor behind the trait ([`model`]).

pub mod choice;
pub mod cholesky;
pub mod iterative;
pub mod likelihood;
pub mod model;
pub mod optimize;
pub mod params;
pub mod posterior;

pub use crate::scaling::GpPredictions;
pub use choice::KernelChoice;
pub use model::{ExactGp, ExactGpState, GroupState};
pub use params::{ExactGpParams, OutputSharing, Solver};

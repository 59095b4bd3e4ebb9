//! The sparse Gaussian process: the authors' final on-board model (GPy
//! `SparseGPRegression`, RBF-ARD, 100 inducing points, hyperparameters
//! shared by the outputs). Titsias' collapsed variational bound (VFE) or
//! FITC ([`bound`]) with analytic gradients for the kernel
//! hyperparameters, the noise and the inducing inputs, learned with the
//! same optimiser as the exact GP ([`crate::hyperopt`]); inducing inputs
//! placed by seeded k-means or a random subset ([`inducing`]); an `O(m²)`
//! posterior for on-board prediction ([`posterior`]); the regressor behind
//! the trait ([`model`]).

pub mod bound;
pub mod inducing;
pub mod model;
pub mod params;
pub mod posterior;

pub use model::{SparseGp, SparseGpState};
pub use params::{Approximation, InducingInit, InducingParams, SparseGpParams};
pub use posterior::SparsePosterior;

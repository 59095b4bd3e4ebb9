//! Residual regressors behind [`gpodo_traits::ResidualRegressor`] (paper §IV),
//! their YAML specifications, and the metrics they are judged by.
//!
//! Implemented here:
//! * [`zero::ZeroResidual`]: "parametric model only", the baseline row of
//!   every table: predicts a zero residual with a fixed (or training) variance;
//! * [`kernels`]: RBF, Matérn 5/2 and 3/2 with ARD, linear, white, sums and
//!   products, with analytic gradients (§IV-A, eq. 10–13);
//! * [`exact_gp::ExactGp`]: the exact GP of §IV-A (faer Cholesky), the
//!   baseline every other regressor is benchmarked against;
//! * [`sparse_gp::SparseGp`]: the authors' on-board sparse GP (VFE or FITC,
//!   learned inducing inputs);
//! * [`ilgr::Ilgr`]: incremental local Gaussian regression (§VI; Meier,
//!   Hennig & Schaal 2014), learning online one sample at a time;
//! * [`external::ExternalRegressor`]: any model in any language, run as a
//!   child process speaking a line-delimited JSON protocol
//!   (`plugins/PROTOCOL.md`; a NumPy reference client in `plugins/python/`);
//! * [`knn::Knn`]: k-nearest-neighbour regression, the worked example of
//!   adding a regressor (`experiments/README.md`);
//! * [`hyperopt`]: the optimiser both GPs learn their hyperparameters with
//!   (argmin L-BFGS or nonlinear CG, bounds, seeded restarts);
//! * [`model_file`]: trained models saved and loaded (versioned JSON with
//!   the input columns and z-scoring), for `gpodo predict` and on-board use;
//! * [`online_model`]: the kinds that go on learning after loading, as one
//!   type a live learner is checkpointed and resumed with;
//! * [`metrics`]: RMSE and MAE per output (Table I), negative log predictive
//!   density and 95 % interval coverage;
//! * [`spec::RegressorSpec`]: the closed set of regressor kinds a YAML
//!   experiment may name, validated when the config is read.

pub mod dense;
mod error;
pub mod exact_gp;
pub mod external;
pub mod hyperopt;
pub mod ilgr;
pub mod kernels;
pub mod knn;
pub mod metrics;
pub mod model_file;
pub mod online_model;
pub mod problem;
pub mod scaling;
pub mod sparse_gp;
pub mod sparse_spectrum;
pub mod spec;
mod stream_rows;
pub mod streaming_sparse_gp;
pub mod zero;

pub use error::RegressorError;
pub use exact_gp::{ExactGp, ExactGpParams};
pub use external::{ExternalParams, ExternalRegressor};
pub use ilgr::{Ilgr, IlgrParams};
pub use kernels::{Kernel, KernelExpr};
pub use knn::{Knn, KnnParams};
pub use problem::{GpProblem, SparseProblem};
pub use sparse_gp::{SparseGp, SparseGpParams};
pub use sparse_spectrum::{SparseSpectrumGp, SparseSpectrumParams};
pub use spec::RegressorSpec;
pub use streaming_sparse_gp::{StreamingSparseGp, StreamingSparseGpParams};
pub use zero::ZeroResidual;

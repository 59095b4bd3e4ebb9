//! Regression problems as borrowed views, the way argmin hands a solver
//! its problem: what a likelihood, a bound or a posterior is evaluated on,
//! in one value instead of a list of numbers.
//!
//! * [`GpProblem`]: a GP with `kernel` and Gaussian noise of variance
//!   `noise_variance` on the data `(x, y)` (paper eq. 7);
//! * [`SparseProblem`]: that GP approximated through the inducing inputs
//!   `z` (VFE or FITC), with the diagonal jitter added to `K_uu`.
//!
//! Both are `Copy`: a view is passed by value, and the data it borrows are
//! never copied.

use faer::MatRef;

use crate::kernels::Kernel;
use crate::sparse_gp::params::Approximation;

/// An exact GP regression problem: kernel, noise variance and data.
#[derive(Debug, Clone, Copy)]
pub struct GpProblem<'a> {
    /// The covariance function, with its hyperparameters.
    pub kernel: &'a Kernel,
    /// The Gaussian noise variance `σ_n²` added to the kernel's diagonal.
    pub noise_variance: f64,
    /// Training inputs (`n × d`).
    pub x: MatRef<'a, f64>,
    /// Training targets (`n × p`), `p` outputs sharing kernel and noise.
    pub y: MatRef<'a, f64>,
}

impl<'a> GpProblem<'a> {
    /// The problem of `kernel` with noise `noise_variance` on `(x, y)`.
    pub fn new(
        kernel: &'a Kernel,
        noise_variance: f64,
        x: MatRef<'a, f64>,
        y: MatRef<'a, f64>,
    ) -> Self {
        Self {
            kernel,
            noise_variance,
            x,
            y,
        }
    }

    /// The number of training rows `n`.
    pub fn n_rows(&self) -> usize {
        self.x.nrows()
    }

    /// The number of outputs `p`.
    pub fn n_outputs(&self) -> usize {
        self.y.ncols()
    }
}

/// A sparse GP regression problem: the GP, its inducing inputs, the
/// approximation and the jitter on `K_uu`.
#[derive(Debug, Clone, Copy)]
pub struct SparseProblem<'a> {
    /// The GP being approximated.
    pub gp: GpProblem<'a>,
    /// Inducing inputs `Z` (`m × d`).
    pub z: MatRef<'a, f64>,
    /// VFE (a lower bound on the exact likelihood) or FITC.
    pub approximation: Approximation,
    /// Diagonal jitter added to `K_uu` before it is factorised.
    pub jitter: f64,
}

impl SparseProblem<'_> {
    /// The number of inducing inputs `m`.
    pub fn n_inducing(&self) -> usize {
        self.z.nrows()
    }
}

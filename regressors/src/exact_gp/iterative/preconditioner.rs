//! The preconditioner `P = L Lᵀ + σ² I` of the iterative exact GP, from a
//! pivoted Cholesky factor `L` (`n × k`) of the kernel matrix: solves by
//! the Woodbury identity, `P⁻¹ v = (v − L C⁻¹ Lᵀ v) / σ²` with
//! `C = σ² I_k + LᵀL`; `log|P| = log|C| + (n − k) log σ²` by the matrix
//! determinant lemma; draws from `N(0, P)` as `L ε₁ + σ ε₂`. Every
//! operation is `O(n k)` per column.

use faer::{Accum, Mat, MatRef};

use crate::RegressorError;
use crate::dense::gemm;
use crate::exact_gp::cholesky::Cholesky;

/// `P = L Lᵀ + σ² I`, ready to solve.
#[derive(Debug, Clone)]
pub struct Preconditioner {
    l: Mat<f64>,
    noise_variance: f64,
    /// The Cholesky factor of `C = σ² I_k + LᵀL`.
    inner: Option<Cholesky>,
}

impl Preconditioner {
    /// The preconditioner of `L Lᵀ + noise_variance · I`.
    ///
    /// # Errors
    /// [`RegressorError::NotPositiveDefinite`] when `C` cannot be factorised
    /// (a non-positive or non-finite noise variance).
    pub fn new(l: Mat<f64>, noise_variance: f64) -> Result<Self, RegressorError> {
        let k = l.ncols();
        let inner = if k == 0 {
            None
        } else {
            let mut c = Mat::<f64>::zeros(k, k);
            gemm(
                c.as_mut(),
                Accum::Replace,
                l.as_ref().transpose(),
                l.as_ref(),
                1.0,
            );
            for i in 0..k {
                c[(i, i)] += noise_variance;
            }
            Some(Cholesky::factor(c)?)
        };
        Ok(Self {
            l,
            noise_variance,
            inner,
        })
    }

    /// Its rank `k`.
    pub fn rank(&self) -> usize {
        self.l.ncols()
    }

    /// `P⁻¹ V`.
    pub fn solve(&self, v: MatRef<'_, f64>) -> Mat<f64> {
        let mut out = v.to_owned();
        if let Some(inner) = &self.inner {
            let mut ltv = Mat::<f64>::zeros(self.rank(), v.ncols());
            gemm(
                ltv.as_mut(),
                Accum::Replace,
                self.l.as_ref().transpose(),
                v,
                1.0,
            );
            let c_inv_ltv = inner.solve(ltv.as_ref());
            gemm(
                out.as_mut(),
                Accum::Add,
                self.l.as_ref(),
                c_inv_ltv.as_ref(),
                -1.0,
            );
        }
        out * faer::Scale(1.0 / self.noise_variance)
    }

    /// `log|P|`.
    pub fn log_det(&self) -> f64 {
        let n = self.l.nrows();
        let inner = self.inner.as_ref().map_or(0.0, Cholesky::log_det);
        inner + (n - self.rank()) as f64 * self.noise_variance.ln()
    }

    /// Draws from `N(0, P)`, one per column, from standard normal draws:
    /// `L ε₁ + σ ε₂` with `ε₁` the first `k` rows of `standard_normal` and
    /// `ε₂` the next `n` (`standard_normal` has at least `k + n` rows).
    pub fn sample(&self, standard_normal: MatRef<'_, f64>) -> Mat<f64> {
        let (n, k) = (self.l.nrows(), self.rank());
        let mut z =
            standard_normal.subrows(k, n).to_owned() * faer::Scale(self.noise_variance.sqrt());
        if k > 0 {
            gemm(
                z.as_mut(),
                Accum::Add,
                self.l.as_ref(),
                standard_normal.subrows(0, k),
                1.0,
            );
        }
        z
    }
}

//! Linear kernel with one variance per input (paper eq. 13 with ARD, as
//! GPy's `Linear(ARD=True)`): `k(x, x') = Σ_q v_q x_q x'_q`;
//! `∂K/∂log v_q = v_q x_q x_qᵀ`, so `Σ_ij W_ij ∂K_ij/∂log v_q = v_q x_qᵀ W x_q`,
//! all `q` from one product `W X`.

use faer::{Accum, Mat, MatRef};
use serde::{Deserialize, Serialize};

use faer::linalg::matmul::triangular::{self, BlockStructure};

use super::GradientTargets;
use crate::dense::{gemm, par, symmetric_times};

/// Hyperparameters of the linear kernel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Linear {
    /// One variance per input, `v_q`.
    pub variances: Vec<f64>,
}

impl Linear {
    /// A linear kernel with the given per-input variances.
    pub fn new(variances: Vec<f64>) -> Self {
        Self { variances }
    }

    /// `X diag(v)`.
    fn scaled(&self, x: MatRef<'_, f64>) -> Mat<f64> {
        Mat::from_fn(x.nrows(), x.ncols(), |i, q| x[(i, q)] * self.variances[q])
    }

    /// `K(X1, X2) = X1 diag(v) X2ᵀ`.
    pub fn cross(&self, x1: MatRef<'_, f64>, x2: MatRef<'_, f64>) -> Mat<f64> {
        let scaled = self.scaled(x1);
        // `Accum::Replace` writes every entry without reading it.
        let mut k = crate::dense::scratch(x1.nrows(), x2.nrows());
        gemm(
            k.as_mut(),
            Accum::Replace,
            scaled.as_ref(),
            x2.transpose(),
            1.0,
        );
        k
    }

    /// `K(X, X)` on and below the diagonal only (one triangular GEMM; what
    /// is above the diagonal is unspecified).
    pub fn gram_lower(&self, x: MatRef<'_, f64>) -> Mat<f64> {
        let scaled = self.scaled(x);
        // `Accum::Replace` writes every entry of the lower triangle.
        let mut k = crate::dense::scratch(x.nrows(), x.nrows());
        triangular::matmul(
            k.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            scaled.as_ref(),
            BlockStructure::Rectangular,
            x.transpose(),
            BlockStructure::Rectangular,
            1.0,
            par(),
        );
        k
    }

    /// Adds `Σ_ij W_ij ∂K_ij/∂log v_q = v_q x_qᵀ W x_q` to `out` (Gram
    /// matrix of `x`, symmetric `W` read by its lower triangle).
    pub fn accumulate_gradient(&self, x: MatRef<'_, f64>, w: MatRef<'_, f64>, out: &mut [f64]) {
        let wx = symmetric_times(w, x);
        for (q, o) in out.iter_mut().enumerate().take(x.ncols()) {
            let quad: f64 = (0..x.nrows()).map(|i| x[(i, q)] * wx[(i, q)]).sum();
            *o += self.variances[q] * quad;
        }
    }

    /// Adds `Σ_ij W_ij ∂K(X1, X2)_ij/∂log v_q` to `to.params` and, when
    /// asked, `factor · Σ_j W_ij ∂K_ij/∂X1_iq` to `to.inputs`.
    pub fn accumulate_cross_gradient(
        &self,
        x1: MatRef<'_, f64>,
        x2: MatRef<'_, f64>,
        w: MatRef<'_, f64>,
        to: GradientTargets<'_>,
    ) {
        let GradientTargets {
            params: out,
            inputs: dx1,
        } = to;
        let (n1, d) = (x1.nrows(), x1.ncols());
        let mut wx2 = Mat::<f64>::zeros(n1, d);
        gemm(wx2.as_mut(), Accum::Replace, w, x2, 1.0);
        if let Some(out) = out {
            for (q, o) in out.iter_mut().enumerate().take(d) {
                let quad: f64 = (0..n1).map(|i| x1[(i, q)] * wx2[(i, q)]).sum();
                *o += self.variances[q] * quad;
            }
        }
        if let Some((dx1, factor)) = dx1 {
            for q in 0..d {
                for i in 0..n1 {
                    dx1[(i, q)] += factor * self.variances[q] * wx2[(i, q)];
                }
            }
        }
    }
}

/// White noise as a kernel (GPy's `White`): `σ_w²` on the diagonal of
/// `K(X, X)`, zero between distinct point sets.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct White {
    /// Variance `σ_w²`.
    pub variance: f64,
}

impl White {
    /// A white kernel with the given variance.
    pub fn new(variance: f64) -> Self {
        Self { variance }
    }
}

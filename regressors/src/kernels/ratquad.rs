//! The rational quadratic kernel with ARD lengthscales, in GPy's
//! parameterisation (`GPy.kern.RatQuad`): `k(x, x') = σ² (1 + r²/2)^(−α)`
//! with `r² = Σ_q (x_q − x'_q)²/ℓ_q²` — a scale mixture of RBF kernels,
//! heavier-tailed the smaller the power `α`. Rasmussen & Williams' form
//! `(1 + r²/(2α))^(−α)` is the same kernel with every lengthscale
//! multiplied by `√α` (it tends to the RBF as `α → ∞`).
//!
//! Gradients, in log space, with `u = 1 + r²/2`: `∂K/∂log σ² = K`;
//! `∂K_ij/∂log ℓ_q = S_ij (x_iq − x_jq)²/ℓ_q²` with `S = −2 ∂K/∂r² =
//! α K/u` (the stationary kernels' form, so their gradient code is
//! reused); `∂K/∂log α = −α K ln u`.

use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};

use super::distance::{scaled_sq_dist, scaled_sq_dist_lower};
use super::{GradientTargets, GramCache, Stationary};
use crate::dense::{column, for_column_blocks, frobenius_dot};

/// Hyperparameters of the rational quadratic kernel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RatQuad {
    /// Signal variance `σ²`.
    pub variance: f64,
    /// One lengthscale per input, `ℓ_q`.
    pub lengthscales: Vec<f64>,
    /// The power `α` (GPy's `power`).
    pub power: f64,
}

/// A Gram or cross-covariance of the kernel with the matrices its
/// gradients need: `K`, `S = K/u` and `A = ∂K/∂log α`.
pub struct RatQuadMatrices {
    /// `K`.
    pub k: Mat<f64>,
    /// `S = −2 ∂K/∂r²`.
    pub s: Mat<f64>,
    /// `∂K/∂log α`.
    pub a: Mat<f64>,
}

impl RatQuad {
    /// A kernel with the given variance, lengthscales and power.
    pub fn new(variance: f64, lengthscales: Vec<f64>, power: f64) -> Self {
        Self {
            variance,
            lengthscales,
            power,
        }
    }

    /// Number of hyperparameters (`1 + d + 1`).
    pub fn n_params(&self) -> usize {
        2 + self.lengthscales.len()
    }

    /// The variance and lengthscales as a stationary kernel's (whose
    /// gradient code the first `1 + d` parameters share).
    fn stationary(&self) -> Stationary {
        Stationary::new(self.variance, self.lengthscales.clone())
    }

    /// `(K, S, A)` of one entry from `r²`.
    fn entry(&self, r2: f64) -> (f64, f64, f64) {
        let alpha = self.power;
        let ln_u = (0.5 * r2).ln_1p();
        let k = self.variance * (-alpha * ln_u).exp();
        (k, alpha * k / (1.0 + 0.5 * r2), -alpha * k * ln_u)
    }

    /// The three matrices from `r²` (taken over as `K`'s buffer), on and
    /// below the diagonal only when `lower` (what is above is then
    /// unspecified): column blocks in parallel ([`for_column_blocks`]),
    /// each entry from one evaluation, bit-identical whatever the thread
    /// count.
    fn matrices(&self, mut r2: Mat<f64>, lower: bool) -> RatQuadMatrices {
        let (n1, n2) = (r2.nrows(), r2.ncols());
        let mut s = crate::dense::scratch(n1, n2);
        let mut a = crate::dense::scratch(n1, n2);
        // `s`'s and `a`'s columns ride along as the per-column outputs of
        // `r2`'s blocks.
        let mut outputs: Vec<(&mut [f64], &mut [f64])> =
            columns(&mut s).into_iter().zip(columns(&mut a)).collect();
        for_column_blocks(&mut r2, &mut outputs, |j0, kcols, outs| {
            for (jj, (kcol, (scol, acol))) in kcols.iter_mut().zip(outs.iter_mut()).enumerate() {
                let i0 = if lower { (j0 + jj).min(n1) } else { 0 };
                for i in i0..n1 {
                    let (kv, sv, av) = self.entry(kcol[i]);
                    kcol[i] = kv;
                    scol[i] = sv;
                    acol[i] = av;
                }
            }
        });
        drop(outputs);
        RatQuadMatrices { k: r2, s, a }
    }
}

/// The columns of an owned (column-major) matrix as mutable slices.
fn columns(m: &mut Mat<f64>) -> Vec<&mut [f64]> {
    m.col_iter_mut()
        .filter_map(|c| c.try_as_col_major_mut().map(|c| c.as_slice_mut()))
        .collect()
}

impl RatQuad {
    /// `K(X, X)` and its derivative matrices on and below the diagonal.
    pub fn gram_lower(&self, x: MatRef<'_, f64>) -> RatQuadMatrices {
        self.matrices(scaled_sq_dist_lower(x, &self.lengthscales), true)
    }

    /// `K(X1, X2)` and its derivative matrices, in full.
    pub fn cross_with_derivatives(
        &self,
        x1: MatRef<'_, f64>,
        x2: MatRef<'_, f64>,
    ) -> RatQuadMatrices {
        self.matrices(scaled_sq_dist(x1, x2, &self.lengthscales), false)
    }

    /// `K(X1, X2)`.
    pub fn cross(&self, x1: MatRef<'_, f64>, x2: MatRef<'_, f64>) -> Mat<f64> {
        self.cross_with_derivatives(x1, x2).k
    }

    /// Adds `Σ_ij W_ij ∂K_ij/∂θ` for `θ = (log σ², log ℓ_1, …, log α)` to
    /// `out`, for a symmetric `W`, reading only lower triangles.
    pub fn accumulate_gradient(
        &self,
        x: MatRef<'_, f64>,
        k: &Mat<f64>,
        s: &Mat<f64>,
        a: &Mat<f64>,
        w: MatRef<'_, f64>,
        out: &mut [f64],
    ) {
        let d = self.lengthscales.len();
        self.stationary()
            .accumulate_gradient(x, k, Some(s), w, &mut out[..=d]);
        // Σ_ij over the symmetric matrices: twice the strict lower part
        // plus the diagonal, column by column.
        let n = a.nrows();
        let mut total = 0.0;
        for j in 0..n {
            let (wcol, acol) = (column(w, j), column(a.as_ref(), j));
            let below: f64 = (j + 1..n).map(|i| wcol[i] * acol[i]).sum();
            total += 2.0 * below + wcol[j] * acol[j];
        }
        out[d + 1] += total;
    }

    /// As [`Stationary::accumulate_cross_gradient`], with the power's
    /// gradient after the lengthscales'.
    pub fn accumulate_cross_gradient(
        &self,
        x1: MatRef<'_, f64>,
        x2: MatRef<'_, f64>,
        cache: &GramCache,
        w: MatRef<'_, f64>,
        to: GradientTargets<'_>,
    ) {
        let d = self.lengthscales.len();
        let GradientTargets { params, inputs } = to;
        match params {
            Some(out) => {
                let stationary = GradientTargets {
                    params: Some(&mut out[..=d]),
                    inputs,
                };
                self.stationary()
                    .accumulate_cross_gradient(x1, x2, cache, w, stationary);
                if let Some(a) = cache.a.as_ref() {
                    out[d + 1] += frobenius_dot(w, a.as_ref());
                }
            }
            None => self.stationary().accumulate_cross_gradient(
                x1,
                x2,
                cache,
                w,
                GradientTargets {
                    params: None,
                    inputs,
                },
            ),
        }
    }
}

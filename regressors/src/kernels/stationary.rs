//! Stationary kernels with ARD lengthscales, `k(x, x') = σ² κ(r)` with
//! `r² = Σ_q (x_q − x'_q)²/ℓ_q²`:
//! * squared exponential (paper eq. 10): `κ = exp(−r²/2)`;
//! * Matérn 5/2: `κ = (1 + √5 r + 5r²/3) exp(−√5 r)`;
//! * Matérn 3/2: `κ = (1 + √3 r) exp(−√3 r)`.
//!
//! Gradients, in log space: `∂K/∂log σ² = K` and
//! `∂K_ij/∂log ℓ_q = s_ij (x_iq − x_jq)²/ℓ_q²` with `s = −k'(r)/r`, finite
//! at `r = 0` for all three. `Σ_ij M_ij (x_iq − x_jq)²` with `M = W ∘ s` is
//! accumulated for all `q` at once from one product `M X` (`O(n²d)` in a
//! GEMM, no per-lengthscale `n × n` temporaries).

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef};
use serde::{Deserialize, Serialize};

use super::distance::{column_means, scaled_sq_dist, shift_scale};
use crate::dense::{frobenius_dot, hadamard, par};

/// Which stationary profile `κ(r)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    /// Squared exponential (RBF).
    Rbf,
    /// Matérn ν = 5/2.
    Matern52,
    /// Matérn ν = 3/2.
    Matern32,
}

impl Family {
    /// `κ(r)` and `−κ'(r)/r`, from `r²`.
    #[inline]
    fn profile(self, r2: f64) -> (f64, f64) {
        match self {
            Self::Rbf => {
                let k = (-0.5 * r2).exp();
                (k, k)
            }
            Self::Matern52 => {
                let sr = (5.0 * r2).sqrt();
                let e = (-sr).exp();
                ((1.0 + sr + 5.0 / 3.0 * r2) * e, 5.0 / 3.0 * (1.0 + sr) * e)
            }
            Self::Matern32 => {
                let sr = (3.0 * r2).sqrt();
                let e = (-sr).exp();
                ((1.0 + sr) * e, 3.0 * e)
            }
        }
    }
}

/// Hyperparameters of a stationary ARD kernel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stationary {
    /// Signal variance `σ²`.
    pub variance: f64,
    /// One lengthscale per input, `ℓ_q`.
    pub lengthscales: Vec<f64>,
}

impl Stationary {
    /// A kernel with the given variance and lengthscales.
    pub fn new(variance: f64, lengthscales: Vec<f64>) -> Self {
        Self {
            variance,
            lengthscales,
        }
    }

    /// Number of hyperparameters (`1 + d`).
    pub fn n_params(&self) -> usize {
        1 + self.lengthscales.len()
    }

    /// `K(X1, X2)`.
    pub fn cross(&self, family: Family, x1: MatRef<'_, f64>, x2: MatRef<'_, f64>) -> Mat<f64> {
        let mut k = scaled_sq_dist(x1, x2, &self.lengthscales, false);
        self.apply_profile(family, &mut k, None);
        k
    }

    /// `K(X, X)` and `S = σ² (−κ'(r)/r)` for the gradient (`None` for the
    /// RBF, where `S = K`).
    pub fn gram(&self, family: Family, x: MatRef<'_, f64>) -> (Mat<f64>, Option<Mat<f64>>) {
        let mut k = scaled_sq_dist(x, x, &self.lengthscales, true);
        let mut s = match family {
            Family::Rbf => None,
            _ => Some(Mat::zeros(k.nrows(), k.ncols())),
        };
        self.apply_profile(family, &mut k, s.as_mut());
        (k, s)
    }

    /// Replaces `r²` by `σ² κ(r)` in place, writing `σ²(−κ'/r)` to `s`.
    fn apply_profile(&self, family: Family, r2: &mut Mat<f64>, mut s: Option<&mut Mat<f64>>) {
        let var = self.variance;
        for j in 0..r2.ncols() {
            let col = r2.col_as_slice_mut(j);
            match s.as_deref_mut() {
                Some(s) => {
                    let scol = s.col_as_slice_mut(j);
                    for (v, sv) in col.iter_mut().zip(scol) {
                        let (k, d) = family.profile(*v);
                        *v = var * k;
                        *sv = var * d;
                    }
                }
                None => {
                    for v in col.iter_mut() {
                        *v = var * family.profile(*v).0;
                    }
                }
            }
        }
    }

    /// Adds `Σ_ij W_ij ∂K_ij/∂θ` for `θ = (log σ², log ℓ_1, …)` to `out`.
    pub fn accumulate_gradient(
        &self,
        x: MatRef<'_, f64>,
        k: &Mat<f64>,
        s: Option<&Mat<f64>>,
        w: MatRef<'_, f64>,
        out: &mut [f64],
    ) {
        out[0] += frobenius_dot(w, k.as_ref());
        let s = s.unwrap_or(k);
        let m = hadamard(w, s.as_ref());
        let sums = distance_weighted_sums(x, m.as_ref());
        for (q, (o, total)) in out[1..].iter_mut().zip(sums).enumerate() {
            *o += total / (self.lengthscales[q] * self.lengthscales[q]);
        }
    }
}

/// `Σ_ij M_ij (x_iq − x_jq)²` for every column `q`, via
/// `Σ_i x_iq² (M1)_i + Σ_j x_jq² (Mᵀ1)_j − 2 x_qᵀ M x_q` on centred inputs.
pub fn distance_weighted_sums(x: MatRef<'_, f64>, m: MatRef<'_, f64>) -> Vec<f64> {
    let (n, d) = (x.nrows(), x.ncols());
    let ones = vec![1.0; d];
    let xc = shift_scale(x, &column_means(x), &ones);
    let mut mx = Mat::<f64>::zeros(n, d);
    matmul(mx.as_mut(), Accum::Replace, m, xc.as_ref(), 1.0, par());
    let row_sums: Vec<f64> = (0..n).map(|i| m.row(i).iter().sum()).collect();
    let col_sums: Vec<f64> = (0..n).map(|j| m.col(j).iter().sum()).collect();
    (0..d)
        .map(|q| {
            let mut total = 0.0;
            for i in 0..n {
                let xi = xc[(i, q)];
                total += xi * xi * (row_sums[i] + col_sums[i]) - 2.0 * xi * mx[(i, q)];
            }
            total
        })
        .collect()
}

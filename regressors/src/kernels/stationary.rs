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

use faer::{Accum, Mat, MatRef};
use serde::{Deserialize, Serialize};

use super::distance::{column_means, scaled_sq_dist, scaled_sq_dist_lower, shift_scale};
use super::profile::Family;
use super::{GradientTargets, GramCache};
use crate::dense::{column, for_column_blocks, frobenius_dot, gemm, hadamard, symmetric_times};

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
        self.cross_with_s(family, x1, x2).0
    }

    /// `K(X, X)` and `S = σ² (−κ'(r)/r)` for the gradient (`None` for the
    /// RBF, where `S = K`), on and below the diagonal only (what is above
    /// it is unspecified; see [`crate::dense::symmetrize_from_lower`]).
    pub fn gram_lower(&self, family: Family, x: MatRef<'_, f64>) -> (Mat<f64>, Option<Mat<f64>>) {
        let k = scaled_sq_dist_lower(x, &self.lengthscales);
        self.profile_of(family, k, true)
    }

    /// `K(X1, X2)` and `S` as in [`Stationary::gram_lower`], in full,
    /// between two distinct point sets.
    pub fn cross_with_s(
        &self,
        family: Family,
        x1: MatRef<'_, f64>,
        x2: MatRef<'_, f64>,
    ) -> (Mat<f64>, Option<Mat<f64>>) {
        let k = scaled_sq_dist(x1, x2, &self.lengthscales);
        self.profile_of(family, k, false)
    }

    /// `(σ² κ(r), σ²(−κ'/r))` from `r²` (taken over as `K`'s buffer), on
    /// and below the diagonal only when `lower`.
    fn profile_of(
        &self,
        family: Family,
        mut k: Mat<f64>,
        lower: bool,
    ) -> (Mat<f64>, Option<Mat<f64>>) {
        let mut s = match family {
            Family::Rbf => None,
            _ => Some(crate::dense::scratch(k.nrows(), k.ncols())),
        };
        self.apply_profile(family, &mut k, s.as_mut(), lower);
        (k, s)
    }

    /// Replaces `r²` by `σ² κ(r)` in place, writing `σ²(−κ'/r)` to `s`
    /// (column blocks in parallel, see [`for_column_blocks`]; rows from the
    /// diagonal down when `lower`); with `s`, both come from one evaluation
    /// of the profile per entry.
    fn apply_profile(
        &self,
        family: Family,
        r2: &mut Mat<f64>,
        s: Option<&mut Mat<f64>>,
        lower: bool,
    ) {
        let var = self.variance;
        let first = |j: usize| if lower { j } else { 0 };
        if let Some(s) = s {
            // `r2`'s columns ride along as the per-column output of `s`'s
            // blocks: one pass reads `r²` and writes both matrices.
            let mut r2_columns: Vec<&mut [f64]> = r2
                .col_iter_mut()
                .filter_map(|c| c.try_as_col_major_mut().map(|c| c.as_slice_mut()))
                .collect();
            debug_assert_eq!(r2_columns.len(), s.ncols());
            for_column_blocks(s, &mut r2_columns, |j0, scols, rcols| {
                for (jj, (scol, rcol)) in scols.iter_mut().zip(rcols.iter_mut()).enumerate() {
                    let i0 = first(j0 + jj);
                    family.apply(var, &mut rcol[i0..], Some(&mut scol[i0..]));
                }
            });
            return;
        }
        let mut unused = vec![(); r2.ncols()];
        for_column_blocks(r2, &mut unused, |j0, columns, _| {
            for (jj, col) in columns.iter_mut().enumerate() {
                family.apply(var, &mut col[first(j0 + jj)..], None);
            }
        });
    }

    /// Adds `Σ_ij W_ij ∂K_ij/∂θ` for `θ = (log σ², log ℓ_1, …)` to `out`,
    /// for the Gram matrix `k = K(X, X)` and a symmetric `W`, reading only
    /// the lower triangles of `W`, `K` and `S`.
    ///
    /// `M = W ∘ S` is formed on and below the diagonal in a parallel pass
    /// over column blocks that also takes `Σ W ∘ K` (twice the strict lower
    /// part plus the diagonal) per column, reduced in column order
    /// (bit-identical whatever the thread count); then `M [X | 1]` from
    /// `M`'s lower triangle (two triangular GEMMs), whose last column is
    /// `M`'s row sums.
    pub fn accumulate_gradient(
        &self,
        x: MatRef<'_, f64>,
        k: &Mat<f64>,
        s: Option<&Mat<f64>>,
        w: MatRef<'_, f64>,
        out: &mut [f64],
    ) {
        let s = s.unwrap_or(k);
        let (n, d) = (k.nrows(), x.ncols());
        // Every entry on and below the diagonal is written.
        let mut m = crate::dense::scratch(n, n);
        // Per column: Σ_i W_ij K_ij over the whole column of the symmetric
        // matrices.
        let mut partial = vec![0.0; n];
        for_column_blocks(&mut m, &mut partial, |j0, columns, partial| {
            for (jj, (mcol, part)) in columns.iter_mut().zip(partial.iter_mut()).enumerate() {
                let j = j0 + jj;
                let (wcol, kcol, scol) =
                    (column(w, j), column(k.as_ref(), j), column(s.as_ref(), j));
                let mut below = 0.0;
                for i in j + 1..n {
                    below += wcol[i] * kcol[i];
                    mcol[i] = wcol[i] * scol[i];
                }
                mcol[j] = wcol[j] * scol[j];
                *part = 2.0 * below + wcol[j] * kcol[j];
            }
        });
        // [x − x̄ | 1].
        let centre = column_means(x);
        let xc1 = Mat::from_fn(
            n,
            d + 1,
            |i, q| if q < d { x[(i, q)] - centre[q] } else { 1.0 },
        );
        let mx = symmetric_times(m.as_ref(), xc1.as_ref());
        crate::dense::recycle(m);
        out[0] += partial.iter().sum::<f64>();
        // Σ_ij M_ij (x_iq − x_jq)² = 2 Σ_i x_iq² r_i − 2 Σ_i x_iq (M X)_iq,
        // with r = M 1 the row sums.
        for (q, o) in out[1..].iter_mut().enumerate() {
            let total: f64 = (0..n)
                .map(|i| {
                    let xi = xc1[(i, q)];
                    2.0 * xi * (xi * mx[(i, d)] - mx[(i, q)])
                })
                .sum();
            *o += total / (self.lengthscales[q] * self.lengthscales[q]);
        }
    }

    /// For `K(X1, X2)` with value `cache.k` and derivative matrix `cache.s`
    /// (see [`Stationary::cross_with_s`]): adds `Σ_ij W_ij ∂K_ij/∂θ` to
    /// `to.params` and, when asked, `Σ_j W_ij ∂K_ij/∂X1_iq` to `to.inputs`
    /// (scaled by its factor, 2 for a Gram matrix with symmetric `W`, whose
    /// every entry depends on both of its points).
    pub fn accumulate_cross_gradient(
        &self,
        x1: MatRef<'_, f64>,
        x2: MatRef<'_, f64>,
        cache: &GramCache,
        w: MatRef<'_, f64>,
        to: GradientTargets<'_>,
    ) {
        let GradientTargets {
            params: out,
            inputs: dx1,
        } = to;
        let k = &cache.k;
        let s = cache.s.as_ref().unwrap_or(k);
        let m = hadamard(w, s.as_ref());
        let sums = CrossSums::new(x1, x2, m.as_ref());
        if let Some(out) = out {
            out[0] += frobenius_dot(w, k.as_ref());
            for (q, o) in out[1..].iter_mut().enumerate() {
                *o += sums.squared_distance_sum(q) / (self.lengthscales[q] * self.lengthscales[q]);
            }
        }
        if let Some((dx1, factor)) = dx1 {
            // ∂K_ij/∂x1_iq = −S_ij (x1_iq − x2_jq)/ℓ_q².
            for q in 0..x1.ncols() {
                let l2 = self.lengthscales[q] * self.lengthscales[q];
                for i in 0..x1.nrows() {
                    dx1[(i, q)] -=
                        factor * (sums.x1c[(i, q)] * sums.row_sums[i] - sums.mx2[(i, q)]) / l2;
                }
            }
        }
    }
}

/// The sums over `M` that the gradients of a stationary cross-covariance
/// need, on inputs centred by the same shift: `M X2`, and `M`'s row and
/// column sums.
struct CrossSums {
    x1c: Mat<f64>,
    x2c: Mat<f64>,
    mx2: Mat<f64>,
    row_sums: Vec<f64>,
    col_sums: Vec<f64>,
}

impl CrossSums {
    fn new(x1: MatRef<'_, f64>, x2: MatRef<'_, f64>, m: MatRef<'_, f64>) -> Self {
        let ones = vec![1.0; x2.ncols()];
        let centre = column_means(x2);
        let x1c = shift_scale(x1, &centre, &ones);
        let x2c = shift_scale(x2, &centre, &ones);
        let mut mx2 = Mat::<f64>::zeros(x1.nrows(), x2.ncols());
        gemm(mx2.as_mut(), Accum::Replace, m, x2c.as_ref(), 1.0);
        let row_sums = (0..m.nrows()).map(|i| m.row(i).iter().sum()).collect();
        let col_sums = (0..m.ncols()).map(|j| m.col(j).iter().sum()).collect();
        Self {
            x1c,
            x2c,
            mx2,
            row_sums,
            col_sums,
        }
    }

    /// `Σ_ij M_ij (x1_iq − x2_jq)²`.
    fn squared_distance_sum(&self, q: usize) -> f64 {
        let first: f64 = (0..self.x1c.nrows())
            .map(|i| {
                self.x1c[(i, q)].powi(2) * self.row_sums[i]
                    - 2.0 * self.x1c[(i, q)] * self.mx2[(i, q)]
            })
            .sum();
        let second: f64 = (0..self.x2c.nrows())
            .map(|j| self.x2c[(j, q)].powi(2) * self.col_sums[j])
            .sum();
        first + second
    }
}

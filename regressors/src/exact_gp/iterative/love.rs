//! Predictive variances without a factor of `K_y`: LOVE's Krylov
//! approximation (Pleiss, Gardner, Weinberger & Wilson, "Constant-Time
//! Predictive Distributions for Gaussian Processes", ICML 2018), built by
//! blocks so that each pass over `K_y` is one matrix product.
//!
//! An orthonormal basis `Q` (`n × k`) of the block Krylov space
//! `span{V, K_y V, K_y² V, …}`, from a seeded Gaussian block `V`, with every
//! new block orthogonalised twice against all before it; `T = Qᵀ K_y Q`
//! from the same products. For a test point's cross-covariances `k_*`,
//!
//! `k_*ᵀ K_y⁻¹ k_* ≈ k_*ᵀ Q T⁻¹ Qᵀ k_* = ‖L_T⁻¹ Qᵀ k_*‖²`,  `T = L_T L_Tᵀ`.
//!
//! This is a Galerkin projection: for any orthonormal `Q` it never exceeds
//! the exact quadratic form (`K_y^{1/2} Q T⁻¹ Qᵀ K_y^{1/2}` is an orthogonal
//! projector), so the latent variances it gives are never below the exact
//! ones, and they reach them when `Q` spans the directions the `k_*` lie
//! in. Those are the kernel's leading eigenvectors, which a Krylov space
//! finds first. After the basis (`k / b` passes over `K_y`), a test point
//! costs `O(n k)`.

use faer::{Accum, Mat, MatRef};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::RegressorError;
use crate::dense::gemm;
use crate::exact_gp::cholesky::Cholesky;

/// Columns of each block of the Krylov basis.
pub const BLOCK: usize = 16;

/// `L_T⁻¹ Qᵀ` (`k × n`): the quadratic form `k_*ᵀ K_y⁻¹ k_*` as a squared
/// norm.
#[derive(Debug, Clone)]
pub struct KrylovVariance {
    root: Mat<f64>,
}

/// Orthogonalises the columns of `block` against the first `done` columns
/// of `q` (twice: once is not enough in floating point) and against each
/// other, appending those that keep more than `1e-10` of their norm to `q`;
/// returns how many it appended.
fn append_orthonormal(q: &mut Mat<f64>, done: usize, mut block: Mat<f64>) -> usize {
    let n = q.nrows();
    let original: Vec<f64> = (0..block.ncols()).map(|c| block.col(c).norm_l2()).collect();
    for _ in 0..2 {
        if done > 0 {
            let basis = q.as_ref().subcols(0, done);
            let mut coefficients = Mat::<f64>::zeros(done, block.ncols());
            gemm(
                coefficients.as_mut(),
                Accum::Replace,
                basis.transpose(),
                block.as_ref(),
                1.0,
            );
            gemm(
                block.as_mut(),
                Accum::Add,
                basis,
                coefficients.as_ref(),
                -1.0,
            );
        }
    }
    let mut added = 0;
    for (c, &before) in original.iter().enumerate() {
        if done + added == q.ncols().min(n) {
            break;
        }
        let mut v = block.col(c).to_owned();
        for _ in 0..2 {
            for j in done..done + added {
                let dot = q.col(j).transpose() * &v;
                for i in 0..n {
                    v[i] -= dot * q[(i, j)];
                }
            }
        }
        let norm = v.norm_l2();
        if norm > 1e-10 * before && norm > 0.0 {
            let at = done + added;
            for i in 0..n {
                q[(i, at)] = v[i] / norm;
            }
            added += 1;
        }
    }
    added
}

impl KrylovVariance {
    /// The basis of at most `rank` columns for `apply(V) = K_y V` on `n`
    /// rows, from the Gaussian block drawn from `seed`.
    ///
    /// # Errors
    /// [`RegressorError::NotPositiveDefinite`] when `Qᵀ K_y Q` cannot be
    /// factorised (`K_y` not positive definite).
    pub fn new(
        apply: impl Fn(MatRef<'_, f64>) -> Mat<f64>,
        n: usize,
        rank: usize,
        seed: u64,
    ) -> Result<Self, RegressorError> {
        let rank = rank.min(n).max(1);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let start = Mat::<f64>::from_fn(n, BLOCK.min(rank), |_, _| StandardNormal.sample(&mut rng));
        let mut q = Mat::<f64>::zeros(n, rank);
        let mut kq = Mat::<f64>::zeros(n, rank);
        let mut done = append_orthonormal(&mut q, 0, start);
        let mut applied = 0;
        while applied < done {
            let block = q.as_ref().subcols(applied, done - applied);
            let product = apply(block);
            kq.as_mut()
                .subcols_mut(applied, done - applied)
                .copy_from(product.as_ref());
            applied = done;
            if done < rank {
                let take = BLOCK.min(rank - done);
                let next = product.as_ref().subcols(0, take.min(product.ncols()));
                done += append_orthonormal(&mut q, done, next.to_owned());
            }
        }
        let (q, kq) = (q.as_ref().subcols(0, done), kq.as_ref().subcols(0, done));
        let mut t = Mat::<f64>::zeros(done, done);
        gemm(t.as_mut(), Accum::Replace, q.transpose(), kq, 1.0);
        let t = Mat::from_fn(done, done, |i, j| 0.5 * (t[(i, j)] + t[(j, i)]));
        let factor = Cholesky::factor(t)?;
        let root = factor.solve_lower(q.transpose());
        Ok(Self { root })
    }

    /// Columns of the basis (`k`).
    pub fn rank(&self) -> usize {
        self.root.nrows()
    }

    /// `k_*ᵀ K_y⁻¹ k_*` for each column of `k_star` (`n × m`), from below.
    pub fn explained(&self, k_star: MatRef<'_, f64>) -> Vec<f64> {
        let mut projected = Mat::<f64>::zeros(self.rank(), k_star.ncols());
        gemm(
            projected.as_mut(),
            Accum::Replace,
            self.root.as_ref(),
            k_star,
            1.0,
        );
        (0..k_star.ncols())
            .map(|j| projected.col(j).squared_norm_l2())
            .collect()
    }
}

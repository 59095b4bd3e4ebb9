//! Batched preconditioned conjugate gradients (mBCG; Gardner et al.,
//! NeurIPS 2018, §4): `K_y X = B` for every column of `B` at once, one
//! matrix product per iteration for all of them, each column with its own
//! step sizes. The steps `αⱼ` and ratios `βⱼ` of a column are its Lanczos
//! tridiagonal matrix (Saad, *Iterative Methods*, §6.7.3) for the
//! preconditioned system, which [`lanczos_log_quadrature`] turns into
//! `e₁ᵀ log(T) e₁`, the stochastic Lanczos quadrature of a log-determinant.

use faer::{Mat, MatRef};
use nalgebra::{DMatrix, SymmetricEigen};

use crate::RegressorError;

/// What a batched solve did.
#[derive(Debug, Clone)]
pub struct BatchedSolve {
    /// `X ≈ K_y⁻¹ B`.
    pub solution: Mat<f64>,
    /// Per column, the steps `α₁, α₂, …` of its iterations.
    pub alphas: Vec<Vec<f64>>,
    /// Per column, the ratios `β₁, β₂, …` (one fewer than its steps).
    pub betas: Vec<Vec<f64>>,
    /// Iterations run (the most any column needed).
    pub iterations: usize,
    /// The largest relative residual `‖b − K_y x‖ / ‖b‖` at the end.
    pub relative_residual: f64,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solves `K_y X = B` with `apply(V) = K_y V` and the preconditioner
/// `solve(R) = P⁻¹ R`, from `X = 0`, until every column's relative
/// residual is below `tolerance` or `max_iterations` have run. A column
/// that has converged stops moving (and stops adding Lanczos coefficients).
///
/// `stop` is asked before every iteration and ends the solve with
/// [`RegressorError::Stopped`] when it says so.
///
/// # Errors
/// [`RegressorError::Stopped`]; [`RegressorError::NotPositiveDefinite`]
/// when a search direction has a non-positive curvature.
pub fn batched_cg(
    apply: impl Fn(MatRef<'_, f64>) -> Mat<f64>,
    solve: impl Fn(MatRef<'_, f64>) -> Mat<f64>,
    b: MatRef<'_, f64>,
    tolerance: f64,
    max_iterations: usize,
    stop: impl Fn() -> bool,
) -> Result<BatchedSolve, RegressorError> {
    let (n, m) = (b.nrows(), b.ncols());
    let mut x = Mat::<f64>::zeros(n, m);
    let mut r = b.to_owned();
    let mut z = solve(r.as_ref());
    let mut d = z.clone();
    let norms: Vec<f64> = (0..m)
        .map(|c| dot(r.col_as_slice(c), r.col_as_slice(c)).sqrt())
        .collect();
    let mut rz: Vec<f64> = (0..m)
        .map(|c| dot(r.col_as_slice(c), z.col_as_slice(c)))
        .collect();
    let mut done: Vec<bool> = norms.iter().map(|&v| v == 0.0).collect();
    let mut alphas = vec![Vec::new(); m];
    let mut betas = vec![Vec::new(); m];
    let mut iterations = 0;
    let relative = |r: &Mat<f64>, c: usize| {
        dot(r.col_as_slice(c), r.col_as_slice(c)).sqrt() / norms[c].max(f64::MIN_POSITIVE)
    };
    while iterations < max_iterations && done.iter().any(|d| !d) {
        if stop() {
            return Err(RegressorError::Stopped);
        }
        let kd = apply(d.as_ref());
        for c in (0..m).filter(|&c| !done[c]) {
            let curvature = dot(d.col_as_slice(c), kd.col_as_slice(c));
            if curvature.is_nan() || curvature <= 0.0 {
                return Err(RegressorError::NotPositiveDefinite {
                    n,
                    jitter_tried: 0.0,
                });
            }
            let alpha = rz[c] / curvature;
            alphas[c].push(alpha);
            for i in 0..n {
                x[(i, c)] += alpha * d[(i, c)];
                r[(i, c)] -= alpha * kd[(i, c)];
            }
        }
        iterations += 1;
        for (c, finished) in done.iter_mut().enumerate() {
            if !*finished && relative(&r, c) < tolerance {
                *finished = true;
            }
        }
        z = solve(r.as_ref());
        for c in (0..m).filter(|&c| !done[c]) {
            let rz_next = dot(r.col_as_slice(c), z.col_as_slice(c));
            let beta = rz_next / rz[c];
            betas[c].push(beta);
            rz[c] = rz_next;
            for i in 0..n {
                d[(i, c)] = z[(i, c)] + beta * d[(i, c)];
            }
        }
    }
    let relative_residual = (0..m).map(|c| relative(&r, c)).fold(0.0, f64::max);
    Ok(BatchedSolve {
        solution: x,
        alphas,
        betas,
        iterations,
        relative_residual,
    })
}

/// `e₁ᵀ log(T) e₁` for the Lanczos tridiagonal `T` of one column's
/// conjugate-gradient steps `α` and ratios `β`: `T₁₁ = 1/α₁`,
/// `Tⱼⱼ = 1/αⱼ + βⱼ₋₁/αⱼ₋₁`, `Tⱼ,ⱼ₊₁ = √βⱼ / αⱼ`; by its eigenpairs
/// `(λᵢ, vᵢ)`, `Σᵢ vᵢ[0]² log λᵢ` (Golub & Meurant's Gauss quadrature).
///
/// # Errors
/// [`RegressorError::NotPositiveDefinite`] when `T` has a non-positive
/// eigenvalue (a breakdown of the iteration).
pub fn lanczos_log_quadrature(alphas: &[f64], betas: &[f64]) -> Result<f64, RegressorError> {
    let j = alphas.len();
    if j == 0 {
        return Ok(0.0);
    }
    let mut t = DMatrix::<f64>::zeros(j, j);
    for i in 0..j {
        t[(i, i)] = 1.0 / alphas[i];
        if i > 0 {
            t[(i, i)] += betas[i - 1] / alphas[i - 1];
            let off = betas[i - 1].sqrt() / alphas[i - 1];
            t[(i, i - 1)] = off;
            t[(i - 1, i)] = off;
        }
    }
    let eigen = SymmetricEigen::new(t);
    let mut sum = 0.0;
    for (i, &lambda) in eigen.eigenvalues.iter().enumerate() {
        if lambda.is_nan() || lambda <= 0.0 {
            return Err(RegressorError::NotPositiveDefinite {
                n: j,
                jitter_tried: 0.0,
            });
        }
        sum += eigen.eigenvectors[(0, i)].powi(2) * lambda.ln();
    }
    Ok(sum)
}

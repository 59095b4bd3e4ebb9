//! The exact GP's log marginal likelihood and gradient by iterative solves
//! (BBMM: Gardner, Pleiss, Bindel, Weinberger & Wilson, NeurIPS 2018), for
//! training sets where the dense path's `n³` factorisation is too slow:
//! `O(n²)` per conjugate-gradient iteration, and no `n × n` inverse.
//!
//! With `K_y = K + σ_n² I`, `p` outputs `Y` and `t` probe vectors
//! `zᵢ ~ N(0, P)` (fixed per fit), one batched preconditioned CG solve
//! ([`mbcg::batched_cg`]) gives `A = K_y⁻¹ Y` and `uᵢ = K_y⁻¹ zᵢ`, and
//!
//! * `log|K_y| ≈ log|P| + (1/t) Σᵢ (zᵢᵀ P⁻¹ zᵢ) e₁ᵀ log(Tᵢ) e₁`, stochastic
//!   Lanczos quadrature on `P^{-1/2} K_y P^{-1/2}` from `P^{-1/2} zᵢ ~ N(0, I)`
//!   (`Tᵢ` from the CG coefficients of probe `i`);
//! * `tr(K_y⁻¹ ∂K) ≈ (1/t) Σᵢ uᵢᵀ ∂K (P⁻¹ zᵢ)`, Hutchinson's estimator with
//!   `E[zzᵀ] = P`;
//!
//! so the gradient is the dense path's `½ Σ_ij W_ij ∂K_ij/∂θ` with
//! `W = A Aᵀ − (p/t) sym(U (P⁻¹Z)ᵀ)`, formed by one GEMM of inner size
//! `p + t` and fed to the same kernel gradients (the ARD lengthscales in
//! one pass over the kernel entries). `P = L Lᵀ + σ_n² I` with `L` the
//! pivoted Cholesky factor of `K` of rank `k`
//! ([`pivoted_cholesky::pivoted_cholesky`]).

pub mod love;
pub mod mbcg;
pub mod pivoted_cholesky;
pub mod preconditioner;

use faer::linalg::matmul::triangular::{BlockStructure, matmul};
use faer::{Accum, Mat, MatRef};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::dense::{par, symmetric_times, trace};
use crate::exact_gp::likelihood::LN_2PI;
use crate::{GpProblem, RegressorError};
use mbcg::{batched_cg, lanczos_log_quadrature};
use preconditioner::Preconditioner;

/// Settings of the iterative solves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IterativeSettings {
    /// Probe vectors `t` of the log-determinant and trace estimates
    /// (default 16).
    pub probes: usize,
    /// Rank `k` of the pivoted-Cholesky preconditioner (default 300; 0: none).
    pub preconditioner_rank: usize,
    /// Relative residual at which a column's CG stops (default 1e-6). The
    /// iteration count is not fixed: the tolerance is tight enough that the
    /// objective, with its probes fixed, is smooth for L-BFGS: where the
    /// count changes between two nearby points, the estimate moves by the
    /// solves' residual error, far below the optimiser's steps.
    pub tolerance: f64,
    /// CG iterations at most (default 1000).
    pub max_iterations: usize,
    /// Seed of the probe vectors and of the predictive variances' Krylov
    /// start block (default 0).
    pub seed: u64,
    /// Columns of the Krylov basis of the predictive variances after an
    /// iterative fit ([`love::KrylovVariance`]; default 256): each test
    /// row then costs `O(n k)`, and its latent variance is never below the
    /// exact one.
    pub variance_rank: usize,
    /// Rows, spread evenly over the training set, of a dense fit (from the
    /// start policy) whose optimum the iterative fit starts from alone
    /// (default 2000; 0, or at least the training rows: the start policy's
    /// candidates, evaluated iteratively). At the policy's small initial
    /// noise CG needs hundreds of iterations; near an optimum, few.
    pub subset_rows: usize,
}

impl IterativeSettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the field (under `iterative.`).
    pub fn check(&self) -> Result<(), RegressorError> {
        let bad = |field: &str, expected: &str| {
            Err(RegressorError::InvalidSpec {
                regressor: "exact_gp".into(),
                field: format!("iterative.{field}"),
                expected: expected.into(),
            })
        };
        if self.probes == 0 {
            return bad("probes", "at least 1 probe vector");
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return bad("tolerance", "a relative residual in (0, 1)");
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", "at least 1");
        }
        if self.variance_rank == 0 {
            return bad("variance_rank", "at least 1 column");
        }
        Ok(())
    }
}

impl Default for IterativeSettings {
    fn default() -> Self {
        Self {
            probes: 16,
            preconditioner_rank: 300,
            tolerance: 1e-6,
            max_iterations: 1000,
            seed: 0,
            variance_rank: 256,
            subset_rows: 2000,
        }
    }
}

/// The iterative solver of one fit: its settings and its probes' standard
/// normal draws, `(k + n) × t`, drawn once from `settings.seed` and reused by
/// every evaluation, so that the objective is a deterministic, smooth
/// function of the hyperparameters.
#[derive(Debug, Clone)]
pub struct IterativeSolver {
    settings: IterativeSettings,
    draws: Mat<f64>,
}

impl IterativeSolver {
    /// The solver for `n` training rows.
    pub fn new(n: usize, settings: IterativeSettings) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
        let rows = n + settings.preconditioner_rank.min(n);
        let mut draws = Mat::<f64>::zeros(rows, settings.probes);
        for c in 0..settings.probes {
            for i in 0..rows {
                draws[(i, c)] = StandardNormal.sample(&mut rng);
            }
        }
        Self { settings, draws }
    }

    /// Its settings.
    pub fn settings(&self) -> &IterativeSettings {
        &self.settings
    }
}

/// One iterative evaluation of the objective.
#[derive(Debug, Clone, PartialEq)]
pub struct IterativeEvaluation {
    /// The estimate of `log p(Y | X, θ)`, summed over the outputs.
    pub lml: f64,
    /// `∂ log p/∂ log θ` (kernel hyperparameters, then the noise variance).
    pub gradient: Option<Vec<f64>>,
    /// CG iterations of the batched solve.
    pub iterations: usize,
    /// The largest relative residual at its end.
    pub relative_residual: f64,
    /// The preconditioner's rank (fewer than asked when `K` has lower rank).
    pub preconditioner_rank: usize,
    /// The standard error of `lml` from its probes: `p/2` times the sample
    /// standard deviation of the probes' log-determinant terms over `√t`
    /// (0 with one probe: there is no spread to measure). Hutchinson's
    /// estimator has variance `2‖log(P^{-1/2} K_y P^{-1/2})‖²_F / t` for
    /// Gaussian probes, which grows as the noise shrinks beneath the
    /// kernel's spectrum.
    pub lml_standard_error: f64,
}

/// The log marginal likelihood of the exact GP `problem` (its kernel, noise
/// variance and data) by `solver`'s iterative solves, and its
/// gradient when asked. `stop` is asked before every CG iteration.
///
/// # Errors
/// [`RegressorError::Stopped`] when `stop` said so;
/// [`RegressorError::NotPositiveDefinite`] when the iteration breaks down;
/// [`RegressorError::InvalidData`] when `solver` was made for another `n`.
pub fn log_marginal_likelihood_iterative(
    problem: GpProblem<'_>,
    with_gradient: bool,
    solver: &IterativeSolver,
    stop: impl Fn() -> bool,
) -> Result<IterativeEvaluation, RegressorError> {
    let clock = std::time::Instant::now();
    let cache = problem.kernel.gram_lower_with_cache(problem.x);
    tracing::debug!(
        gram_secs = clock.elapsed().as_secs_f64(),
        "iterative exact-GP kernel matrix"
    );
    let out = evaluate(problem, &cache, with_gradient, solver, &stop);
    cache.recycle();
    out.map(|(evaluation, _)| evaluation)
}

/// The GP conditioned by iterative solves: the weights `K_y⁻¹ Y` by CG (to
/// the solver's tolerance), the likelihood's estimate there, and the
/// Krylov basis of the predictive variances ([`love::KrylovVariance`], of
/// `variance_rank` columns, its start block from the solver's seed).
#[derive(Debug, Clone)]
pub struct IterativePosterior {
    /// `K_y⁻¹ Y`.
    pub alpha: Mat<f64>,
    /// The predictive variances' basis.
    pub variance: love::KrylovVariance,
    /// The likelihood's estimate and its standard error.
    pub evaluation: IterativeEvaluation,
}

/// Conditions the GP `problem` by
/// `solver`'s iterative solves and a Krylov basis of `variance_rank`
/// columns for the variances; the kernel matrix is formed once for both.
///
/// # Errors
/// As [`log_marginal_likelihood_iterative`].
pub fn iterative_posterior(
    problem: GpProblem<'_>,
    solver: &IterativeSolver,
    variance_rank: usize,
) -> Result<IterativePosterior, RegressorError> {
    let GpProblem {
        kernel,
        noise_variance,
        x,
        ..
    } = problem;
    let cache = kernel.gram_lower_with_cache(x);
    let out =
        evaluate(problem, &cache, false, solver, &|| false).and_then(|(evaluation, alpha)| {
            let k = cache.k.as_ref();
            let clock = std::time::Instant::now();
            let variance = love::KrylovVariance::new(
                |v| {
                    let mut out = symmetric_times(k, v);
                    out += v * faer::Scale(noise_variance);
                    out
                },
                x.nrows(),
                variance_rank,
                solver.settings.seed,
            )?;
            tracing::debug!(
                rank = variance.rank(),
                secs = clock.elapsed().as_secs_f64(),
                "iterative exact GP: the predictive variances' Krylov basis"
            );
            Ok(IterativePosterior {
                alpha,
                variance,
                evaluation,
            })
        });
    cache.recycle();
    out
}

/// [`log_marginal_likelihood_iterative`] on a kernel matrix already
/// formed (`cache`, its lower triangle), with the weights `K_y⁻¹ Y`.
fn evaluate(
    problem: GpProblem<'_>,
    cache: &crate::kernels::GramCache,
    with_gradient: bool,
    solver: &IterativeSolver,
    stop: &dyn Fn() -> bool,
) -> Result<(IterativeEvaluation, Mat<f64>), RegressorError> {
    let GpProblem {
        kernel,
        noise_variance,
        x,
        y,
    } = problem;
    let (n, p) = (y.nrows(), y.ncols());
    let settings = &solver.settings;
    if solver.draws.nrows() != n + settings.preconditioner_rank.min(n) {
        return Err(RegressorError::InvalidData {
            detail: format!(
                "the iterative solver's probes were drawn for another number of rows than {n}"
            ),
        });
    }
    let t = settings.probes;
    let clock = std::time::Instant::now();
    let l =
        pivoted_cholesky::pivoted_cholesky(cache.k.as_ref(), settings.preconditioner_rank, 1e-10);
    let rank = l.ncols();
    let pre = Preconditioner::new(l, noise_variance)?;
    // Probes from N(0, P): the first `rank` rows of the draws feed L ε₁.
    let draws = solver
        .draws
        .as_ref()
        .subrows(settings.preconditioner_rank.min(n) - rank, n + rank);
    let z = pre.sample(draws);
    let mut b = Mat::<f64>::zeros(n, p + t);
    b.as_mut().subcols_mut(0, p).copy_from(y);
    b.as_mut().subcols_mut(p, t).copy_from(z.as_ref());
    let k = cache.k.as_ref();
    let solved = batched_cg(
        |v| {
            let mut out = symmetric_times(k, v);
            out += v * faer::Scale(noise_variance);
            out
        },
        |r| pre.solve(r),
        b.as_ref(),
        settings.tolerance,
        settings.max_iterations,
        stop,
    )?;
    tracing::debug!(
        n,
        iterations = solved.iterations,
        relative_residual = solved.relative_residual,
        preconditioner_rank = rank,
        noise_variance,
        solve_secs = clock.elapsed().as_secs_f64(),
        "iterative exact-GP solve"
    );
    let alpha = solved.solution.as_ref().subcols(0, p);
    let u = solved.solution.as_ref().subcols(p, t);
    let pz = pre.solve(z.as_ref());
    let data_fit: f64 = (0..p)
        .map(|c| (0..n).map(|i| y[(i, c)] * alpha[(i, c)]).sum::<f64>())
        .sum();
    let terms = (0..t)
        .map(|i| {
            let weight: f64 = (0..n).map(|r| z[(r, i)] * pz[(r, i)]).sum();
            let c = p + i;
            Ok(weight * lanczos_log_quadrature(&solved.alphas[c], &solved.betas[c])?)
        })
        .collect::<Result<Vec<f64>, RegressorError>>()?;
    let quadrature = terms.iter().sum::<f64>() / t.max(1) as f64;
    let log_det = pre.log_det() + quadrature;
    let lml_standard_error = if t > 1 {
        let spread = terms.iter().map(|q| (q - quadrature).powi(2)).sum::<f64>() / (t - 1) as f64;
        0.5 * p as f64 * (spread / t as f64).sqrt()
    } else {
        0.0
    };
    let lml = -0.5 * data_fit - 0.5 * p as f64 * log_det - 0.5 * (n * p) as f64 * LN_2PI;
    if !lml.is_finite() {
        return Err(RegressorError::NotPositiveDefinite {
            n,
            jitter_tried: 0.0,
        });
    }
    let gradient = with_gradient.then(|| {
        // W = A Aᵀ − (p/2t)(U (P⁻¹Z)ᵀ + (P⁻¹Z) Uᵀ), lower triangle only.
        // Only the lower triangle is written and read.
        let mut w = crate::dense::scratch(n, n);
        let lower =
            |w: &mut Mat<f64>, a: MatRef<'_, f64>, b: MatRef<'_, f64>, scale: f64, accum| {
                matmul(
                    w.as_mut(),
                    BlockStructure::TriangularLower,
                    accum,
                    a,
                    BlockStructure::Rectangular,
                    b.transpose(),
                    BlockStructure::Rectangular,
                    scale,
                    par(),
                );
            };
        lower(&mut w, alpha, alpha, 1.0, Accum::Replace);
        if t > 0 {
            let s = -(p as f64) / (2.0 * t as f64);
            lower(&mut w, u, pz.as_ref(), s, Accum::Add);
            lower(&mut w, pz.as_ref(), u, s, Accum::Add);
        }
        let m = kernel.n_params();
        let mut g = vec![0.0; m + 1];
        kernel.accumulate_gradient(x, cache, w.as_ref(), &mut g[..m]);
        g[m] = noise_variance * trace(w.as_ref());
        crate::dense::recycle(w);
        for v in &mut g {
            *v *= 0.5;
        }
        g
    });
    let alpha = alpha.to_owned();
    let evaluation = IterativeEvaluation {
        lml,
        gradient,
        iterations: solved.iterations,
        relative_residual: solved.relative_residual,
        preconditioner_rank: rank,
        lml_standard_error,
    };
    Ok((evaluation, alpha))
}

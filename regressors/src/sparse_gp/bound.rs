//! The sparse GP objective and its analytic gradient with respect to the
//! kernel hyperparameters, the noise variance and the inducing inputs `Z`,
//! for `p` outputs sharing kernel and noise.
//!
//! Both approximations are `log N(Y | 0, Q_ff + Λ)` with
//! `Q_ff = K_fu K_uu⁻¹ K_uf`, `q_i = [Q_ff]_ii`:
//! * VFE (Titsias 2009): `Λ = σ²I`, minus the trace term
//!   `p/(2σ²) Σ_i (k_ii − q_i)` — a lower bound on the exact LML;
//! * FITC (Snelson & Ghahramani 2006): `λ_i = k_ii − q_i + σ²`.
//!
//! Computed stably (as GPy's `VarDTC`) with `K_uu = L Lᵀ`,
//! `A = L⁻¹ K_uf Λ^{-1/2}`, `B = I + A Aᵀ = L_B L_Bᵀ`:
//! `log|Q_ff + Λ| = log|B| + Σ log λ_i` and
//! `Yᵀ(Q_ff + Λ)⁻¹Y = Σ_i ‖y_i‖²/λ_i − ‖L_B⁻¹ A Λ^{-1/2} Y‖²`.
//!
//! Gradient: with `Σ = K_uu + K_uf Λ⁻¹ K_fu`, `β = Σ⁻¹ K_uf Λ⁻¹ Y`,
//! `r_i = βᵀk_i` (`k_i` the i-th column of `K_uf`), the partial derivatives
//! at fixed `Λ` are
//! `∂F/∂λ_i = (p/2) k_iᵀΣ⁻¹k_i/λ_i² − p/(2λ_i) + ‖y_i − r_i‖²/(2λ_i²)`,
//! `∂F/∂K_uu = (p/2)(K_uu⁻¹ − Σ⁻¹) − ½ββᵀ`,
//! `∂F/∂K_uf = [−pΣ⁻¹K_uf + β(Y − R)ᵀ] Λ⁻¹`;
//! then `λ_i` and the trace term depend on `k_ii`, `σ²` and `q_i`, and
//! `∂q_i/∂K_uf = 2 K_uu⁻¹k_i`, `∂q_i/∂K_uu = −K_uu⁻¹k_i k_iᵀK_uu⁻¹`.
//! Everything is `O(n m²)` in a few GEMMs and triangular solves; the
//! kernel turns `∂F/∂K_uu`, `∂F/∂K_uf` and `∂F/∂k_ii` into hyperparameter
//! and inducing-input gradients without per-hyperparameter `m × n`
//! temporaries.

use faer::{Accum, Mat};

use super::params::Approximation;
use crate::dense::gemm;
use crate::exact_gp::cholesky::Cholesky;
use crate::kernels::{GradientTargets, GramCache};
use crate::{RegressorError, SparseProblem};

/// `log 2π`.
const LN_2PI: f64 = 1.837_877_066_409_345_3;

/// One evaluation of the objective.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundEvaluation {
    /// The objective (VFE bound or FITC log likelihood), summed over outputs.
    pub value: f64,
    /// `∂F/∂ log θ` for the kernel's hyperparameters, then the noise variance.
    pub gradient: Option<Vec<f64>>,
    /// `∂F/∂Z` (`m × d`), when asked.
    pub inducing_gradient: Option<Mat<f64>>,
    /// Diagonal jitter that `K_uu` needed beyond the configured one.
    pub extra_jitter: f64,
}

/// The factorisations both the objective and the posterior need.
pub(super) struct Factors {
    pub cache_uu: GramCache,
    pub cache_uf: GramCache,
    pub kdiag: Vec<f64>,
    pub l: Cholesky,
    /// `L⁻¹ K_uf`.
    pub lk: Mat<f64>,
    /// `q_i = ‖L⁻¹ k_i‖²`.
    pub q: Vec<f64>,
    pub lambda: Vec<f64>,
    /// `A = L⁻¹ K_uf Λ^{-1/2}`.
    pub a: Mat<f64>,
    /// `B = I + A Aᵀ`.
    pub b: Mat<f64>,
    pub lb: Cholesky,
    /// `c = L_B⁻¹ A Λ^{-1/2} Y`.
    pub c: Mat<f64>,
    pub value: f64,
}

/// `Σ_r a_ri b_ri` for every column `i`.
fn column_dots(a: &Mat<f64>, b: &Mat<f64>) -> Vec<f64> {
    (0..a.ncols())
        .map(|i| {
            let (ca, cb) = (a.col_as_slice(i), b.col_as_slice(i));
            ca.iter().zip(cb).map(|(x, y)| x * y).sum()
        })
        .collect()
}

/// `m` with column `i` multiplied by `w[i]`.
fn scale_columns(m: &Mat<f64>, w: &[f64]) -> Mat<f64> {
    let mut out = m.clone();
    for (i, wi) in w.iter().enumerate() {
        for v in out.col_as_slice_mut(i) {
            *v *= wi;
        }
    }
    out
}

/// Builds the factors and the objective.
pub(super) fn factorize(problem: &SparseProblem<'_>) -> Result<Factors, RegressorError> {
    let SparseProblem {
        gp,
        z,
        approximation,
        jitter,
    } = *problem;
    let (kernel, x, y) = (gp.kernel, gp.x, gp.y);
    let (n, m, p) = (x.nrows(), z.nrows(), y.ncols());
    let s = gp.noise_variance;
    let cache_uu = kernel.gram_with_cache(z);
    let mut kuu = cache_uu.k.clone();
    for i in 0..m {
        kuu[(i, i)] += jitter;
    }
    let l = Cholesky::factor(kuu)?;
    let cache_uf = kernel.cross_with_cache(z, x);
    let kdiag = kernel.diag(x);
    let lk = l.solve_lower(cache_uf.k.as_ref());
    let q = column_dots(&lk, &lk);
    let lambda: Vec<f64> = match approximation {
        Approximation::Vfe => vec![s; n],
        Approximation::Fitc => (0..n).map(|i| (kdiag[i] - q[i]).max(0.0) + s).collect(),
    };
    let inv_sqrt_lambda: Vec<f64> = lambda.iter().map(|v| 1.0 / v.sqrt()).collect();
    let a = scale_columns(&lk, &inv_sqrt_lambda);
    let mut b = Mat::<f64>::identity(m, m);
    gemm(b.as_mut(), Accum::Add, a.as_ref(), a.transpose(), 1.0);
    let lb = Cholesky::factor(b.clone())?;
    let yt = Mat::from_fn(n, p, |i, c| y[(i, c)] * inv_sqrt_lambda[i]);
    let mut ay = Mat::<f64>::zeros(m, p);
    gemm(ay.as_mut(), Accum::Replace, a.as_ref(), yt.as_ref(), 1.0);
    let c = lb.solve_lower(ay.as_ref());
    let yy: f64 = (0..p)
        .map(|k| (0..n).map(|i| yt[(i, k)].powi(2)).sum::<f64>())
        .sum();
    let cc: f64 = (0..p)
        .map(|k| c.col(k).iter().map(|v| v * v).sum::<f64>())
        .sum();
    let log_det = lb.log_det() + lambda.iter().map(|v| v.ln()).sum::<f64>();
    let mut value = -0.5 * (n * p) as f64 * LN_2PI - 0.5 * p as f64 * log_det - 0.5 * (yy - cc);
    if approximation == Approximation::Vfe {
        let trace: f64 = kdiag.iter().zip(&q).map(|(k, q)| k - q).sum();
        value -= 0.5 * p as f64 / s * trace;
    }
    if !value.is_finite() {
        return Err(RegressorError::NotPositiveDefinite {
            n: m,
            jitter_tried: l.jitter,
        });
    }
    Ok(Factors {
        cache_uu,
        cache_uf,
        kdiag,
        l,
        lk,
        q,
        lambda,
        a,
        b,
        lb,
        c,
        value,
    })
}

/// Evaluates the objective of `problem`, with the hyperparameter gradient
/// when `with_gradient` and the inducing-input gradient when also
/// `with_inducing_gradient`.
///
/// # Errors
/// [`RegressorError::NotPositiveDefinite`] when `K_uu` cannot be factorised.
pub fn sparse_objective(
    problem: SparseProblem<'_>,
    with_gradient: bool,
    with_inducing_gradient: bool,
) -> Result<BoundEvaluation, RegressorError> {
    let f = factorize(&problem)?;
    let mut out = BoundEvaluation {
        value: f.value,
        gradient: None,
        inducing_gradient: None,
        extra_jitter: f.l.jitter,
    };
    if !with_gradient {
        return Ok(out);
    }
    let SparseProblem {
        gp,
        z,
        approximation,
        ..
    } = problem;
    let (kernel, x, y) = (gp.kernel, gp.x, gp.y);
    let (n, m, p) = (x.nrows(), z.nrows(), y.ncols());
    let (pf, s) = (p as f64, gp.noise_variance);
    // γ = B⁻¹ A Λ^{-1/2} Y (β = L⁻ᵀγ), R = K_fu β = (L⁻¹K_uf)ᵀ γ.
    let gamma = f.lb.solve_upper(f.c.as_ref());
    let mut r = Mat::<f64>::zeros(n, p);
    gemm(
        r.as_mut(),
        Accum::Replace,
        f.lk.transpose(),
        gamma.as_ref(),
        1.0,
    );
    // H = B⁻¹ A; k_iᵀΣ⁻¹k_i = λ_i a_iᵀ B⁻¹ a_i = λ_i (a_i · h_i).
    let b_inv = f.lb.inverse();
    let mut h = Mat::<f64>::zeros(m, n);
    gemm(
        h.as_mut(),
        Accum::Replace,
        b_inv.as_ref(),
        f.a.as_ref(),
        1.0,
    );
    let ah = column_dots(&f.a, &h);
    let g_lambda: Vec<f64> = (0..n)
        .map(|i| {
            let lam = f.lambda[i];
            let resid: f64 = (0..p).map(|k| (y[(i, k)] - r[(i, k)]).powi(2)).sum();
            0.5 * pf * ah[i] / lam - 0.5 * pf / lam + 0.5 * resid / (lam * lam)
        })
        .collect();
    let (g_q, g_kdiag, g_s): (Vec<f64>, Vec<f64>, f64) = match approximation {
        Approximation::Fitc => (
            g_lambda.iter().map(|g| -g).collect(),
            g_lambda.clone(),
            g_lambda.iter().sum(),
        ),
        Approximation::Vfe => {
            let trace: f64 = f.kdiag.iter().zip(&f.q).map(|(k, q)| k - q).sum();
            (
                vec![0.5 * pf / s; n],
                vec![-0.5 * pf / s; n],
                g_lambda.iter().sum::<f64>() + 0.5 * pf / (s * s) * trace,
            )
        }
    };
    // ∂F/∂K_uf = L⁻ᵀ [−p H Λ^{-1/2} + γ((Y − R)Λ⁻¹)ᵀ + 2 (L⁻¹K_uf) diag(g_q)].
    let mut guf = Mat::<f64>::zeros(m, n);
    for (i, (lam, gq)) in f.lambda.iter().zip(&g_q).enumerate() {
        let (wh, wl) = (-pf / lam.sqrt(), 2.0 * gq);
        let (hc, lc) = (h.col_as_slice(i), f.lk.col_as_slice(i));
        for ((o, hv), lv) in guf.col_as_slice_mut(i).iter_mut().zip(hc).zip(lc) {
            *o = wh * hv + wl * lv;
        }
    }
    let weighted_resid = Mat::from_fn(n, p, |i, k| (y[(i, k)] - r[(i, k)]) / f.lambda[i]);
    gemm(
        guf.as_mut(),
        Accum::Add,
        gamma.as_ref(),
        weighted_resid.transpose(),
        1.0,
    );
    let guf = f.l.solve_upper(guf.as_ref());
    // ∂F/∂K_uu = L⁻ᵀ J L⁻¹,
    // J = (p/2)(I − B⁻¹) − ½γγᵀ − (L⁻¹K_uf) diag(g_q) (L⁻¹K_uf)ᵀ; for VFE
    // g_q is the constant p/(2σ²) and (L⁻¹K_uf)(L⁻¹K_uf)ᵀ = σ²(B − I).
    let mut j = Mat::from_fn(m, m, |a, b| {
        let eye = if a == b { 1.0 } else { 0.0 };
        0.5 * pf * (eye - b_inv[(a, b)])
    });
    gemm(
        j.as_mut(),
        Accum::Add,
        gamma.as_ref(),
        gamma.transpose(),
        -0.5,
    );
    match approximation {
        Approximation::Vfe => {
            let g = g_q.first().copied().unwrap_or(0.0) * s;
            for col in 0..m {
                for row in 0..m {
                    let eye = if row == col { 1.0 } else { 0.0 };
                    j[(row, col)] -= g * (f.b[(row, col)] - eye);
                }
            }
        }
        Approximation::Fitc => {
            let lk_g = scale_columns(&f.lk, &g_q);
            gemm(
                j.as_mut(),
                Accum::Add,
                lk_g.as_ref(),
                f.lk.transpose(),
                -1.0,
            );
        }
    }
    let t = f.l.solve_upper(j.as_ref());
    let guu_t = f.l.solve_upper(t.transpose());
    let guu = Mat::from_fn(m, m, |a, b| 0.5 * (guu_t[(a, b)] + guu_t[(b, a)]));

    let k = kernel.n_params();
    let mut gradient = vec![0.0; k + 1];
    let mut dz = with_inducing_gradient.then(|| Mat::<f64>::zeros(m, z.ncols()));
    kernel.accumulate_gradient(z, &f.cache_uu, guu.as_ref(), &mut gradient[..k]);
    kernel.accumulate_cross_gradient(
        z,
        x,
        &f.cache_uf,
        guf.as_ref(),
        GradientTargets {
            params: Some(&mut gradient[..k]),
            inputs: dz.as_mut().map(|d| (d, 1.0)),
        },
    );
    kernel.accumulate_diag_gradient(x, &g_kdiag, &mut gradient[..k]);
    if let Some(d) = dz.as_mut() {
        kernel.accumulate_cross_gradient(
            z,
            z,
            &f.cache_uu,
            guu.as_ref(),
            GradientTargets::inputs(d, 2.0),
        );
    }
    gradient[k] = s * g_s;
    out.gradient = Some(gradient);
    out.inducing_gradient = dz;
    Ok(out)
}

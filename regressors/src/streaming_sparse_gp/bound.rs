//! The streaming sparse GP's collapsed bound and its optimal posterior
//! (Bui, Nguyen & Turner, "Streaming Gaussian process approximations",
//! NeurIPS 2017, §3.1 with a Gaussian likelihood), for `p` outputs
//! sharing kernel and noise.
//!
//! The old batches are summarised by a Gaussian `q_old(a) = N(m_a, S_a)`
//! over the function at the old inducing inputs `Z_a`, with `K'_aa` the
//! old prior covariance there (the old hyperparameters'). A new batch
//! `(X, Y)` with new inducing inputs `Z_b` and the current hyperparameters
//! gives, with `K_bb = L_b L_bᵀ`, `D_a⁻¹ = S_a⁻¹ − K'_aa⁻¹`,
//!
//! ```text
//! c = K_bf Y / σ² + K_ba S_a⁻¹ m_a                       (M_b × p)
//! D = I + L_b⁻¹ (K_bf K_fb / σ² + K_ba D_a⁻¹ K_ab) L_b⁻ᵀ   (M_b × M_b)
//! ```
//!
//! the optimal `q(b) = N(L_b D⁻¹ L_b⁻¹ c, L_b D⁻¹ L_bᵀ)` and the bound
//!
//! ```text
//! F = −(Np/2) log 2π − (Np/2) log σ² − ‖Y‖²/(2σ²) + ½‖L_D⁻¹ L_b⁻¹ c‖²
//!     − (p/2) log|D| − p/(2σ²) Σ_i (k_ii − q_i)
//!     − ½ Σ_k m_akᵀ S_a⁻¹ m_ak + (p/2)(log|K'_aa| − log|S_a|)
//!     − (p/2) tr[D_a⁻¹ (K_aa − K_ab K_bb⁻¹ K_ba)]
//! ```
//!
//! (`q_i = ‖L_b⁻¹ k_i‖²`; `D = L_D L_Dᵀ`).
//!
//! The summary is kept as what the old data told the inducing outputs,
//! `Λ_a = D_a⁻¹ = S_a⁻¹ − K'_aa⁻¹` and `η_a = S_a⁻¹ m_a`, rather than as
//! `(m_a, S_a)`: both come out of a batch without a difference of two
//! inverses (`Λ_b = L_b⁻ᵀ (D − I) L_b⁻¹`, `η_b = K_bb⁻¹ c`), and the old
//! terms of `F` are `−½ Σ_k η_akᵀ S_a η_ak`, `(p/2) log|I + L'ᵀ Λ_a L'|`
//! (`K'_aa = L' L'ᵀ`) and the trace with `Λ_a`. Without old batches it is
//! Titsias' VFE bound. With the hyperparameters and inducing inputs held
//! fixed, `K_ba D_a⁻¹ K_ab` is the old batches' `K_bf K_fb / σ²`, and
//! streaming gives the batch posterior over all the data. The authors'
//! implementation (`OSGPR_VFE` in `thangbui/streaming_sparse_gp`) computes
//! the same terms for one output.

use faer::{Accum, Mat, MatRef};

use crate::RegressorError;
use crate::dense::gemm;
use crate::exact_gp::cholesky::Cholesky;
use crate::kernels::Kernel;
use crate::sparse_gp::SparsePosterior;

/// `log 2π`.
const LN_2PI: f64 = 1.837_877_066_409_345_3;

/// What the old batches leave: what they told the function at their
/// inducing inputs, a Gaussian `q(a) = N(m_a, S_a)` with
/// `S_a⁻¹ = K'_aa⁻¹ + Λ_a` and `S_a⁻¹ m_a = η_a`.
#[derive(Debug, Clone, PartialEq)]
pub struct InducingSummary {
    /// The inducing inputs `Z_a` (`M_a × d`).
    pub inducing: Mat<f64>,
    /// The prior covariance `K'_aa` under the hyperparameters it was
    /// computed with, jitter included.
    pub prior_covariance: Mat<f64>,
    /// `Λ_a = S_a⁻¹ − K'_aa⁻¹` (`M_a × M_a`, shared by the outputs).
    pub data_precision: Mat<f64>,
    /// `η_a = S_a⁻¹ m_a` (`M_a × p`).
    pub natural_mean: Mat<f64>,
}

impl InducingSummary {
    /// `K'_aa = L' L'ᵀ` and `I + L'ᵀ Λ_a L' = L_B L_Bᵀ`.
    fn factors(&self) -> Result<(Cholesky, Cholesky), RegressorError> {
        let lk = Cholesky::factor(self.prior_covariance.clone())?;
        let lt_lambda = product(lk.l.transpose(), self.data_precision.as_ref());
        let mut b = Mat::<f64>::identity(lk.l.nrows(), lk.l.nrows());
        gemm(
            b.as_mut(),
            Accum::Add,
            lt_lambda.as_ref(),
            lk.l.as_ref(),
            1.0,
        );
        Ok((lk, Cholesky::factor(symmetric(b))?))
    }

    /// The covariance `S_a = L' (I + L'ᵀ Λ_a L')⁻¹ L'ᵀ`.
    ///
    /// # Errors
    /// [`RegressorError::NotPositiveDefinite`] when a factor fails.
    pub fn covariance(&self) -> Result<Mat<f64>, RegressorError> {
        let (lk, lb) = self.factors()?;
        let t = lb.solve_lower(lk.l.transpose());
        Ok(symmetric(product(t.transpose(), t.as_ref())))
    }

    /// The mean `m_a = S_a η_a`.
    ///
    /// # Errors
    /// As [`InducingSummary::covariance`].
    pub fn mean(&self) -> Result<Mat<f64>, RegressorError> {
        Ok(product(
            self.covariance()?.as_ref(),
            self.natural_mean.as_ref(),
        ))
    }
}

/// One batch of the streaming sparse GP.
#[derive(Debug, Clone, Copy)]
pub struct StreamingProblem<'a> {
    /// The kernel with the current hyperparameters.
    pub kernel: &'a Kernel,
    /// The noise variance `σ²`.
    pub noise_variance: f64,
    /// The batch's inputs (`N × d`).
    pub x: MatRef<'a, f64>,
    /// The batch's targets (`N × p`).
    pub y: MatRef<'a, f64>,
    /// The new inducing inputs `Z_b` (`M_b × d`).
    pub inducing: MatRef<'a, f64>,
    /// The old batches' summary (none for the first batch).
    pub old: Option<&'a InducingSummary>,
    /// Diagonal jitter added to `K_bb` and `K_aa`.
    pub jitter: f64,
}

/// The bound and the posterior after one batch.
#[derive(Debug, Clone)]
pub struct StreamingFit {
    /// The collapsed bound `F`.
    pub value: f64,
    /// `q(b)`, the summary the next batch starts from.
    pub summary: InducingSummary,
    /// The posterior for prediction (weights `L_b⁻ᵀ D⁻¹ L_b⁻¹ c`,
    /// variance matrix `L_b⁻ᵀ (I − D⁻¹) L_b⁻¹`).
    pub posterior: SparsePosterior,
}

fn with_jitter(mut k: Mat<f64>, jitter: f64) -> Mat<f64> {
    for i in 0..k.nrows() {
        k[(i, i)] += jitter;
    }
    k
}

fn product(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(a.nrows(), b.ncols());
    gemm(out.as_mut(), Accum::Replace, a, b, 1.0);
    out
}

/// Evaluates the bound of one batch and its optimal posterior.
///
/// # Errors
/// [`RegressorError::NotPositiveDefinite`] when `K_bb`, `S_a`, `K'_aa` or
/// `D` cannot be factorised.
pub fn streaming_fit(problem: StreamingProblem<'_>) -> Result<StreamingFit, RegressorError> {
    let StreamingProblem {
        kernel,
        noise_variance: s,
        x,
        y,
        inducing: zb,
        old,
        jitter,
    } = problem;
    let (n, mb, p) = (x.nrows(), zb.nrows(), y.ncols());
    let pf = p as f64;
    let kbb = with_jitter(kernel.gram(zb), jitter);
    let lb = Cholesky::factor(kbb.clone())?;
    let kbf = kernel.cross(zb, x);
    let lb_kbf = lb.solve_lower(kbf.as_ref());
    // c = K_bf Y / σ² (+ K_ba S_a⁻¹ m_a); D = I + L_b⁻¹(...)L_b⁻ᵀ.
    let mut c = product(kbf.as_ref(), y);
    for v in c.col_iter_mut().flat_map(|col| col.iter_mut()) {
        *v /= s;
    }
    // D − I, the data's part.
    let mut dm = Mat::<f64>::zeros(mb, mb);
    gemm(
        dm.as_mut(),
        Accum::Add,
        lb_kbf.as_ref(),
        lb_kbf.transpose(),
        1.0 / s,
    );
    let yy: f64 = (0..p)
        .map(|k| (0..n).map(|i| y[(i, k)].powi(2)).sum::<f64>())
        .sum();
    let trace_f: f64 = kernel
        .diag(x)
        .iter()
        .enumerate()
        .map(|(i, k)| k - lb_kbf.col(i).iter().map(|v| v * v).sum::<f64>())
        .sum();
    let mut value =
        -0.5 * (n * p) as f64 * (LN_2PI + s.ln()) - 0.5 * yy / s - 0.5 * pf / s * trace_f;
    if let Some(old) = old {
        let za = old.inducing.as_ref();
        let kba = cross_with_shared_jitter(kernel, zb, za, jitter);
        gemm(
            c.as_mut(),
            Accum::Add,
            kba.as_ref(),
            old.natural_mean.as_ref(),
            1.0,
        );
        // L_b⁻¹ K_ba Λ_a K_ab L_b⁻ᵀ.
        let w = lb.solve_lower(kba.as_ref());
        let w_lambda = product(w.as_ref(), old.data_precision.as_ref());
        gemm(
            dm.as_mut(),
            Accum::Add,
            w_lambda.as_ref(),
            w.transpose(),
            1.0,
        );
        // K_ab K_bb⁻¹ K_ba = Wᵀ W.
        let qaa = product(w.transpose(), w.as_ref());
        value += old_terms(kernel, old, &qaa, jitter, p)?;
    }
    let dm = symmetric(dm);
    let mut d = dm.clone();
    for i in 0..mb {
        d[(i, i)] += 1.0;
    }
    let ld = Cholesky::factor(d)?;
    let lb_c = lb.solve_lower(c.as_ref());
    let e = ld.solve_lower(lb_c.as_ref());
    let ee: f64 = (0..p)
        .map(|k| e.col(k).iter().map(|v| v * v).sum::<f64>())
        .sum();
    value += 0.5 * ee - 0.5 * pf * ld.log_det();
    if !value.is_finite() {
        return Err(RegressorError::NotPositiveDefinite {
            n: mb,
            jitter_tried: ld.jitter,
        });
    }
    // The summary of q(b): Λ_b = L_b⁻ᵀ (D − I) L_b⁻¹, η_b = L_b⁻ᵀ L_b⁻¹ c.
    let t = lb.solve_upper(dm.as_ref());
    let data_precision = symmetric(lb.solve_upper(t.transpose()));
    let natural_mean = lb.solve_upper(lb_c.as_ref());
    // Prediction: weights L_b⁻ᵀ D⁻¹ L_b⁻¹ c, variance matrix L_b⁻ᵀ (I − D⁻¹) L_b⁻¹.
    let weights = lb.solve_upper(ld.solve_upper(e.as_ref()).as_ref());
    let d_inv = ld.inverse();
    let inner = Mat::from_fn(mb, mb, |i, j| {
        (if i == j { 1.0 } else { 0.0 }) - d_inv[(i, j)]
    });
    let t = lb.solve_upper(inner.as_ref());
    let variance_matrix = symmetric(lb.solve_upper(t.transpose()));
    Ok(StreamingFit {
        value,
        summary: InducingSummary {
            inducing: zb.to_owned(),
            prior_covariance: with_jitter(kbb, lb.jitter),
            data_precision,
            natural_mean,
        },
        posterior: SparsePosterior {
            kernel: kernel.clone(),
            noise_variance: s,
            inducing: zb.to_owned(),
            weights,
            variance_matrix,
            objective: value,
            extra_jitter: lb.jitter,
        },
    })
}

/// The old batches' terms of `F`: `−½ Σ_k η_akᵀ S_a η_ak`
/// (`= −½ ‖L_B⁻¹ L'ᵀ η‖²`), `(p/2) log|I + L'ᵀ Λ_a L'|` and
/// `−(p/2) tr[Λ_a (K_aa − Q_aa)]`, given `Q_aa = K_ab K_bb⁻¹ K_ba`.
fn old_terms(
    kernel: &Kernel,
    old: &InducingSummary,
    qaa: &Mat<f64>,
    jitter: f64,
    p: usize,
) -> Result<f64, RegressorError> {
    let (lk, l_bracket) = old.factors()?;
    let lt_eta = product(lk.l.transpose(), old.natural_mean.as_ref());
    let u = l_bracket.solve_lower(lt_eta.as_ref());
    let eta_s_eta: f64 = (0..p)
        .map(|k| u.col(k).iter().map(|v| v * v).sum::<f64>())
        .sum();
    let kaa = with_jitter(kernel.gram(old.inducing.as_ref()), jitter);
    let ma = kaa.nrows();
    let trace_a: f64 = (0..ma)
        .map(|i| {
            (0..ma)
                .map(|j| old.data_precision[(i, j)] * (kaa[(j, i)] - qaa[(j, i)]))
                .sum::<f64>()
        })
        .sum();
    let pf = p as f64;
    Ok(-0.5 * eta_s_eta + 0.5 * pf * l_bracket.log_det() - 0.5 * pf * trace_a)
}

/// `K_ba`, with the jitter added where an old inducing input is kept as a
/// new one (the same row, bit for bit): the jitter belongs to the
/// inducing variable, as on `K_bb`'s and `K_aa`'s diagonals, so a kept
/// inducing point is the same variable in both.
fn cross_with_shared_jitter(
    kernel: &Kernel,
    zb: MatRef<'_, f64>,
    za: MatRef<'_, f64>,
    jitter: f64,
) -> Mat<f64> {
    let mut k = kernel.cross(zb, za);
    for i in 0..zb.nrows() {
        for j in 0..za.nrows() {
            if (0..zb.ncols()).all(|c| zb[(i, c)].to_bits() == za[(j, c)].to_bits()) {
                k[(i, j)] += jitter;
            }
        }
    }
    k
}

/// `(A + Aᵀ) / 2`.
fn symmetric(a: Mat<f64>) -> Mat<f64> {
    Mat::from_fn(a.nrows(), a.ncols(), |i, j| 0.5 * (a[(i, j)] + a[(j, i)]))
}

/// The bound `F` with its gradient: `∂F/∂log θ` for the kernel's
/// hyperparameters then the noise variance, and `∂F/∂Z_b` when
/// `with_inducing_gradient`. The old summary is held fixed.
///
/// With `Σ = K_bb + K_bf K_fb/σ² + K_ba Λ_a K_ab` (so that
/// `log|D| = log|Σ| − log|K_bb|`, `‖L_D⁻¹L_b⁻¹c‖² = cᵀΣ⁻¹c`),
/// `A = Σ⁻¹c`, `G_Σ = −½AAᵀ − (p/2)Σ⁻¹`, `H_f = K_bb⁻¹K_bf`,
/// `H_a = K_bb⁻¹K_ba`:
///
/// ```text
/// ∂F/∂K_bb = G_Σ + (p/2)K_bb⁻¹ − p/(2σ²) H_f H_fᵀ − (p/2) H_a Λ_a H_aᵀ
/// ∂F/∂K_bf = (2/σ²) G_Σ K_bf + A Yᵀ/σ² + (p/σ²) H_f
/// ∂F/∂k_ii = −p/(2σ²)
/// ∂F/∂K_ba = 2 G_Σ K_ba Λ_a + A η_aᵀ + p H_a Λ_a
/// ∂F/∂K_aa = −(p/2) Λ_a
/// ∂F/∂σ²  = −Np/(2σ²) + ‖Y‖²/(2σ⁴) + p/(2σ⁴) Σ_i (k_ii − q_i)
///           − tr(G_Σ K_bf K_fb)/σ⁴ − tr(Aᵀ K_bf Y)/σ⁴
/// ```
///
/// and the kernel turns these into hyperparameter and inducing-input
/// gradients as for the batch sparse GP. A kept inducing input's shared
/// jitter is a constant.
///
/// # Errors
/// As [`streaming_fit`].
pub fn streaming_objective(
    problem: StreamingProblem<'_>,
    with_inducing_gradient: bool,
) -> Result<crate::sparse_gp::bound::BoundEvaluation, RegressorError> {
    let StreamingProblem {
        kernel,
        noise_variance: s,
        x,
        y,
        inducing: zb,
        old,
        jitter,
    } = problem;
    let (n, mb, p) = (x.nrows(), zb.nrows(), y.ncols());
    let pf = p as f64;
    let cache_bb = kernel.gram_with_cache(zb);
    let lb = Cholesky::factor(with_jitter(cache_bb.k.clone(), jitter))?;
    let kbb_inv = lb.inverse();
    let cache_bf = kernel.cross_with_cache(zb, x);
    let kbf = &cache_bf.k;
    let h_f = product(kbb_inv.as_ref(), kbf.as_ref());
    let mut sigma = with_jitter(cache_bb.k.clone(), jitter + lb.jitter);
    gemm(
        sigma.as_mut(),
        Accum::Add,
        kbf.as_ref(),
        kbf.transpose(),
        1.0 / s,
    );
    let mut c = product(kbf.as_ref(), y);
    for v in c.col_iter_mut().flat_map(|col| col.iter_mut()) {
        *v /= s;
    }
    // The old batches' parts: K_ba (with the shared jitter), H_a, K_ba Λ_a.
    let old_parts = match old {
        Some(old) => {
            let za = old.inducing.as_ref();
            let cache_ba = kernel.cross_with_cache(zb, za);
            let kba = cross_with_shared_jitter(kernel, zb, za, jitter);
            let kba_lambda = product(kba.as_ref(), old.data_precision.as_ref());
            gemm(
                sigma.as_mut(),
                Accum::Add,
                kba_lambda.as_ref(),
                kba.transpose(),
                1.0,
            );
            gemm(
                c.as_mut(),
                Accum::Add,
                kba.as_ref(),
                old.natural_mean.as_ref(),
                1.0,
            );
            let h_a = product(kbb_inv.as_ref(), kba.as_ref());
            // K_ab K_bb⁻¹ K_ba.
            let qaa = product(kba.transpose(), h_a.as_ref());
            Some((old, cache_ba, kba_lambda, h_a, qaa))
        }
        None => None,
    };
    let sigma = symmetric(sigma);
    let ls = Cholesky::factor(sigma)?;
    let sigma_inv = ls.inverse();
    let a = ls.solve(c.as_ref());
    // F, with log|D| = log|Σ| − log|K_bb| and ‖L_D⁻¹L_b⁻¹c‖² = cᵀΣ⁻¹c.
    let ca: f64 = (0..mb)
        .map(|i| (0..p).map(|k| c[(i, k)] * a[(i, k)]).sum::<f64>())
        .sum();
    let mut value = -0.5 * (n * p) as f64 * (LN_2PI + s.ln()) + 0.5 * ca
        - 0.5 * pf * (ls.log_det() - lb.log_det());
    if let Some((old, _, _, _, qaa)) = &old_parts {
        value += old_terms(kernel, old, qaa, jitter, p)?;
    }
    // G_Σ = −½AAᵀ − (p/2)Σ⁻¹.
    let mut g_sigma = Mat::from_fn(mb, mb, |i, j| -0.5 * pf * sigma_inv[(i, j)]);
    gemm(
        g_sigma.as_mut(),
        Accum::Add,
        a.as_ref(),
        a.transpose(),
        -0.5,
    );
    // ∂F/∂K_bb.
    let mut g_bb = Mat::from_fn(mb, mb, |i, j| g_sigma[(i, j)] + 0.5 * pf * kbb_inv[(i, j)]);
    gemm(
        g_bb.as_mut(),
        Accum::Add,
        h_f.as_ref(),
        h_f.transpose(),
        -0.5 * pf / s,
    );
    // ∂F/∂K_bf.
    let mut g_bf = product(g_sigma.as_ref(), kbf.as_ref());
    for v in g_bf.col_iter_mut().flat_map(|col| col.iter_mut()) {
        *v *= 2.0 / s;
    }
    gemm(
        g_bf.as_mut(),
        Accum::Add,
        a.as_ref(),
        y.transpose(),
        1.0 / s,
    );
    for i in 0..mb {
        for j in 0..n {
            g_bf[(i, j)] += pf / s * h_f[(i, j)];
        }
    }
    // ∂F/∂σ².
    let yy: f64 = (0..p)
        .map(|k| (0..n).map(|i| y[(i, k)].powi(2)).sum::<f64>())
        .sum();
    let kdiag = kernel.diag(x);
    let q_sum: f64 = (0..mb)
        .map(|i| (0..n).map(|j| h_f[(i, j)] * kbf[(i, j)]).sum::<f64>())
        .sum();
    let kff_kbf = product(kbf.transpose(), g_sigma.as_ref()); // K_fb G_Σ
    let tr_g_kk: f64 = (0..n)
        .map(|j| (0..mb).map(|i| kff_kbf[(j, i)] * kbf[(i, j)]).sum::<f64>())
        .sum();
    let kbf_y = product(kbf.as_ref(), y);
    let tr_a_kbf_y: f64 = (0..mb)
        .map(|i| (0..p).map(|k| a[(i, k)] * kbf_y[(i, k)]).sum::<f64>())
        .sum();
    value += -0.5 * yy / s - 0.5 * pf / s * (kdiag.iter().sum::<f64>() - q_sum);
    if !value.is_finite() {
        return Err(RegressorError::NotPositiveDefinite {
            n: mb,
            jitter_tried: ls.jitter,
        });
    }
    let g_s = -0.5 * (n * p) as f64 / s
        + 0.5 * yy / (s * s)
        + 0.5 * pf / (s * s) * (kdiag.iter().sum::<f64>() - q_sum)
        - tr_g_kk / (s * s)
        - tr_a_kbf_y / (s * s);

    let k = kernel.n_params();
    let mut gradient = vec![0.0; k + 1];
    let mut dz = with_inducing_gradient.then(|| Mat::<f64>::zeros(mb, zb.ncols()));
    if let Some((old, cache_ba, kba_lambda, h_a, _)) = &old_parts {
        let za = old.inducing.as_ref();
        // ∂F/∂K_bb gets −(p/2) H_a Λ_a H_aᵀ.
        let h_a_lambda = product(h_a.as_ref(), old.data_precision.as_ref());
        gemm(
            g_bb.as_mut(),
            Accum::Add,
            h_a_lambda.as_ref(),
            h_a.transpose(),
            -0.5 * pf,
        );
        // ∂F/∂K_ba = 2 G_Σ K_ba Λ_a + A η_aᵀ + p H_a Λ_a.
        let mut g_ba = product(g_sigma.as_ref(), kba_lambda.as_ref());
        for v in g_ba.col_iter_mut().flat_map(|col| col.iter_mut()) {
            *v *= 2.0;
        }
        gemm(
            g_ba.as_mut(),
            Accum::Add,
            a.as_ref(),
            old.natural_mean.transpose(),
            1.0,
        );
        for i in 0..mb {
            for j in 0..za.nrows() {
                g_ba[(i, j)] += pf * h_a_lambda[(i, j)];
            }
        }
        kernel.accumulate_cross_gradient(
            zb,
            za,
            cache_ba,
            g_ba.as_ref(),
            crate::kernels::GradientTargets {
                params: Some(&mut gradient[..k]),
                inputs: dz.as_mut().map(|d| (d, 1.0)),
            },
        );
        // ∂F/∂K_aa = −(p/2) Λ_a.
        let cache_aa = kernel.gram_with_cache(za);
        let g_aa = Mat::from_fn(za.nrows(), za.nrows(), |i, j| {
            -0.5 * pf * old.data_precision[(i, j)]
        });
        kernel.accumulate_gradient(za, &cache_aa, g_aa.as_ref(), &mut gradient[..k]);
    }
    let g_bb = symmetric(g_bb);
    kernel.accumulate_gradient(zb, &cache_bb, g_bb.as_ref(), &mut gradient[..k]);
    kernel.accumulate_cross_gradient(
        zb,
        x,
        &cache_bf,
        g_bf.as_ref(),
        crate::kernels::GradientTargets {
            params: Some(&mut gradient[..k]),
            inputs: dz.as_mut().map(|d| (d, 1.0)),
        },
    );
    kernel.accumulate_diag_gradient(x, &vec![-0.5 * pf / s; n], &mut gradient[..k]);
    if let Some(d) = dz.as_mut() {
        kernel.accumulate_cross_gradient(
            zb,
            zb,
            &cache_bb,
            g_bb.as_ref(),
            crate::kernels::GradientTargets::inputs(d, 2.0),
        );
    }
    gradient[k] = s * g_s;
    Ok(crate::sparse_gp::bound::BoundEvaluation {
        value,
        gradient: Some(gradient),
        inducing_gradient: dz,
        extra_jitter: lb.jitter,
    })
}

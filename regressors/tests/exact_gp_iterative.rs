//! The iterative exact GP (BBMM): the pivoted Cholesky factor, the
//! preconditioner and the batched CG against dense linear algebra, the
//! Lanczos log-determinant on a matrix of known spectrum, and the
//! likelihood and its gradient against the dense path's.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use faer::{Mat, MatRef};
use gpodo_regressors::GpProblem;
use gpodo_regressors::exact_gp::cholesky::Cholesky;
use gpodo_regressors::exact_gp::iterative::mbcg::{batched_cg, lanczos_log_quadrature};
use gpodo_regressors::exact_gp::iterative::pivoted_cholesky::pivoted_cholesky;
use gpodo_regressors::exact_gp::iterative::preconditioner::Preconditioner;
use gpodo_regressors::exact_gp::iterative::{
    IterativeSettings, IterativeSolver, log_marginal_likelihood_iterative,
};
use gpodo_regressors::exact_gp::likelihood::log_marginal_likelihood;
use gpodo_regressors::kernels::Kernel;
use rand_distr::{Distribution, StandardNormal};
use support::*;

fn product(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    a * b
}

fn max_abs(m: &Mat<f64>) -> f64 {
    (0..m.nrows())
        .flat_map(|i| (0..m.ncols()).map(move |j| (i, j)))
        .map(|(i, j)| m[(i, j)].abs())
        .fold(0.0, f64::max)
}

/// A smooth RBF problem: 28-dimensional inputs of low intrinsic
/// dimension, as the residual inputs are.
fn problem(n: usize, seed: u64) -> (Kernel, Mat<f64>, Mat<f64>) {
    let mut r = rng(seed);
    let latent = inputs(&mut r, n, 3);
    let mix = inputs(&mut r, 3, 8);
    let x = product(latent.as_ref(), mix.as_ref()) * faer::Scale(0.5);
    let y = targets(&mut r, &x, 0.1);
    let kernel = random_kernel(&mut r, "rbf", 8);
    (kernel, x, y)
}

#[test]
fn the_pivoted_cholesky_factor_reproduces_k_at_full_rank_and_improves_with_rank() {
    let (kernel, x, _) = problem(60, 1);
    let k = kernel.gram(x.as_ref());
    let full = pivoted_cholesky(k.as_ref(), 60, 0.0);
    let err = max_abs(&(product(full.as_ref(), full.as_ref().transpose()) - &k));
    assert!(err < 1e-10, "full rank: {err:e}");
    let total: f64 = (0..60).map(|i| k[(i, i)]).sum();
    let mut previous = f64::INFINITY;
    let mut left_at = Vec::new();
    for rank in [2, 5, 10, 20] {
        let l = pivoted_cholesky(k.as_ref(), rank, 0.0);
        let left = k.clone() - product(l.as_ref(), l.as_ref().transpose());
        let trace: f64 = (0..60).map(|i| left[(i, i)]).sum();
        assert!(trace >= -1e-10 && trace < previous, "rank {rank}: {trace}");
        previous = trace;
        left_at.push(trace / total);
    }
    // It stops once what is left is below the tolerance: just above what
    // rank 10 leaves, at rank 10.
    let stopped = pivoted_cholesky(k.as_ref(), 60, left_at[2] * (1.0 + 1e-9));
    assert_eq!(stopped.ncols(), 10, "{left_at:?}");
}

#[test]
fn the_preconditioner_solves_and_draws_as_dense_algebra_says() {
    let (kernel, x, _) = problem(50, 2);
    let k = kernel.gram(x.as_ref());
    let l = pivoted_cholesky(k.as_ref(), 8, 0.0);
    let noise = 0.07;
    let mut p = product(l.as_ref(), l.as_ref().transpose());
    for i in 0..50 {
        p[(i, i)] += noise;
    }
    let pre = Preconditioner::new(l, noise).unwrap();
    let dense = Cholesky::factor(p.clone()).unwrap();
    let v = inputs(&mut rng(3), 50, 4);
    let err = max_abs(&(pre.solve(v.as_ref()) - dense.solve(v.as_ref())));
    assert!(err < 1e-8 * max_abs(&dense.solve(v.as_ref())), "{err:e}");
    assert!((pre.log_det() - dense.log_det()).abs() < 1e-9);
    // Draws have covariance P: the sample covariance of 20 000 of them.
    let mut r = rng(4);
    let eps = Mat::from_fn(58, 20_000, |_, _| -> f64 { StandardNormal.sample(&mut r) });
    let z = pre.sample(eps.as_ref());
    let cov = product(z.as_ref(), z.as_ref().transpose()) * faer::Scale(1.0 / 20_000.0);
    let err = max_abs(&(cov - &p)) / max_abs(&p);
    assert!(err < 0.05, "sample covariance off by {err}");
}

#[test]
fn batched_cg_solves_every_column_to_its_tolerance() {
    let (kernel, x, y) = problem(120, 5);
    let mut k = kernel.gram(x.as_ref());
    for i in 0..120 {
        k[(i, i)] += 0.01;
    }
    let dense = Cholesky::factor(k.clone()).unwrap();
    let b = Mat::from_fn(120, 5, |i, c| {
        if c < 3 {
            y[(i, c)]
        } else {
            (i * c) as f64 % 3.0
        }
    });
    let out = batched_cg(
        |v| product(k.as_ref(), v),
        |r| r.to_owned(),
        b.as_ref(),
        1e-10,
        2000,
        || false,
    )
    .unwrap();
    let exact = dense.solve(b.as_ref());
    let err = max_abs(&(out.solution.clone() - &exact)) / max_abs(&exact);
    assert!(err < 1e-6, "{err:e} after {} iterations", out.iterations);
    assert!(out.relative_residual < 1e-10);
    // A stop request ends it.
    let stopped = batched_cg(
        |v| product(k.as_ref(), v),
        |r| r.to_owned(),
        b.as_ref(),
        1e-10,
        10,
        || true,
    );
    assert!(matches!(
        stopped,
        Err(gpodo_regressors::RegressorError::Stopped)
    ));
}

#[test]
fn the_lanczos_log_determinant_is_unbiased_on_a_known_spectrum() {
    // K = Q diag(λ) Qᵀ with a random orthogonal Q and eigenvalues spread
    // over three decades: a diagonal K would be exact for any probe.
    let n = 150;
    let mut r = rng(6);
    let g = inputs(&mut r, n, n);
    let q = g.qr().compute_Q();
    let lambda: Vec<f64> = (0..n)
        .map(|i| 10f64.powf(-1.0 + 3.0 * i as f64 / (n - 1) as f64))
        .collect();
    let scaled = Mat::from_fn(n, n, |i, j| q[(i, j)] * lambda[j]);
    let k = product(scaled.as_ref(), q.as_ref().transpose());
    let exact: f64 = lambda.iter().map(|l| l.ln()).sum();
    let probes = 400;
    let w = Mat::from_fn(n, probes, |_, _| -> f64 { StandardNormal.sample(&mut r) });
    let out = batched_cg(
        |v| product(k.as_ref(), v),
        |r| r.to_owned(),
        w.as_ref(),
        1e-10,
        1000,
        || false,
    )
    .unwrap();
    let estimates: Vec<f64> = (0..probes)
        .map(|c| {
            let norm2: f64 = (0..n).map(|i| w[(i, c)] * w[(i, c)]).sum();
            norm2 * lanczos_log_quadrature(&out.alphas[c], &out.betas[c]).unwrap()
        })
        .collect();
    let mean = estimates.iter().sum::<f64>() / probes as f64;
    let sd =
        (estimates.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (probes - 1) as f64).sqrt();
    let se = sd / (probes as f64).sqrt();
    println!("log|K| = {exact:.3}; SLQ mean {mean:.3} ± {se:.3} (one probe's sd {sd:.3})");
    assert!(
        (mean - exact).abs() < 3.0 * se,
        "bias: {mean} against {exact} (se {se})"
    );
    // One probe's spread is that of Hutchinson's estimator, √2 ‖log K‖_F.
    let frobenius = lambda.iter().map(|l| l.ln().powi(2)).sum::<f64>().sqrt();
    assert!(
        sd < 1.5 * 2f64.sqrt() * frobenius && sd > 0.5 * 2f64.sqrt() * frobenius,
        "{sd} vs {frobenius}"
    );
}

/// One iterative evaluation of `kernel` with `noise` on `(x, y)` by a fresh
/// solver with `settings`, never stopped.
fn iterative(
    kernel: &Kernel,
    noise: f64,
    x: &Mat<f64>,
    y: &Mat<f64>,
    settings: IterativeSettings,
    with_gradient: bool,
) -> gpodo_regressors::exact_gp::iterative::IterativeEvaluation {
    let solver = IterativeSolver::new(x.nrows(), settings);
    log_marginal_likelihood_iterative(
        GpProblem::new(kernel, noise, x.as_ref(), y.as_ref()),
        with_gradient,
        &solver,
        || false,
    )
    .unwrap()
}

fn dense_and_iterative(
    kernel: &Kernel,
    noise: f64,
    x: &Mat<f64>,
    y: &Mat<f64>,
    settings: &IterativeSettings,
) -> (f64, Vec<f64>, f64, Vec<f64>, usize) {
    let dense =
        log_marginal_likelihood(GpProblem::new(kernel, noise, x.as_ref(), y.as_ref()), true)
            .unwrap();
    let it = iterative(kernel, noise, x, y, *settings, true);
    (
        dense.lml,
        dense.gradient.unwrap(),
        it.lml,
        it.gradient.unwrap(),
        it.iterations,
    )
}

fn cosine(a: &[f64], b: &[f64]) -> f64 {
    let dot: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let na: f64 = a.iter().map(|x| x * x).sum::<f64>().sqrt();
    let nb: f64 = b.iter().map(|x| x * x).sum::<f64>().sqrt();
    dot / (na * nb)
}

#[test]
fn the_iterative_likelihood_and_gradient_agree_with_the_dense_ones() {
    let (kernel, x, y) = problem(400, 7);
    let noise = 0.05;
    let settings = IterativeSettings {
        preconditioner_rank: 30,
        ..IterativeSettings::default()
    };
    let (lml, grad, it_lml, it_grad, iterations) =
        dense_and_iterative(&kernel, noise, &x, &y, &settings);
    let c = cosine(&grad, &it_grad);
    println!(
        "n = 400: dense {lml:.3}, iterative {it_lml:.3} after {iterations} CG iterations; gradient cosine {c:.5}"
    );
    // Over 50 probe seeds the mean estimate is within 3 standard errors.
    let estimates: Vec<f64> = (0..50)
        .map(|seed| {
            let s = IterativeSettings {
                seed,
                probes: 4,
                ..settings
            };
            iterative(&kernel, noise, &x, &y, s, false).lml
        })
        .collect();
    let mean = estimates.iter().sum::<f64>() / 50.0;
    let se =
        (estimates.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / 49.0).sqrt() / 50f64.sqrt();
    println!("50 seeds of 4 probes: mean {mean:.3} ± {se:.3} against {lml:.3}");
    assert!((mean - lml).abs() < 3.0 * se, "{mean} ± {se} against {lml}");
    // One estimate of 16 probes is within 4 of its standard deviations
    // (that of 4 probes, halved), and its gradient points the dense one's
    // way (this is not an optimum: the gradient is far from zero).
    let sd16 = se * 50f64.sqrt() / 2.0;
    assert!(
        (lml - it_lml).abs() < 4.0 * sd16,
        "{lml} vs {it_lml} (sd {sd16})"
    );
    assert!(c > 0.99, "cosine {c}");
}

#[test]
fn the_preconditioner_cuts_the_iterations_and_threads_do_not_change_a_bit() {
    let (kernel, x, y) = problem(300, 8);
    let run = |rank| {
        let s = IterativeSettings {
            preconditioner_rank: rank,
            ..IterativeSettings::default()
        };
        iterative(&kernel, 0.01, &x, &y, s, true)
    };
    let (none, some) = (run(0), run(40));
    println!(
        "CG iterations: {} without a preconditioner, {} with rank 40",
        none.iterations, some.iterations
    );
    assert!(some.iterations * 2 < none.iterations);
    let one = faer::get_global_parallelism();
    faer::set_global_parallelism(faer::Par::Seq);
    let seq = run(40);
    faer::set_global_parallelism(faer::Par::rayon(2));
    let two = run(40);
    faer::set_global_parallelism(one);
    assert_eq!(seq, two);
}

#[test]
fn a_fit_by_iterative_solves_lands_where_the_dense_fit_does() {
    use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams, Solver};
    use gpodo_traits::ResidualRegressor;
    // Noisy targets (as full-rate residuals are): few CG iterations.
    let mut r = rng(9);
    let x = inputs(&mut r, 300, 3);
    let y = targets(&mut r, &x, 0.5);
    let data = dataset(&x, &y);
    let fit = |solver| {
        let mut gp = ExactGp::new(ExactGpParams {
            solver,
            ..ExactGpParams::default()
        })
        .unwrap();
        let report = gp.fit(&data).unwrap();
        (report.objective.unwrap(), gp)
    };
    let (dense, dense_gp) = fit(Solver::Dense);
    let (iterative, iterative_gp) = fit(Solver::Iterative);
    println!("dense optimum {dense:.3}, iterative {iterative:.3}");
    // From a 100-row subset's dense optimum: the same optimum.
    let mut from_subset = ExactGp::new(ExactGpParams {
        solver: Solver::Iterative,
        iterative: IterativeSettings {
            subset_rows: 100,
            ..IterativeSettings::default()
        },
        ..ExactGpParams::default()
    })
    .unwrap();
    let report = from_subset.fit(&data).unwrap();
    let lml = report.objective.unwrap();
    println!("from the subset's optimum {lml:.3}");
    assert!((dense - lml).abs() < 1.0, "{dense} vs {lml}");
    assert!(
        report
            .starts
            .iter()
            .all(|s| s.label.contains("100-row subset")),
        "{:?}",
        report.starts
    );
    // The report's likelihood is the exact one at the learned
    // hyperparameters (the posterior's factor).
    assert!((dense - iterative).abs() < 1.0, "{dense} vs {iterative}");
    let q = sample_matrix(&inputs(&mut r, 20, 3));
    let (a, b) = (
        dense_gp.predict(&q).unwrap(),
        iterative_gp.predict(&q).unwrap(),
    );
    let worst = a
        .mean
        .as_slice()
        .iter()
        .zip(b.mean.as_slice())
        .map(|(u, v)| (u - v).abs())
        .fold(0.0, f64::max);
    assert!(worst < 0.05, "predictions differ by {worst}");
}

#[test]
fn a_stop_asked_between_cg_iterations_stops_the_fit() {
    use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams, Solver};
    use gpodo_traits::{FitProgress, ResidualRegressor};
    use std::sync::Arc;
    use std::sync::atomic::{AtomicUsize, Ordering};
    /// Never stops at an optimiser iteration; asks to stop after `after`
    /// questions between CG iterations.
    struct StopInside {
        asked: AtomicUsize,
        after: usize,
    }
    impl FitProgress for StopInside {
        fn iteration(&self, _: usize, _: u64, _: f64) -> std::ops::ControlFlow<()> {
            std::ops::ControlFlow::Continue(())
        }
        fn stop_requested(&self) -> bool {
            self.asked.fetch_add(1, Ordering::SeqCst) >= self.after
        }
    }
    let mut r = rng(10);
    let x = inputs(&mut r, 200, 3);
    let y = targets(&mut r, &x, 0.5);
    let data = dataset(&x, &y);
    let progress = Arc::new(StopInside {
        asked: AtomicUsize::new(0),
        after: 25,
    });
    let mut gp = ExactGp::new(ExactGpParams {
        solver: Solver::Iterative,
        ..ExactGpParams::default()
    })
    .unwrap();
    gp.set_progress(Some(progress.clone()));
    let e = gp.fit(&data).unwrap_err();
    assert!(e.to_string().contains("stopped"), "{e}");
    assert!(gp.state().is_none(), "nothing half-fitted");
    // It was asked from inside the evaluations: more than once per
    // optimiser iteration, and it stopped soon after.
    assert!(progress.asked.load(Ordering::SeqCst) > 25);
}

/// The first `n` rows of the authors' ExoTeR table (`shared/data`, beside
/// the workspace), inputs and targets z-scored on those rows; `None`, with a
/// message, when the table is not there.
fn exoter(n: usize) -> Option<(Mat<f64>, Mat<f64>)> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/data/exoter_gp_train_1s.csv"
    );
    if !std::path::Path::new(path).exists() {
        eprintln!("skipped: the ExoTeR table is not at {path}");
        return None;
    }
    let mut reader =
        csv::Reader::from_path(path).unwrap_or_else(|e| panic!("the ExoTeR table at {path}: {e}"));
    let rows: Vec<Vec<f64>> = reader
        .records()
        .take(n)
        .map(|r| r.unwrap().iter().map(|v| v.parse().unwrap()).collect())
        .collect();
    let width = rows[0].len();
    let z = Mat::from_fn(n, width, |i, j| {
        let column = rows.iter().map(|r| r[j]);
        let mean = column.clone().sum::<f64>() / n as f64;
        let sd = (column.map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
        if sd > 1e-12 {
            (rows[i][j] - mean) / sd
        } else {
            0.0
        }
    });
    Some((
        z.as_ref().subcols(0, width - 3).to_owned(),
        z.as_ref().subcols(width - 3, 3).to_owned(),
    ))
}

/// The RBF-ARD kernel at the start policy's lengthscale √d.
fn rbf_at_start(d: usize) -> Kernel {
    gpodo_regressors::kernels::KernelExpr::Leaf(gpodo_regressors::kernels::LeafName::Rbf)
        .build(d, &gpodo_regressors::kernels::KernelInit::default())
}

#[test]
fn on_exoter_inputs_the_estimate_is_within_half_a_nat_at_large_noise_and_knows_its_error_at_small()
{
    let Some((x, y)) = exoter(2000) else {
        return;
    };
    let kernel = rbf_at_start(x.ncols());
    // The noise the simulated full-rate rows learn (0.9 of the targets'
    // variance), where the iterative path is the one `auto` takes. Its
    // spread is Hutchinson's, `2‖log(P^{-1/2} K_y P^{-1/2})‖²_F / t`: from
    // the exact spectrum here, a standard error of 1.92 nats at the default
    // rank 300 and 0.03 at rank 1000 (bench/iterative.md).
    let settings = IterativeSettings {
        preconditioner_rank: 1000,
        ..IterativeSettings::default()
    };
    let (lml, grad, it_lml, it_grad, iterations) =
        dense_and_iterative(&kernel, 0.9, &x, &y, &settings);
    let c = cosine(&grad, &it_grad);
    eprintln!(
        "ExoTeR, n = 2000, noise 0.9, rank 1000: dense {lml:.3}, iterative {it_lml:.3} ({iterations} CG iterations), gradient cosine {c:.5}"
    );
    assert!((it_lml - lml).abs() < 0.5, "{it_lml} against {lml}");
    assert!(c > 0.99, "cosine {c}");
    let settings = IterativeSettings::default();
    let default = iterative(&kernel, 0.9, &x, &y, settings, false);
    eprintln!(
        "ExoTeR, n = 2000, noise 0.9, rank 300: {:+.3} ± {:.3}",
        default.lml - lml,
        default.lml_standard_error
    );
    let se = default.lml_standard_error;
    assert!(se > 0.5 && se < 4.0, "standard error {se}");
    assert!((default.lml - lml).abs() < 4.0 * se);
    // At the 1-s table's own noise (0.0216) Hutchinson's estimator spreads
    // by nats: each estimate says so, and its standard error is the
    // seeds' spread.
    let dense = log_marginal_likelihood(
        GpProblem::new(&kernel, 0.0216, x.as_ref(), y.as_ref()),
        false,
    )
    .unwrap()
    .lml;
    let seeds = 20;
    let runs: Vec<(f64, f64)> = (0..seeds)
        .map(|seed| {
            let s = IterativeSettings { seed, ..settings };
            let e = iterative(&kernel, 0.0216, &x, &y, s, false);
            (e.lml, e.lml_standard_error)
        })
        .collect();
    let count = seeds as f64;
    let mean = runs.iter().map(|r| r.0).sum::<f64>() / count;
    let spread = (runs.iter().map(|r| (r.0 - mean).powi(2)).sum::<f64>() / (count - 1.0)).sqrt();
    let said = runs.iter().map(|r| r.1).sum::<f64>() / count;
    eprintln!(
        "ExoTeR, n = 2000, noise 0.0216: dense {dense:.3}; estimates {:?}; their spread {spread:.2}, their mean standard error {said:.2}",
        runs.iter()
            .map(|r| format!("{:+.2} ± {:.2}", r.0 - dense, r.1))
            .collect::<Vec<_>>()
    );
    assert!(said > 1.0, "a standard error of {said} nats");
    for (estimate, se) in &runs {
        assert!(
            (estimate - dense).abs() < 4.0 * se,
            "{estimate} ± {se} against {dense}"
        );
    }
    assert!(
        spread > 0.4 * said && spread < 2.5 * said,
        "spread {spread} against standard error {said}"
    );
}

#[test]
fn preconditioning_cuts_the_cg_iterations_on_the_exoter_table() {
    let Some((x, y)) = exoter(1869) else {
        return;
    };
    // The start policy's lengthscale √d, at the small noise the ExoTeR fit
    // learns (0.0216 of the standardised targets' variance).
    let kernel = rbf_at_start(x.ncols());
    let iterations = |rank: usize| {
        let s = IterativeSettings {
            preconditioner_rank: rank,
            ..IterativeSettings::default()
        };
        iterative(&kernel, 0.0216, &x, &y, s, false).iterations
    };
    let (none, hundred, three_hundred) = (iterations(0), iterations(100), iterations(300));
    eprintln!(
        "CG iterations on ExoTeR: {none} without, {hundred} at rank 100, {three_hundred} at 300"
    );
    assert!(
        hundred * 2 < none && three_hundred < hundred,
        "CG iterations: {none} without a preconditioner, {hundred} at rank 100, {three_hundred} at rank 300"
    );
}

#[test]
fn solver_auto_goes_dense_at_small_noise_and_iterative_at_large_noise_above_its_crossover() {
    use gpodo_regressors::exact_gp::optimize::maximize_lml;
    use gpodo_regressors::exact_gp::{ExactGpParams, Solver};
    use gpodo_regressors::hyperopt::ProgressSink;
    let n = Solver::AUTO_ITERATIVE_ABOVE_ROWS + 1;
    let mut r = rng(11);
    let x = inputs(&mut r, n, 2);
    let params = ExactGpParams {
        solver: Solver::Auto,
        iterative: IterativeSettings {
            subset_rows: 300,
            ..IterativeSettings::default()
        },
        ..ExactGpParams::default()
    };
    // A dense fit reports the exact likelihood at its optimum, to the bit;
    // an iterative one its estimate, off by at least the CG tolerance's
    // error (here the rank-300 preconditioner of a two-input kernel is
    // nearly exact, so by little more).
    let mut exact_gap = |noise: f64| {
        let y = targets(&mut r, &x, noise);
        let out = maximize_lml(
            x.as_ref(),
            y.as_ref(),
            &params,
            &ProgressSink::default(),
            None,
        )
        .unwrap();
        let exact = log_marginal_likelihood(
            GpProblem::new(&out.kernel, out.noise_variance, x.as_ref(), y.as_ref()),
            false,
        )
        .unwrap()
        .lml;
        println!(
            "noise sd {noise}: learned noise variance {:.4}, LML {:.4}, exact {exact:.4}",
            out.noise_variance, out.lml
        );
        assert!(
            out.starts
                .iter()
                .all(|s| s.label.contains("300-row subset")),
            "{:?}",
            out.starts
        );
        (out.lml - exact).abs()
    };
    let small = exact_gap(0.02);
    assert!(small < 1e-10, "small noise: dense expected, off by {small}");
    let large = exact_gap(1.0);
    assert!(
        large > 1e-9 && large < 5.0,
        "large noise: an iterative estimate expected, off by {large}"
    );
}

#[test]
fn the_krylov_variances_are_bounded_by_the_exact_ones_and_reach_them_at_full_rank() {
    use gpodo_regressors::exact_gp::iterative::love::KrylovVariance;
    let (kernel, x, _) = problem(300, 12);
    let noise = 0.05;
    let mut ky = kernel.gram(x.as_ref());
    for i in 0..300 {
        ky[(i, i)] += noise;
    }
    let apply = |v: MatRef<'_, f64>| ky.as_ref() * v;
    // Cross-covariances of 40 points near the training inputs.
    let mut r = rng(13);
    let xs = Mat::from_fn(40, x.ncols(), |i, j| {
        let e: f64 = StandardNormal.sample(&mut r);
        x[(i, j)] + 0.3 * e
    });
    let k_star = kernel.cross(x.as_ref(), xs.as_ref());
    let exact_factor = Cholesky::factor(ky.clone()).unwrap();
    let v = exact_factor.solve_lower(k_star.as_ref());
    let exact: Vec<f64> = (0..40).map(|j| v.col(j).squared_norm_l2()).collect();
    let mut worst_before = f64::INFINITY;
    for rank in [16, 48, 96, 300] {
        let basis = KrylovVariance::new(apply, 300, rank, 0).unwrap();
        assert_eq!(basis.rank(), rank);
        let approx = basis.explained(k_star.as_ref());
        let worst = exact
            .iter()
            .zip(&approx)
            .map(|(e, a)| {
                assert!(
                    a <= &(e * (1.0 + 1e-9)),
                    "rank {rank}: {a} above the exact {e}"
                );
                (e - a) / e
            })
            .fold(0.0, f64::max);
        println!("rank {rank}: the quadratic form short of the exact one by {worst:.2e} at most");
        assert!(
            worst <= worst_before,
            "rank {rank}: {worst} after {worst_before}"
        );
        worst_before = worst;
    }
    assert!(worst_before < 1e-8, "full rank: {worst_before}");
}

#[test]
fn an_iterative_posterior_predicts_as_the_dense_one_does_and_reloads_to_the_bit_at_any_thread_count()
 {
    use gpodo_regressors::exact_gp::posterior::Posterior;
    use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams, Solver};
    use gpodo_traits::{ResidualDataset, ResidualRegressor, SampleMatrix};
    let (kernel, x, y) = problem(500, 14);
    let noise = 0.5;
    let xs = x.as_ref().subrows(0, 100).to_owned() * faer::Scale(1.1);
    let dense = Posterior::new(kernel.clone(), noise, x.clone(), y.clone())
        .unwrap()
        .predict(xs.as_ref());
    let solver = IterativeSolver::new(500, IterativeSettings::default());
    let posterior =
        Posterior::iterative(kernel.clone(), noise, x.clone(), y.clone(), &solver, 256).unwrap();
    assert!(posterior.lml_standard_error.is_some());
    let iterative = posterior.predict(xs.as_ref());
    for i in 0..100 {
        for j in 0..y.ncols() {
            let gap = (iterative.mean[(i, j)] - dense.mean[(i, j)]).abs();
            assert!(gap < 1e-5, "mean {i},{j} off by {gap}");
        }
        let (a, b) = (
            iterative.latent_variance[i] + noise,
            dense.latent_variance[i] + noise,
        );
        // From above, and close: this random kernel's spectrum decays
        // slowly (on the simulated full-rate rows rank 256 is within 1e-6).
        assert!(
            a >= b * (1.0 - 1e-9) && a <= b * (1.0 + 5e-2),
            "variance {i}: {a} against the exact {b}"
        );
    }
    // A model conditioned by iterative solves is rebuilt from its saved
    // state by the same solves, to the bit.
    let to_rows = |m: &Mat<f64>| {
        SampleMatrix::from_row_major(
            m.nrows(),
            m.ncols(),
            (0..m.nrows())
                .flat_map(|i| (0..m.ncols()).map(move |j| (i, j)))
                .map(|(i, j)| m[(i, j)])
                .collect(),
        )
        .unwrap()
    };
    let data = ResidualDataset::new(
        to_rows(&x),
        to_rows(&y),
        (0..x.ncols()).map(|j| format!("x{j}")).collect(),
        (0..y.ncols()).map(|j| format!("y{j}")).collect(),
    )
    .unwrap();
    let mut gp = ExactGp::new(ExactGpParams {
        solver: Solver::Iterative,
        optimize: false,
        noise_variance: 0.5,
        ..ExactGpParams::default()
    })
    .unwrap();
    gp.fit(&data).unwrap();
    let reloaded = ExactGp::from_state(gp.state().unwrap().clone()).unwrap();
    let queries = to_rows(&xs);
    let (a, b) = (
        gp.predict(&queries).unwrap(),
        reloaded.predict(&queries).unwrap(),
    );
    assert_eq!(a, b);
}

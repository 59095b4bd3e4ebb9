//! Sparse GP specification: gradients of the VFE bound and the FITC
//! likelihood (hyperparameters, noise, inducing inputs) against finite
//! differences; with inducing points at the training points both reproduce
//! the exact GP; the VFE bound is a bound; learning, saving and loading.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use faer::Mat;
use gpodo_regressors::exact_gp::likelihood::log_marginal_likelihood;
use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams};
use gpodo_regressors::kernels::KernelExpr;
use gpodo_regressors::sparse_gp::bound::sparse_objective;
use gpodo_regressors::sparse_gp::{
    Approximation, InducingInit, InducingParams, SparseGp, SparseGpParams, SparseGpState,
};
use gpodo_regressors::{GpProblem, SparseProblem};
use gpodo_traits::{ResidualRegressor, SampleMatrix};
use support::*;

const METHODS: [Approximation; 2] = [Approximation::Vfe, Approximation::Fitc];

#[test]
fn objective_gradients_match_finite_differences() {
    let mut rng = rng(31);
    for expr in [
        "rbf",
        "matern52",
        "matern32",
        "rbf + linear",
        "rbf * linear",
        "rbf + white",
    ] {
        for method in METHODS {
            for outputs in [1, 3] {
                let (n, m, d) = (30, 7, 3);
                let x = inputs(&mut rng, n, d);
                let y = targets(&mut rng, &x, 0.1);
                let y = Mat::from_fn(n, outputs, |i, c| y[(i, c)]);
                let z = inputs(&mut rng, m, d);
                let kernel = random_kernel(&mut rng, expr, d);
                let noise = 0.07;
                let at = |k: &gpodo_regressors::Kernel, s: f64, z: &Mat<f64>| {
                    sparse_objective(
                        SparseProblem {
                            gp: GpProblem::new(k, s, x.as_ref(), y.as_ref()),
                            z: z.as_ref(),
                            approximation: method,
                            jitter: 1e-8,
                        },
                        false,
                        false,
                    )
                    .unwrap()
                    .value
                };
                let eval = sparse_objective(
                    SparseProblem {
                        gp: GpProblem::new(&kernel, noise, x.as_ref(), y.as_ref()),
                        z: z.as_ref(),
                        approximation: method,
                        jitter: 1e-8,
                    },
                    true,
                    true,
                )
                .unwrap();
                let analytic = eval.gradient.unwrap();
                let mut theta = kernel.log_params();
                theta.push(noise.ln());
                let h = 1e-5;
                for (k, a) in analytic.iter().enumerate() {
                    let value = |delta: f64| {
                        let mut t = theta.clone();
                        t[k] += delta;
                        let mut kern = kernel.clone();
                        kern.set_log_params(&t[..t.len() - 1]);
                        at(&kern, t[t.len() - 1].exp(), &z)
                    };
                    let fd = (value(h) - value(-h)) / (2.0 * h);
                    let err = rel_err(*a, fd, 1e-4);
                    assert!(
                        err < 1e-5,
                        "{expr} {method:?} p={outputs} θ{k}: {a} vs {fd} ({err:e})"
                    );
                }
                let dz = eval.inducing_gradient.unwrap();
                for i in 0..m {
                    for q in 0..d {
                        let value = |delta: f64| {
                            let mut zz = z.clone();
                            zz[(i, q)] += delta;
                            at(&kernel, noise, &zz)
                        };
                        let fd = (value(h) - value(-h)) / (2.0 * h);
                        let err = rel_err(dz[(i, q)], fd, 1e-4);
                        assert!(
                            err < 1e-5,
                            "{expr} {method:?} p={outputs} Z[{i},{q}]: {} vs {fd} ({err:e})",
                            dz[(i, q)]
                        );
                    }
                }
            }
        }
    }
}

fn fixed_sparse(expr: &str, method: Approximation, count: usize) -> SparseGpParams {
    SparseGpParams {
        kernel: KernelExpr::parse(expr).unwrap(),
        approximation: method,
        inducing: InducingParams {
            count,
            ..Default::default()
        },
        optimize: false,
        standardize: false,
        jitter: 0.0,
        ..Default::default()
    }
}

#[test]
fn inducing_points_at_the_training_points_reproduce_the_exact_gp() {
    let mut rng = rng(32);
    let (n, d) = (40, 2);
    let x = inputs(&mut rng, n, d);
    let y = targets(&mut rng, &x, 0.1);
    let kernel = random_kernel(&mut rng, "rbf + linear", d);
    let noise = 0.05;
    let exact = log_marginal_likelihood(
        GpProblem::new(&kernel, noise, x.as_ref(), y.as_ref()),
        false,
    )
    .unwrap()
    .lml;
    for method in METHODS {
        let sparse = sparse_objective(
            SparseProblem {
                gp: GpProblem::new(&kernel, noise, x.as_ref(), y.as_ref()),
                z: x.as_ref(),
                approximation: method,
                jitter: 0.0,
            },
            false,
            false,
        )
        .unwrap()
        .value;
        assert!(
            (sparse - exact).abs() < 1e-6,
            "{method:?}: {sparse} vs exact {exact}"
        );
    }

    // Predictions through the regressors, inducing points = all training rows.
    let data = dataset(&x, &y);
    let mut exact_gp = ExactGp::new(ExactGpParams {
        optimize: false,
        standardize: false,
        noise_variance: 0.05,
        ..ExactGpParams::with_kernel(KernelExpr::parse("rbf").unwrap())
    })
    .unwrap();
    exact_gp.fit(&data).unwrap();
    let queries = sample_matrix(&inputs(&mut rng, 15, d));
    let reference = exact_gp.predict_full(&queries).unwrap();
    for method in METHODS {
        let mut params = fixed_sparse("rbf", method, n);
        params.noise_variance = 0.05;
        let mut sparse = SparseGp::new(params).unwrap();
        let report = sparse.fit(&data).unwrap();
        let exact_lml: f64 = exact_gp.log_marginal_likelihoods().iter().sum();
        assert!(
            (report.objective.unwrap() - exact_lml).abs() < 1e-6,
            "{method:?}"
        );
        let got = sparse.predict_full(&queries).unwrap();
        for i in 0..15 {
            for c in 0..3 {
                let pairs = [
                    (got.mean.get(i, c), reference.mean.get(i, c)),
                    (
                        got.latent_variance.get(i, c),
                        reference.latent_variance.get(i, c),
                    ),
                    (got.variance.get(i, c), reference.variance.get(i, c)),
                ];
                for (a, b) in pairs {
                    assert!(
                        (a - b).abs() < 1e-6,
                        "{method:?} row {i} col {c}: {a} vs {b}"
                    );
                }
            }
        }
    }
}

#[test]
fn vfe_is_a_lower_bound_that_tightens_with_more_inducing_points() {
    let mut rng = rng(33);
    let (n, d) = (120, 2);
    let x = inputs(&mut rng, n, d);
    let y = targets(&mut rng, &x, 0.1);
    let kernel = random_kernel(&mut rng, "rbf", d);
    let exact =
        log_marginal_likelihood(GpProblem::new(&kernel, 0.05, x.as_ref(), y.as_ref()), false)
            .unwrap()
            .lml;
    let mut previous = f64::NEG_INFINITY;
    for m in [5, 20, 60, 120] {
        // Nested subsets: every m-th row set contains the previous one.
        let z = Mat::from_fn(m, d, |i, q| x[(i, q)]);
        let bound = sparse_objective(
            SparseProblem {
                gp: GpProblem::new(&kernel, 0.05, x.as_ref(), y.as_ref()),
                z: z.as_ref(),
                approximation: Approximation::Vfe,
                jitter: 0.0,
            },
            false,
            false,
        )
        .unwrap()
        .value;
        assert!(
            bound <= exact + 1e-8,
            "m={m}: bound {bound} above exact {exact}"
        );
        assert!(
            bound >= previous - 1e-8,
            "m={m}: bound fell from {previous} to {bound}"
        );
        previous = bound;
    }
    assert!((previous - exact).abs() < 1e-6);
}

fn sine_data(n: usize, seed: u64) -> (Mat<f64>, Mat<f64>) {
    let mut rng = rng(seed);
    let x = Mat::from_fn(n, 1, |i, _| -3.0 + 6.0 * i as f64 / (n - 1) as f64);
    let y = Mat::from_fn(n, 1, |i, _| {
        (2.0 * x[(i, 0)]).sin() + 0.1 * rand::Rng::random_range(&mut rng, -1.0..1.0)
    });
    (x, y)
}

#[test]
fn learns_a_sine_close_to_the_exact_gp_with_few_inducing_points() {
    let (x, y) = sine_data(400, 34);
    let data = dataset(&x, &y);
    let grid = Mat::from_fn(50, 1, |i, _| -2.9 + 5.8 * i as f64 / 49.0);
    let queries = sample_matrix(&grid);
    let truth: Vec<f64> = (0..50).map(|i| (2.0 * grid[(i, 0)]).sin()).collect();
    let rmse = |p: &SampleMatrix| {
        ((0..50)
            .map(|i| (p.get(i, 0) - truth[i]).powi(2))
            .sum::<f64>()
            / 50.0)
            .sqrt()
    };
    let mut exact = ExactGp::new(ExactGpParams::default()).unwrap();
    exact.fit(&data).unwrap();
    let exact_rmse = rmse(&exact.predict(&queries).unwrap().mean);
    for (method, init, fixed) in [
        (Approximation::Vfe, InducingInit::Kmeans, false),
        (Approximation::Vfe, InducingInit::RandomSubset, true),
        (Approximation::Fitc, InducingInit::Kmeans, false),
    ] {
        let mut sparse = SparseGp::new(SparseGpParams {
            approximation: method,
            inducing: InducingParams {
                count: 15,
                init,
                fixed,
                ..Default::default()
            },
            ..Default::default()
        })
        .unwrap();
        let report = sparse.fit(&data).unwrap();
        let p = sparse.predict(&queries).unwrap();
        let sparse_rmse = rmse(&p.mean);
        assert!(
            sparse_rmse < exact_rmse * 1.3 + 0.005,
            "{method:?} {init:?} fixed={fixed}: {sparse_rmse} vs exact {exact_rmse}"
        );
        assert!(report.evaluations.unwrap() > 1);
        assert!(p.variance.rows().all(|r| r[0] > 0.0 && r[0].is_finite()));
        // Far from the data the latent variance returns towards the prior.
        let far = sparse
            .predict_full(&SampleMatrix::from_rows(1, &[[10.0]]).unwrap())
            .unwrap();
        let near = sparse
            .predict_full(&SampleMatrix::from_rows(1, &[[0.0]]).unwrap())
            .unwrap();
        assert!(far.latent_variance.get(0, 0) > 10.0 * near.latent_variance.get(0, 0));
    }
}

#[test]
fn saved_state_predicts_the_same_without_the_data_and_fits_are_reproducible() {
    let mut rng = rng(35);
    let x = inputs(&mut rng, 200, 3);
    let y = targets(&mut rng, &x, 0.05);
    let data = dataset(&x, &y);
    let params = SparseGpParams {
        inducing: InducingParams {
            count: 12,
            ..Default::default()
        },
        hyperopt: gpodo_regressors::hyperopt::HyperoptParams {
            max_iters: 40,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut a = SparseGp::new(params.clone()).unwrap();
    a.fit(&data).unwrap();
    let mut b = SparseGp::new(params).unwrap();
    b.fit(&data).unwrap();
    let queries = sample_matrix(&inputs(&mut rng, 9, 3));
    let pa = a.predict(&queries).unwrap();
    assert_eq!(pa, b.predict(&queries).unwrap(), "same seed, same numbers");

    let json = serde_json::to_string(a.state().unwrap()).unwrap();
    let state: SparseGpState = serde_json::from_str(&json).unwrap();
    assert_eq!(state.inducing.nrows(), 12);
    let loaded = SparseGp::from_state(state).unwrap();
    let pl = loaded.predict(&queries).unwrap();
    for i in 0..9 {
        for c in 0..3 {
            assert!((pa.mean.get(i, c) - pl.mean.get(i, c)).abs() < 1e-12);
            assert!((pa.variance.get(i, c) - pl.variance.get(i, c)).abs() < 1e-12);
        }
    }
}

#[test]
fn bad_data_and_unfitted_use_are_errors() {
    let sparse = SparseGp::new(SparseGpParams::default()).unwrap();
    let q = SampleMatrix::from_rows(1, &[[0.0]]).unwrap();
    assert!(matches!(
        sparse.predict(&q),
        Err(gpodo_traits::Error::NotFitted { .. })
    ));
    let mut rng = rng(36);
    let x = inputs(&mut rng, 30, 2);
    let mut y = targets(&mut rng, &x, 0.1);
    y[(4, 1)] = f64::NAN;
    let mut sparse = SparseGp::new(SparseGpParams::default()).unwrap();
    let err = sparse.fit(&dataset(&x, &y)).unwrap_err().to_string();
    assert!(err.contains("row 4, column 1"), "{err}");
    y[(4, 1)] = 0.0;
    sparse.fit(&dataset(&x, &y)).unwrap();
    assert!(matches!(
        sparse.predict(&q),
        Err(gpodo_traits::Error::DimensionMismatch { .. })
    ));
    let bad = SparseGpParams {
        jitter: -1.0,
        ..Default::default()
    };
    assert!(
        SparseGp::new(bad)
            .unwrap_err()
            .to_string()
            .contains("jitter")
    );
}

//! ILGR specification: fitting a 1-D function, predictive variance near and
//! far from the data, forgetting under drift, model creation and pruning,
//! the closed form of a single global model, parameters, errors,
//! determinism, a 28-input case and the per-sample cost.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::time::Instant;

use gpodo_regressors::ilgr::{GammaPrior, Ilgr, IlgrParams, IlgrState};
use gpodo_regressors::{RegressorError, RegressorSpec};
use gpodo_traits::{Error, ResidualDataset, ResidualRegressor, SampleMatrix};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// `n` samples of `f(x) + N(0, noise²)` with `x ~ U[lo, hi]`.
fn dataset_1d(
    rng: &mut ChaCha8Rng,
    n: usize,
    [lo, hi]: [f64; 2],
    noise: f64,
    f: impl Fn(f64) -> f64,
) -> ResidualDataset {
    let normal = Normal::new(0.0, noise).unwrap();
    let x: Vec<f64> = (0..n).map(|_| rng.random_range(lo..hi)).collect();
    let y: Vec<f64> = x.iter().map(|&v| f(v) + normal.sample(rng)).collect();
    ResidualDataset::new(
        SampleMatrix::from_row_major(n, 1, x).unwrap(),
        SampleMatrix::from_row_major(n, 1, y).unwrap(),
        vec!["x".into()],
        vec!["y".into()],
    )
    .unwrap()
}

fn grid(lo: f64, hi: f64, n: usize) -> SampleMatrix {
    let x: Vec<f64> = (0..n)
        .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
        .collect();
    SampleMatrix::from_row_major(n, 1, x).unwrap()
}

fn rmse_against(model: &Ilgr, x: &SampleMatrix, f: impl Fn(f64) -> f64) -> f64 {
    let p = model.predict(x).unwrap();
    let sse: f64 = (0..x.nrows())
        .map(|i| (p.mean.get(i, 0) - f(x.get(i, 0))).powi(2))
        .sum();
    (sse / x.nrows() as f64).sqrt()
}

fn sine(x: f64) -> f64 {
    (2.0 * x).sin()
}

/// The sine's settings: a single fast-varying input wants narrower models,
/// adapted faster, than the default.
fn sine_params() -> IlgrParams {
    IlgrParams {
        init_lengthscale: 0.5,
        lengthscale_learning_rate: 1e-3,
        ..IlgrParams::default()
    }
}

fn fitted_sine(params: IlgrParams) -> Ilgr {
    let data = dataset_1d(&mut rng(1), 3000, [-3.0, 3.0], 0.05, sine);
    let mut model = Ilgr::new(params).unwrap();
    model.fit(&data).unwrap();
    model
}

#[test]
fn one_pass_fits_a_sine_inside_the_data() {
    let model = fitted_sine(sine_params());
    let rmse = rmse_against(&model, &grid(-2.8, 2.8, 200), sine);
    println!(
        "sine, 1 pass: RMSE {rmse:.4}, {} local models",
        model.n_local_models()
    );
    assert!(rmse < 0.08, "RMSE {rmse}");
    let model = fitted_sine(IlgrParams {
        passes: 3,
        ..sine_params()
    });
    let rmse3 = rmse_against(&model, &grid(-2.8, 2.8, 200), sine);
    println!("sine, 3 passes: RMSE {rmse3:.4}");
    assert!(rmse3 < 0.05, "RMSE {rmse3}");
}

#[test]
fn variance_is_small_near_the_data_and_grows_away_from_it() {
    let model = fitted_sine(sine_params());
    let at = [0.0, 2.0, 3.2, 3.4, 3.6, 3.8, 4.5, 6.0, 8.0];
    let x = SampleMatrix::from_row_major(at.len(), 1, at.to_vec()).unwrap();
    let v = model.predict(&x).unwrap().variance.column(0);
    println!("variance at x = {at:?}: {v:.4?}");
    // Inside the data: a few times the noise variance 0.05² = 2.5e-3 (the
    // one-pass noise estimate is conservative).
    assert!(v[0] < 1e-2 && v[1] < 1e-2, "{v:?}");
    assert!(v[0] > 2.5e-3 && v[1] > 2.5e-3, "{v:?}");
    // Leaving the data (x ≤ 3): growing with the distance ...
    for i in 2..7 {
        assert!(v[i] > v[i - 1], "{v:?}");
    }
    // ... to the prior variance of the targets (≈ 0.5) far away.
    let target_variance = 0.5;
    assert!((v[7] - target_variance).abs() < 0.1, "{v:?}");
    assert!(v[8] >= v[7] * (1.0 - 1e-9), "{v:?}");
}

/// Online on `f1` then on `f2` over the same region; the error against `f2`.
fn drift_error(forgetting: f64) -> f64 {
    let f1 = sine;
    let f2 = |x: f64| (2.0 * x - 1.0).sin() + 0.3;
    let mut model = Ilgr::new(IlgrParams {
        forgetting,
        target_scale: 1.0,
        ..sine_params()
    })
    .unwrap();
    let mut r = rng(3);
    let normal = Normal::new(0.0, 0.05).unwrap();
    for f in [&f1 as &dyn Fn(f64) -> f64, &f2] {
        for _ in 0..4000 {
            let x = r.random_range(-3.0..3.0);
            model.update(&[x], &[f(x) + normal.sample(&mut r)]).unwrap();
        }
    }
    rmse_against(&model, &grid(-2.8, 2.8, 200), f2)
}

#[test]
fn forgetting_tracks_a_drifting_function() {
    let tracked = drift_error(0.99);
    let stuck = drift_error(1.0);
    println!("drift: RMSE to f2 with κ = 0.99: {tracked:.4}, with κ = 1: {stuck:.4}");
    assert!(tracked < 0.1, "κ = 0.99: {tracked}");
    assert!(stuck > 2.0 * tracked, "κ = 1: {stuck}, κ = 0.99: {tracked}");
}

#[test]
fn a_model_is_created_only_where_no_activation_reaches_w_gen() {
    // Models narrow enough that the square needs several of them.
    let params = IlgrParams {
        init_lengthscale: 1.0,
        prune_precision: None,
        lengthscale_learning_rate: 0.0,
        ..IlgrParams::default()
    };
    let mut model = Ilgr::new(params.clone()).unwrap();
    let mut r = rng(4);
    for _ in 0..500 {
        let x = [r.random_range(-5.0..5.0), r.random_range(-5.0..5.0)];
        let before = model.n_local_models();
        let max_activation = if before == 0 {
            0.0
        } else {
            model
                .activations(&x)
                .unwrap()
                .into_iter()
                .fold(0.0, f64::max)
        };
        model.update(&x, &[x[0].sin()]).unwrap();
        let created = model.n_local_models() - before;
        assert_eq!(created, usize::from(max_activation < params.w_gen));
        if created == 1 {
            // The new model is centred on the sample.
            let a = model.activations(&x).unwrap();
            assert_eq!(*a.last().unwrap(), 1.0);
        }
    }
    assert!(model.n_local_models() > 5);
    assert_eq!(model.models_created() as usize, model.n_local_models());
}

#[test]
fn the_number_of_models_is_bounded_by_max_models() {
    let mut model = Ilgr::new(IlgrParams {
        max_models: 7,
        ..IlgrParams::default()
    })
    .unwrap();
    for i in 0..100 {
        // Far apart: each sample is outside every existing model.
        let x = 10.0 * i as f64;
        model.update(&[x], &[0.01]).unwrap();
        assert!(model.n_local_models() <= 7);
    }
    assert_eq!(model.n_local_models(), 7);
    // A sample far from all models still predicts (the unexplored prior).
    let mut mean = [0.0];
    let mut var = [0.0];
    model.predict_row(&[-100.0], &mut mean, &mut var).unwrap();
    assert!(mean[0].abs() < 1e-12 && var[0] > 0.0);
}

#[test]
fn pruning_removes_a_model_whose_precisions_diverge() {
    // A constant target leaves the models nothing to explain: the ARD
    // precisions of their weights grow without bound.
    let params = IlgrParams {
        target_scale: 1.0,
        ..IlgrParams::default()
    };
    let mut model = Ilgr::new(params.clone()).unwrap();
    let mut r = rng(5);
    let mut max_alpha_seen = 0.0f64;
    for _ in 0..400 {
        let x = r.random_range(-1.0..1.0);
        model.update(&[x], &[0.0]).unwrap();
        if let Some(state) = model.state() {
            for m in &state.models {
                max_alpha_seen = max_alpha_seen.max(m.posterior.ard.min());
            }
        }
    }
    println!(
        "zero target: {} models created, {} pruned, {} left",
        model.models_created(),
        model.models_pruned(),
        model.n_local_models()
    );
    assert!(model.models_pruned() >= 1);
    assert_eq!(
        model.models_created() - model.models_pruned(),
        model.n_local_models() as u64
    );
    assert!(max_alpha_seen > params.prune_precision.unwrap() / 10.0);
    // With the same data and no pruning, the model stays.
    let mut kept = Ilgr::new(IlgrParams {
        prune_precision: None,
        ..params
    })
    .unwrap();
    for _ in 0..400 {
        let x = r.random_range(-1.0..1.0);
        kept.update(&[x], &[0.0]).unwrap();
    }
    assert_eq!(kept.models_pruned(), 0);
    assert!(kept.n_local_models() >= 1);
    // A target with structure keeps its models.
    let informative = fitted_sine(sine_params());
    assert!(informative.n_local_models() > 3);
}

#[test]
fn a_single_global_model_is_bayesian_linear_regression() {
    // Activation 1 everywhere (huge lengthscale), no forgetting, no
    // lengthscale adaptation, precisions pinned by near-degenerate priors,
    // no output noise: the weights are Bayesian linear regression on
    // x̃ = [x − c, 1] with noise precision β and prior precisions α.
    let (beta, alpha) = (40.0, 0.5);
    let pinned = |mean: f64| GammaPrior::new(1e14, 1e14 / mean);
    let params = IlgrParams {
        init_lengthscale: 1e7,
        lengthscale_bounds: [1e-2, 1e8],
        lengthscale_learning_rate: 0.0,
        forgetting: 1.0,
        prune_precision: None,
        weight_precision_prior: pinned(alpha),
        model_noise_precision_prior: pinned(beta),
        output_noise_precision_prior: pinned(1e14),
        unexplored_variance: 0.0,
        target_scale: 1.0,
        ..IlgrParams::default()
    };
    let mut model = Ilgr::new(params).unwrap();
    let mut r = rng(6);
    let xs: Vec<[f64; 2]> = (0..50)
        .map(|_| [r.random_range(-2.0..2.0), r.random_range(-2.0..2.0)])
        .collect();
    let ys: Vec<f64> = xs
        .iter()
        .map(|x| 0.8 * x[0] - 0.4 * x[1] + 0.2 + 0.1 * r.random_range(-1.0..1.0))
        .collect();
    for (x, y) in xs.iter().zip(&ys) {
        model.update(x, &[*y]).unwrap();
    }
    let state = model.state().unwrap();
    assert_eq!(state.models.len(), 1);
    let m = &state.models[0];
    let c = &m.centre;
    let design = DMatrix::from_fn(
        xs.len(),
        3,
        |i, j| if j < 2 { xs[i][j] - c[j] } else { 1.0 },
    );
    let lhs = design.transpose() * &design * beta + DMatrix::identity(3, 3) * alpha;
    let rhs = design.transpose() * DVector::from_column_slice(&ys) * beta;
    let w = lhs.lu().solve(&rhs).unwrap();
    let mean = m.posterior.mean.column(0);
    let diff = (mean - &w).amax();
    println!("closed form: |μ_w − w_BLR|∞ = {diff:.2e}");
    assert!(diff < 1e-8, "{mean} vs {w}");
}

#[test]
fn params_have_defaults_and_reject_unknown_fields_and_bad_values() {
    let p: IlgrParams = serde_json::from_str("{}").unwrap();
    assert_eq!(p, IlgrParams::default());
    assert_eq!(p.forgetting, 0.999);
    assert_eq!(p.max_models, 200);
    assert_eq!(p.passes, 1);
    assert_eq!(p.prune_precision, Some(1e4));
    let p: IlgrParams = serde_json::from_str(
        r#"{"prune_precision": null, "weight_precision_prior": {"shape": 2, "rate": 1}}"#,
    )
    .unwrap();
    assert_eq!(p.prune_precision, None);
    assert_eq!(p.weight_precision_prior, GammaPrior::new(2.0, 1.0));
    let err = serde_json::from_str::<IlgrParams>(r#"{"forgeting": 0.99}"#).unwrap_err();
    assert!(err.to_string().contains("forgeting"), "{err}");
    let err = serde_json::from_str::<IlgrParams>(
        r#"{"weight_precision_prior": {"shape": 1, "scale": 1}}"#,
    )
    .unwrap_err();
    assert!(err.to_string().contains("scale"), "{err}");
    let bad = [
        (
            "w_gen",
            IlgrParams {
                w_gen: 1.0,
                ..IlgrParams::default()
            },
        ),
        (
            "forgetting",
            IlgrParams {
                forgetting: 0.0,
                ..IlgrParams::default()
            },
        ),
        (
            "init_lengthscale",
            IlgrParams {
                init_lengthscale: -1.0,
                ..IlgrParams::default()
            },
        ),
        (
            "lengthscale_bounds",
            IlgrParams {
                lengthscale_bounds: [2.0, 1.0],
                ..IlgrParams::default()
            },
        ),
        (
            "lengthscale_learning_rate",
            IlgrParams {
                lengthscale_learning_rate: f64::NAN,
                ..IlgrParams::default()
            },
        ),
        (
            "update_cutoff",
            IlgrParams {
                update_cutoff: 0.5,
                ..IlgrParams::default()
            },
        ),
        (
            "max_models",
            IlgrParams {
                max_models: 0,
                ..IlgrParams::default()
            },
        ),
        (
            "prune_precision",
            IlgrParams {
                prune_precision: Some(-1.0),
                ..IlgrParams::default()
            },
        ),
        (
            "refresh_every",
            IlgrParams {
                refresh_every: 0,
                ..IlgrParams::default()
            },
        ),
        (
            "model_noise_precision_prior",
            IlgrParams {
                model_noise_precision_prior: GammaPrior::new(0.0, 1.0),
                ..IlgrParams::default()
            },
        ),
        (
            "unexplored_variance",
            IlgrParams {
                unexplored_variance: -1.0,
                ..IlgrParams::default()
            },
        ),
        (
            "passes",
            IlgrParams {
                passes: 0,
                ..IlgrParams::default()
            },
        ),
        (
            "target_scale",
            IlgrParams {
                target_scale: 0.0,
                ..IlgrParams::default()
            },
        ),
    ];
    for (field, p) in bad {
        match p.check() {
            Err(RegressorError::InvalidSpec {
                regressor,
                field: f,
                ..
            }) => {
                assert_eq!(regressor, "ilgr");
                assert_eq!(f, field);
            }
            other => panic!("{field}: {other:?}"),
        }
        assert!(Ilgr::new(p).is_err());
    }
    let spec: RegressorSpec = serde_json::from_str(r#"{"kind": "ilgr", "passes": 2}"#).unwrap();
    assert!(spec.build().is_ok());
}

#[test]
fn online_use_without_fit_and_errors() {
    let mut model = Ilgr::new(IlgrParams::default()).unwrap();
    let x = SampleMatrix::from_row_major(1, 2, vec![0.1, 0.2]).unwrap();
    assert!(matches!(model.predict(&x), Err(Error::NotFitted { .. })));
    let (mut mean, mut var) = ([0.0; 3], [0.0; 3]);
    assert!(matches!(
        model.predict_row(&[0.1, 0.2], &mut mean, &mut var),
        Err(Error::NotFitted { .. })
    ));
    assert!(model.supports_online_update());
    // Residual-sized targets (m/s), as on the rover.
    let mut r = rng(7);
    for _ in 0..300 {
        let xi = [r.random_range(-1.0..1.0), r.random_range(-1.0..1.0)];
        let y = [0.005 * xi[0], -0.003 * xi[1], 0.002];
        model.update(&xi, &y).unwrap();
    }
    let p = model.predict(&x).unwrap();
    assert!((p.mean.get(0, 0) - 0.0005).abs() < 5e-4, "{:?}", p.mean);
    assert!((p.mean.get(0, 2) - 0.002).abs() < 5e-4, "{:?}", p.mean);
    assert!(
        p.variance
            .as_slice()
            .iter()
            .all(|v| v.is_finite() && *v > 0.0)
    );
    // Wrong widths.
    assert!(matches!(
        model.predict(&SampleMatrix::zeros(1, 3)),
        Err(Error::DimensionMismatch {
            expected: 2,
            found: 3,
            ..
        })
    ));
    assert!(matches!(
        model.update(&[0.0; 3], &[0.0; 3]),
        Err(Error::DimensionMismatch { .. })
    ));
    assert!(matches!(
        model.update(&[0.0; 2], &[0.0; 2]),
        Err(Error::DimensionMismatch { .. })
    ));
    assert!(matches!(
        model.predict_row(&[0.0; 2], &mut [0.0; 2], &mut var),
        Err(Error::DimensionMismatch { .. })
    ));
    // Non-finite values are errors and leave the model untouched.
    let before = model.state().unwrap().clone();
    assert!(matches!(
        model.update(&[f64::NAN, 0.0], &[0.0; 3]),
        Err(Error::InvalidInput(_))
    ));
    assert!(matches!(
        model.update(&[0.0, 0.0], &[0.0, f64::INFINITY, 0.0]),
        Err(Error::InvalidInput(_))
    ));
    assert_eq!(model.state().unwrap(), &before);
    let nan = SampleMatrix::from_row_major(1, 2, vec![0.0, f64::NAN]).unwrap();
    assert!(matches!(model.predict(&nan), Err(Error::InvalidInput(_))));
    // A batch with a non-finite value is rejected by fit.
    let bad = ResidualDataset::new(
        nan,
        SampleMatrix::zeros(1, 3),
        vec!["a".into(), "b".into()],
        vec!["x".into(), "y".into(), "z".into()],
    )
    .unwrap();
    assert!(model.fit(&bad).is_err());
}

#[test]
fn same_seed_same_predictions_and_the_state_round_trips() {
    let params = IlgrParams {
        passes: 2,
        seed: 11,
        ..sine_params()
    };
    let a = fitted_sine(params.clone());
    let b = fitted_sine(params.clone());
    let x = grid(-3.0, 3.0, 50);
    assert_eq!(a.predict(&x).unwrap(), b.predict(&x).unwrap());
    let c = fitted_sine(IlgrParams { seed: 12, ..params });
    assert_ne!(a.predict(&x).unwrap(), c.predict(&x).unwrap());
    let json = serde_json::to_string(a.state().unwrap()).unwrap();
    let state: IlgrState = serde_json::from_str(&json).unwrap();
    let restored = Ilgr::from_state(state).unwrap();
    let (pa, pr) = (a.predict(&x).unwrap(), restored.predict(&x).unwrap());
    for (u, v) in pa.mean.as_slice().iter().zip(pr.mean.as_slice()) {
        assert!((u - v).abs() < 1e-12);
    }
}

#[test]
fn ilgr_is_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<Ilgr>();
    check::<IlgrState>();
}

/// `n` standard-normal 28-input samples; the target depends on 3 inputs.
fn dataset_28(rng: &mut ChaCha8Rng, n: usize) -> ResidualDataset {
    let normal = Normal::new(0.0, 1.0).unwrap();
    let d = 28;
    let x: Vec<f64> = (0..n * d).map(|_| normal.sample(rng)).collect();
    let y: Vec<f64> = x
        .chunks(d)
        .map(|r| (r[0]).sin() + 0.5 * r[5] - 0.3 * r[11] * r[11] + 0.1 * normal.sample(rng))
        .collect();
    ResidualDataset::new(
        SampleMatrix::from_row_major(n, d, x).unwrap(),
        SampleMatrix::from_row_major(n, 1, y).unwrap(),
        (0..d).map(|i| format!("x{i}")).collect(),
        vec!["y".into()],
    )
    .unwrap()
}

#[test]
fn one_pass_on_28_inputs_beats_predicting_zero() {
    let mut r = rng(8);
    let train = dataset_28(&mut r, 4000);
    let test = dataset_28(&mut r, 1000);
    let mut model = Ilgr::new(IlgrParams::default()).unwrap();
    let start = Instant::now();
    model.fit(&train).unwrap();
    let fit_secs = start.elapsed().as_secs_f64();
    let p = model.predict(&test.inputs).unwrap();
    let y = test.targets.column(0);
    let n = y.len() as f64;
    let rmse = (y
        .iter()
        .enumerate()
        .map(|(i, v)| (v - p.mean.get(i, 0)).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    let rmse_zero = (y.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
    println!(
        "d = 28: RMSE {rmse:.4} vs zero {rmse_zero:.4}, {} models, fit {fit_secs:.3} s",
        model.n_local_models()
    );
    assert!(rmse < 0.75 * rmse_zero, "{rmse} vs {rmse_zero}");
}

/// Per-sample cost of `update` + one-row `predict_row` at d = 28, 3
/// outputs. `cargo test --release -p gpodo-regressors --test ilgr --
/// --ignored --nocapture per_sample_cost`
#[test]
#[ignore = "timing; run in --release"]
fn per_sample_cost_at_d28() {
    let mut r = rng(9);
    let normal = Normal::new(0.0, 1.0).unwrap();
    let d = 28;
    // Default settings (few, broad models on isotropic inputs), then narrow
    // models that fill all 200 slots.
    for (init_lengthscale, max_active_models) in [(1.0, 4), (1.0, 8), (0.5, 4), (0.5, 8)] {
        let mut model = Ilgr::new(IlgrParams {
            init_lengthscale,
            max_active_models,
            target_scale: 1.0,
            ..IlgrParams::default()
        })
        .unwrap();
        let n = 20_000;
        let samples: Vec<(Vec<f64>, [f64; 3])> = (0..n)
            .map(|_| {
                let x: Vec<f64> = (0..d).map(|_| normal.sample(&mut r)).collect();
                let y = [x[0].sin(), 0.5 * x[1], x[2] * x[3]];
                (x, y)
            })
            .collect();
        let (mut mean, mut var) = ([0.0; 3], [0.0; 3]);
        let mut times = Vec::new();
        for chunk in samples.chunks(5000) {
            let start = Instant::now();
            for (x, y) in chunk {
                model.update(x, y).unwrap();
                model.predict_row(x, &mut mean, &mut var).unwrap();
            }
            times.push(start.elapsed().as_secs_f64() * 1e6 / chunk.len() as f64);
        }
        let active = model
            .activations(&samples[0].0)
            .unwrap()
            .iter()
            .filter(|&&a| a >= model.params().update_cutoff)
            .count();
        println!(
            "init_lengthscale {init_lengthscale}, max_active_models {max_active_models}: {} models, {active} above the cutoff at a sample; µs per update+predict by block of 5000: {times:.2?}",
            model.n_local_models()
        );
    }
}

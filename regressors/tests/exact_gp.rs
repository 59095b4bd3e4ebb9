//! Exact GP specification: the log marginal likelihood and its gradient,
//! closed-form cases, interpolation, hyperparameter learning, scaling,
//! saving and loading, and error handling.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use faer::Mat;
use gpodo_regressors::GpProblem;
use gpodo_regressors::exact_gp::likelihood::log_marginal_likelihood;
use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams, ExactGpState, OutputSharing};
use gpodo_regressors::hyperopt::{Bounds, HyperoptParams, Optimizer};
use gpodo_regressors::kernels::{KernelExpr, KernelInit};
use gpodo_traits::{ResidualRegressor, SampleMatrix};
use support::*;

fn fixed(expr: &str) -> ExactGpParams {
    ExactGpParams {
        optimize: false,
        standardize: false,
        ..ExactGpParams::with_kernel(KernelExpr::parse(expr).unwrap())
    }
}

#[test]
fn lml_gradient_matches_finite_differences() {
    let mut rng = rng(21);
    for expr in [
        "rbf",
        "matern52",
        "matern32",
        "linear",
        "rbf + linear",
        "matern52 + linear",
        "rbf * linear",
        "rbf + white",
    ] {
        for outputs in [1, 3] {
            let x = inputs(&mut rng, 25, 3);
            let y = targets(&mut rng, &x, 0.1);
            let y = Mat::from_fn(25, outputs, |i, c| y[(i, c)]);
            let kernel = random_kernel(&mut rng, expr, 3);
            let noise = 0.05;
            let eval = log_marginal_likelihood(
                GpProblem::new(&kernel, noise, x.as_ref(), y.as_ref()),
                true,
            )
            .unwrap();
            let analytic = eval.gradient.unwrap();
            let mut theta = kernel.log_params();
            theta.push(noise.ln());
            let lml_at = |t: &[f64]| {
                let mut k = kernel.clone();
                k.set_log_params(&t[..t.len() - 1]);
                log_marginal_likelihood(
                    GpProblem::new(&k, t[t.len() - 1].exp(), x.as_ref(), y.as_ref()),
                    false,
                )
                .unwrap()
                .lml
            };
            let h = 1e-5;
            for (k, a) in analytic.iter().enumerate() {
                let mut tp = theta.clone();
                tp[k] += h;
                let up = lml_at(&tp);
                tp[k] -= 2.0 * h;
                let down = lml_at(&tp);
                let fd = (up - down) / (2.0 * h);
                let err = rel_err(*a, fd, 1e-4);
                assert!(
                    err < 1e-5,
                    "{expr}, {outputs} outputs, parameter {k}: {a} vs {fd} ({err:e})"
                );
            }
        }
    }
}

#[test]
fn the_likelihood_and_its_gradient_are_bit_identical_whatever_the_thread_count() {
    let mut rng = rng(22);
    // Several column blocks and faer's parallel GEMM and triangular paths.
    let (n, d) = (700, 5);
    let x = inputs(&mut rng, n, d);
    let y = targets(&mut rng, &x, 0.1);
    let before = faer::get_global_parallelism();
    for expr in ["rbf", "matern52 + linear", "rbf * linear"] {
        let kernel = random_kernel(&mut rng, expr, d);
        let at = |par: faer::Par| {
            faer::set_global_parallelism(par);
            log_marginal_likelihood(GpProblem::new(&kernel, 0.05, x.as_ref(), y.as_ref()), true)
                .unwrap()
        };
        let sequential = at(faer::Par::Seq);
        for threads in [2, 3] {
            assert_eq!(
                at(faer::Par::rayon(threads)),
                sequential,
                "{expr}, {threads} threads"
            );
        }
    }
    faer::set_global_parallelism(before);
}

#[test]
fn one_and_two_point_cases_match_closed_forms() {
    let (s2, ell, sn2) = (1.3_f64, 0.7_f64, 0.2_f64);
    let mut kernel = KernelExpr::parse("rbf")
        .unwrap()
        .build(1, &KernelInit::default());
    kernel.set_log_params(&[s2.ln(), ell.ln()]);
    let ln2pi = (2.0 * std::f64::consts::PI).ln();

    let x1 = Mat::from_fn(1, 1, |_, _| 0.4);
    let y1 = Mat::from_fn(1, 1, |_, _| 0.9);
    let lml = log_marginal_likelihood(
        GpProblem::new(&kernel, sn2, x1.as_ref(), y1.as_ref()),
        false,
    )
    .unwrap()
    .lml;
    let v = s2 + sn2;
    assert!((lml - (-0.5 * 0.81 / v - 0.5 * v.ln() - 0.5 * ln2pi)).abs() < 1e-14);

    // Two points: K_y = [[a, b], [b, a]].
    let x2 = Mat::from_fn(2, 1, |i, _| [0.0, 0.5][i]);
    let y2 = Mat::from_fn(2, 1, |i, _| [1.0, -0.5][i]);
    let (a, b) = (s2 + sn2, s2 * (-0.5 * (0.5 / ell).powi(2)).exp());
    let det = a * a - b * b;
    let quad = (a * 1.0 + a * 0.25 - 2.0 * b * (1.0 * -0.5)) / det;
    let expected = -0.5 * quad - 0.5 * det.ln() - ln2pi;
    let lml = log_marginal_likelihood(
        GpProblem::new(&kernel, sn2, x2.as_ref(), y2.as_ref()),
        false,
    )
    .unwrap()
    .lml;
    assert!((lml - expected).abs() < 1e-13, "{lml} vs {expected}");

    // Prediction from one point: mean k*·y/(σ²+σn²), variance σ² − k*²/(σ²+σn²).
    let mut gp = ExactGp::new(ExactGpParams {
        init: KernelInit {
            variance: s2,
            lengthscale: Some(ell),
            ..KernelInit::default()
        },
        noise_variance: sn2,
        ..fixed("rbf")
    })
    .unwrap();
    gp.fit(&dataset(&x1, &y1)).unwrap();
    let xs = SampleMatrix::from_row_major(1, 1, vec![1.0]).unwrap();
    let p = gp.predict_full(&xs).unwrap();
    let ks = s2 * (-0.5 * (0.6 / ell).powi(2)).exp();
    assert!((p.mean.get(0, 0) - ks * 0.9 / v).abs() < 1e-14);
    assert!((p.latent_variance.get(0, 0) - (s2 - ks * ks / v)).abs() < 1e-14);
    assert!((p.variance.get(0, 0) - (s2 - ks * ks / v + sn2)).abs() < 1e-14);
}

#[test]
fn prediction_at_training_points_interpolates_with_tiny_noise() {
    let mut rng = rng(22);
    let x = inputs(&mut rng, 20, 2);
    let y = targets(&mut rng, &x, 0.0);
    let mut gp = ExactGp::new(ExactGpParams {
        noise_variance: 1e-8,
        init: KernelInit {
            lengthscale: Some(1.0),
            ..KernelInit::default()
        },
        hyperopt: HyperoptParams {
            bounds: Bounds {
                noise_variance: [1e-10, 1.0],
                ..Default::default()
            },
            ..Default::default()
        },
        ..fixed("matern52")
    })
    .unwrap();
    gp.fit(&dataset(&x, &y)).unwrap();
    let p = gp.predict_full(&sample_matrix(&x)).unwrap();
    for i in 0..20 {
        for c in 0..3 {
            assert!(
                (p.mean.get(i, c) - y[(i, c)]).abs() < 1e-5,
                "row {i} output {c}"
            );
            assert!(p.latent_variance.get(i, c) < 1e-6);
        }
    }
}

fn sine_data(n: usize, seed: u64) -> (Mat<f64>, Mat<f64>) {
    use rand::Rng;
    let mut rng = rng(seed);
    let x = Mat::from_fn(n, 1, |i, _| -3.0 + 6.0 * i as f64 / (n - 1) as f64);
    let y = Mat::from_fn(n, 1, |i, _| {
        let t = x[(i, 0)];
        (1.5 * t).sin() - 0.2 * t * t + rng.random_range(-0.05..0.05)
    });
    (x, y)
}

#[test]
fn learning_raises_the_likelihood_and_fits_a_sine_with_both_optimisers() {
    let (x, y) = sine_data(60, 23);
    let data = dataset(&x, &y);
    let mut lmls = Vec::new();
    for optimizer in [Optimizer::Lbfgs, Optimizer::ConjugateGradient] {
        let mut gp = ExactGp::new(ExactGpParams {
            hyperopt: HyperoptParams {
                optimizer,
                ..Default::default()
            },
            ..ExactGpParams::default()
        })
        .unwrap();
        let mut fixed_gp = ExactGp::new(ExactGpParams {
            optimize: false,
            ..ExactGpParams::default()
        })
        .unwrap();
        let report = gp.fit(&data).unwrap();
        let initial = fixed_gp.fit(&data).unwrap().objective.unwrap();
        let learned = report.objective.unwrap();
        assert!(
            learned > initial + 1.0,
            "{optimizer:?}: {initial} → {learned}"
        );
        assert!(report.evaluations.unwrap() > 3);
        assert!(
            report
                .parameters
                .iter()
                .any(|(n, _)| n == "rbf.lengthscale[x0]")
        );
        let xs = Mat::from_fn(25, 1, |i, _| -2.9 + 5.8 * i as f64 / 24.0);
        let p = gp.predict_full(&sample_matrix(&xs)).unwrap();
        let rmse = ((0..25)
            .map(|i| {
                let t = xs[(i, 0)];
                (p.mean.get(i, 0) - ((1.5 * t).sin() - 0.2 * t * t)).powi(2)
            })
            .sum::<f64>()
            / 25.0)
            .sqrt();
        assert!(rmse < 0.05, "{optimizer:?}: rmse {rmse}");
        lmls.push(learned);
    }
    assert!(
        rel_err(lmls[0], lmls[1], 1.0) < 1e-3,
        "L-BFGS {} vs CG {}",
        lmls[0],
        lmls[1]
    );
}

#[test]
fn predictions_scale_with_the_targets() {
    let (x, y) = sine_data(30, 24);
    let scaled = Mat::from_fn(30, 1, |i, _| 1000.0 * y[(i, 0)] + 5.0);
    let mut a = ExactGp::new(ExactGpParams::default()).unwrap();
    let mut b = ExactGp::new(ExactGpParams::default()).unwrap();
    a.fit(&dataset(&x, &y)).unwrap();
    b.fit(&dataset(&x, &scaled)).unwrap();
    let xs = SampleMatrix::from_row_major(3, 1, vec![-1.0, 0.3, 2.2]).unwrap();
    let (pa, pb) = (a.predict_full(&xs).unwrap(), b.predict_full(&xs).unwrap());
    for i in 0..3 {
        assert!((1000.0 * pa.mean.get(i, 0) + 5.0 - pb.mean.get(i, 0)).abs() < 1e-6 * 1000.0);
        assert!(rel_err(1e6 * pa.variance.get(i, 0), pb.variance.get(i, 0), 1e-12) < 1e-6);
    }
}

#[test]
fn saved_state_reloads_to_identical_predictions() {
    let mut rng = rng(25);
    let x = inputs(&mut rng, 40, 3);
    let y = targets(&mut rng, &x, 0.05);
    let mut gp = ExactGp::new(ExactGpParams::with_kernel(
        KernelExpr::parse("rbf + linear").unwrap(),
    ))
    .unwrap();
    gp.fit(&dataset(&x, &y)).unwrap();
    let json = serde_json::to_string(gp.state().unwrap()).unwrap();
    let state: ExactGpState = serde_json::from_str(&json).unwrap();
    // Bit-exact: serde_json parses with correct rounding (float_roundtrip).
    assert_eq!(&state, gp.state().unwrap());
    let reloaded = ExactGp::from_state(state).unwrap();
    let xs = sample_matrix(&inputs(&mut rng, 5, 3));
    let (a, b) = (
        gp.predict_full(&xs).unwrap(),
        reloaded.predict_full(&xs).unwrap(),
    );
    assert_eq!(a, b);
}

#[test]
fn independent_outputs_equal_separate_single_output_fits() {
    let mut rng = rng(26);
    let x = inputs(&mut rng, 30, 2);
    let y = targets(&mut rng, &x, 0.05);
    let mut joint = ExactGp::new(ExactGpParams {
        outputs: OutputSharing::Independent,
        ..ExactGpParams::default()
    })
    .unwrap();
    let report = joint.fit(&dataset(&x, &y)).unwrap();
    assert!(
        report
            .parameters
            .iter()
            .any(|(n, _)| n == "y2.noise_variance")
    );
    let xs = sample_matrix(&inputs(&mut rng, 4, 2));
    let pj = joint.predict_full(&xs).unwrap();
    for c in 0..3 {
        let yc = Mat::from_fn(30, 1, |i, _| y[(i, c)]);
        let mut single = ExactGp::new(ExactGpParams {
            seed: c as u64,
            ..ExactGpParams::default()
        })
        .unwrap();
        single.fit(&dataset(&x, &yc)).unwrap();
        let ps = single.predict_full(&xs).unwrap();
        for i in 0..4 {
            assert!((pj.mean.get(i, c) - ps.mean.get(i, 0)).abs() < 1e-9);
            assert!(rel_err(pj.variance.get(i, c), ps.variance.get(i, 0), 1e-12) < 1e-9);
        }
    }
}

#[test]
fn restarts_are_reproducible_and_never_worse() {
    let (x, y) = sine_data(40, 27);
    let data = dataset(&x, &y);
    let fit = |restarts, seed| {
        let mut gp = ExactGp::new(ExactGpParams {
            hyperopt: HyperoptParams {
                restarts,
                ..Default::default()
            },
            seed,
            ..ExactGpParams::default()
        })
        .unwrap();
        gp.fit(&data).unwrap()
    };
    let (one, a, b) = (fit(0, 5), fit(3, 5), fit(3, 5));
    assert_eq!(a.objective, b.objective);
    assert_eq!(a.parameters, b.parameters);
    assert!(a.objective.unwrap() >= one.objective.unwrap() - 1e-9);
}

#[test]
fn bad_data_and_misuse_give_clear_errors() {
    let mut rng = rng(28);
    let x = inputs(&mut rng, 10, 2);
    let mut y = targets(&mut rng, &x, 0.1);
    let mut gp = ExactGp::new(ExactGpParams::default()).unwrap();
    let xs = SampleMatrix::from_row_major(1, 2, vec![0.0, 0.0]).unwrap();
    assert!(
        gp.predict(&xs)
            .unwrap_err()
            .to_string()
            .contains("not been fitted")
    );
    y[(4, 1)] = f64::NAN;
    let err = gp.fit(&dataset(&x, &y)).unwrap_err().to_string();
    assert!(err.contains("row 4") && err.contains("column 1"), "{err}");
    y[(4, 1)] = 0.0;
    gp.fit(&dataset(&x, &y)).unwrap();
    let wide = SampleMatrix::from_row_major(1, 3, vec![0.0; 3]).unwrap();
    assert!(
        gp.predict(&wide)
            .unwrap_err()
            .to_string()
            .contains("expected dimension 2")
    );
    let bad = ExactGpParams {
        noise_variance: -1.0,
        ..ExactGpParams::default()
    };
    assert!(
        ExactGp::new(bad)
            .unwrap_err()
            .to_string()
            .contains("noise_variance")
    );
}

#[test]
fn regressors_are_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<ExactGp>();
    check::<ExactGpState>();
}

/// Records the optimiser's reports.
#[derive(Default)]
struct Recorder(std::sync::Mutex<Vec<(usize, u64, f64)>>);

impl gpodo_traits::FitProgress for Recorder {
    fn iteration(&self, start: usize, iteration: u64, objective: f64) -> std::ops::ControlFlow<()> {
        self.0.lock().unwrap().push((start, iteration, objective));
        std::ops::ControlFlow::Continue(())
    }
}

#[test]
fn a_fit_reports_its_iterations_without_changing_its_result() {
    let (x, y) = sine_data(60, 23);
    let data = dataset(&x, &y);
    let params = ExactGpParams {
        hyperopt: HyperoptParams {
            restarts: 1,
            ..Default::default()
        },
        ..ExactGpParams::default()
    };
    let recorder = std::sync::Arc::new(Recorder::default());
    let mut watched = ExactGp::new(params.clone()).unwrap();
    watched.set_progress(Some(recorder.clone()));
    let report = watched.fit(&data).unwrap();
    let mut quiet = ExactGp::new(params).unwrap();
    assert_eq!(quiet.fit(&data).unwrap().objective, report.objective);
    let seen = recorder.0.lock().unwrap().clone();
    assert!(seen.len() > 3, "{seen:?}");
    // Both starts report, iterations count up within a start, and the best
    // objective so far never falls.
    assert!(seen.iter().any(|s| s.0 == 0) && seen.iter().any(|s| s.0 == 1));
    for w in seen.windows(2) {
        if w[0].0 == w[1].0 {
            assert!(w[1].1 > w[0].1 && w[1].2 >= w[0].2 - 1e-9, "{w:?}");
        }
    }
    let best = seen.iter().map(|s| s.2).fold(f64::NEG_INFINITY, f64::max);
    assert!((best - report.objective.unwrap()).abs() < 1e-6 * best.abs());
}

/// Asks the fit to stop at its `after`-th reported iteration.
struct StopAfter {
    after: usize,
    seen: std::sync::atomic::AtomicUsize,
}

impl gpodo_traits::FitProgress for StopAfter {
    fn iteration(&self, _: usize, _: u64, _: f64) -> std::ops::ControlFlow<()> {
        let n = self.seen.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
        if n >= self.after {
            std::ops::ControlFlow::Break(())
        } else {
            std::ops::ControlFlow::Continue(())
        }
    }
}

/// A fit whose progress asks it to stop ends with an error saying so, at
/// once (no further iteration is reported), and leaves no model behind,
/// for the exact and the sparse GP; the same fit left alone succeeds.
#[test]
fn a_stopped_fit_says_so_and_fits_nothing() {
    use gpodo_regressors::{SparseGp, SparseGpParams};
    let (x, y) = sine_data(80, 29);
    let data = dataset(&x, &y);
    let models: Vec<Box<dyn Fn() -> Box<dyn ResidualRegressor>>> = vec![
        Box::new(|| Box::new(ExactGp::new(ExactGpParams::default()).unwrap())),
        Box::new(|| Box::new(SparseGp::new(SparseGpParams::default()).unwrap())),
    ];
    for make in models {
        let stop = std::sync::Arc::new(StopAfter {
            after: 3,
            seen: std::sync::atomic::AtomicUsize::new(0),
        });
        let mut model = make();
        model.set_progress(Some(stop.clone()));
        let err = model.fit(&data).unwrap_err();
        assert!(err.to_string().contains("stopped"), "{err}");
        assert_eq!(stop.seen.load(std::sync::atomic::Ordering::SeqCst), 3);
        let predicted = model.predict(&data.inputs);
        assert!(
            matches!(predicted, Err(gpodo_traits::Error::NotFitted { .. })),
            "{:?}",
            predicted.map(|_| ())
        );
        let mut alone = make();
        assert!(alone.fit(&data).is_ok());
    }
}

#[test]
fn start_policy_is_deterministic_and_optimises_the_best_scored_candidates() {
    let mut rng = rng(33);
    let x = inputs(&mut rng, 60, 4);
    let y = targets(&mut rng, &x, 0.1);
    let data = dataset(&x, &y);
    let fit = || {
        let mut gp = ExactGp::new(ExactGpParams::default()).unwrap();
        gp.fit(&data).unwrap()
    };
    let (a, b) = (fit(), fit());
    assert_eq!(a.starts, b.starts, "same data, same seed, same candidates");
    assert_eq!(a.objective, b.objective);
    // Three bases (lengthscale 1, √D, median distance) with two
    // perturbations each.
    assert_eq!(a.starts.len(), 9, "{:#?}", a.starts);
    let optimised: Vec<_> = a
        .starts
        .iter()
        .filter(|s| s.final_objective.is_some())
        .collect();
    // Every named base races, with the two best-scored perturbations.
    for s in &a.starts {
        if !s.label.contains("perturbed") {
            assert!(s.final_objective.is_some(), "base {s:?} did not race");
        }
    }
    let mut scores: Vec<f64> = a.starts.iter().filter_map(|s| s.start_objective).collect();
    scores.sort_by(|x, y| y.total_cmp(x));
    for s in optimised.iter().filter(|s| s.label.contains("perturbed")) {
        let score = s.start_objective.unwrap();
        assert!(score >= scores[1], "{s:?} is not among the two best-scored");
    }
    assert!(optimised.len() >= 3 && optimised.len() <= 5);
    // Only the race's leader runs past the race's 15 iterations.
    let past_race = optimised
        .iter()
        .filter(|s| s.iterations.unwrap() > 15)
        .count();
    assert!(past_race <= 1, "{:#?}", a.starts);
    // The reported optimum is the best optimised candidate's, and no
    // optimiser run ends below where it started.
    let best = optimised
        .iter()
        .map(|s| s.final_objective.unwrap())
        .fold(f64::NEG_INFINITY, f64::max);
    assert!((a.objective.unwrap() - best).abs() < 1e-6 * best.abs());
    for s in &optimised {
        assert!(s.final_objective.unwrap() >= s.start_objective.unwrap());
    }
    // `init.lengthscale` overrides the candidates: one base, its perturbations.
    let mut gp = ExactGp::new(ExactGpParams {
        init: KernelInit {
            lengthscale: Some(2.0),
            ..KernelInit::default()
        },
        ..ExactGpParams::default()
    })
    .unwrap();
    let report = gp.fit(&data).unwrap();
    assert_eq!(report.starts.len(), 3);
    assert!(report.starts[0].label.starts_with("init"));
}

#[test]
fn kernel_auto_keeps_the_highest_likelihood_candidate_and_saves_it() {
    use gpodo_regressors::exact_gp::KernelChoice;
    // A trend linear in the inputs plus a little noise: a linear part wins.
    let mut rng = rng(35);
    let x = inputs(&mut rng, 60, 2);
    let noise = targets(&mut rng, &x, 0.05);
    let y = Mat::from_fn(60, 1, |i, _| {
        3.0 * x[(i, 0)] - 2.0 * x[(i, 1)] + 0.1 * noise[(i, 0)]
    });
    let data = dataset(&x, &y);
    let mut auto = ExactGp::new(ExactGpParams {
        kernel: KernelChoice::Auto,
        ..ExactGpParams::default()
    })
    .unwrap();
    let report = auto.fit(&data).unwrap();
    let tried = &report.kernel_candidates;
    assert_eq!(tried.len(), 4);
    let (best, best_lml) = tried.iter().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
    assert!(best.contains("linear"), "{tried:?}");
    assert_eq!(report.objective, Some(*best_lml));
    // Each candidate's LML is what that kernel alone reaches.
    for (kernel, lml) in tried {
        let mut alone = ExactGp::new(ExactGpParams::with_kernel(
            KernelExpr::parse(kernel).unwrap(),
        ))
        .unwrap();
        assert_eq!(alone.fit(&data).unwrap().objective, Some(*lml), "{kernel}");
    }
    // The saved state records the kernel kept, and reloads.
    let state = auto.state().unwrap().clone();
    assert_eq!(state.params.kernel.to_string(), *best);
    let reloaded = ExactGp::from_state(state).unwrap();
    let q = sample_matrix(&x);
    assert_eq!(
        reloaded.predict(&q).unwrap().mean,
        auto.predict(&q).unwrap().mean
    );
    // `auto` needs something to choose from, and learned kernels to compare.
    for params in [
        ExactGpParams {
            kernel: KernelChoice::Auto,
            kernel_candidates: vec![],
            ..ExactGpParams::default()
        },
        ExactGpParams {
            kernel: KernelChoice::Auto,
            optimize: false,
            ..ExactGpParams::default()
        },
    ] {
        let e = ExactGp::new(params).unwrap_err().to_string();
        assert!(e.contains("kernel"), "{e}");
    }
}

#[test]
fn a_warm_start_runs_from_the_previous_optimum_alone() {
    use gpodo_regressors::exact_gp::KernelChoice;
    let (x, y) = sine_data(80, 36);
    let prefix = dataset(
        &Mat::from_fn(60, 1, |i, _| x[(i, 0)]),
        &Mat::from_fn(60, 1, |i, _| y[(i, 0)]),
    );
    let full = dataset(&x, &y);
    let mut first = ExactGp::new(ExactGpParams::default()).unwrap();
    first.fit(&prefix).unwrap();
    let mut cold = ExactGp::new(ExactGpParams::default()).unwrap();
    let cold_report = cold.fit(&full).unwrap();
    let mut warm = ExactGp::new(ExactGpParams::default()).unwrap();
    warm.warm_start_from(first.state().unwrap()).unwrap();
    let warm_report = warm.fit(&full).unwrap();
    // One start, named; fewer evaluations than the cold race; the same
    // optimum of this unimodal problem.
    assert_eq!(warm_report.starts.len(), 1, "{:?}", warm_report.starts);
    assert_eq!(warm_report.starts[0].label, "previous optimum");
    assert!(warm_report.evaluations < cold_report.evaluations);
    let (w, c) = (
        warm_report.objective.unwrap(),
        cold_report.objective.unwrap(),
    );
    assert!((w - c).abs() < 1e-3, "warm {w} cold {c}");
    // Its start is the previous optimum: the start's LML on the full data
    // is the likelihood there, recomputed independently.
    let g = &first.state().unwrap().groups[0];
    let state = warm.state().unwrap();
    let at_previous = log_marginal_likelihood(
        GpProblem::new(
            &g.kernel,
            g.noise_variance,
            gpodo_regressors::dense::to_faer(&state.x_train).as_ref(),
            gpodo_regressors::dense::to_faer(&state.y_train).as_ref(),
        ),
        false,
    )
    .unwrap()
    .lml;
    let started = warm_report.starts[0].start_objective.unwrap();
    assert!((started - at_previous).abs() < 1e-9 * at_previous.abs().max(1.0));
    // Another kernel, or `auto`, cannot warm-start from it.
    let mut other = ExactGp::new(fixed("matern52")).unwrap();
    let e = other.warm_start_from(first.state().unwrap()).unwrap_err();
    assert!(e.to_string().contains("same kernel"), "{e}");
    let mut auto = ExactGp::new(ExactGpParams {
        kernel: KernelChoice::Auto,
        ..ExactGpParams::default()
    })
    .unwrap();
    assert!(auto.warm_start_from(first.state().unwrap()).is_err());
}

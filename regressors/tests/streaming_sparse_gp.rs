//! The streaming sparse GP's bound and posterior (Bui, Nguyen & Turner
//! 2017) against the batch sparse GP: on the first batch its bound is
//! Titsias' VFE bound and its posterior the VFE posterior; with the
//! hyperparameters and inducing inputs held fixed, streaming the batches
//! gives the batch VFE posterior over the inducing outputs on all the
//! data (mean and covariance), with the same jitter, and the batches'
//! bounds sum to the batch bound.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use faer::{Mat, MatRef};
use gpodo_regressors::exact_gp::cholesky::Cholesky;
use gpodo_regressors::sparse_gp::bound::sparse_objective;
use gpodo_regressors::sparse_gp::{Approximation, SparsePosterior};
use gpodo_regressors::sparse_gp::{InducingParams, SparseGp, SparseGpParams};
use gpodo_regressors::streaming_sparse_gp::{
    InducingSummary, StreamingFit, StreamingProblem, streaming_fit,
};
use gpodo_regressors::streaming_sparse_gp::{
    StreamingSparseGp, StreamingSparseGpParams, StreamingSparseGpState,
};
use gpodo_regressors::{GpProblem, Kernel, SparseProblem};
use gpodo_traits::ResidualRegressor;
use support::*;

const JITTER: f64 = 1e-8;

fn rows(m: &Mat<f64>, from: usize, to: usize) -> Mat<f64> {
    Mat::from_fn(to - from, m.ncols(), |i, j| m[(from + i, j)])
}

/// The batch VFE posterior over the inducing outputs, computed directly:
/// with `Σ = K_uu + K_uf K_fu / σ²` (`K_uu` with the jitter), mean
/// `K_uu Σ⁻¹ K_uf Y / σ²` and covariance `K_uu Σ⁻¹ K_uu`, through one
/// Cholesky factor of `Σ`; and the batch sparse GP's posterior.
fn batch_q_u(
    kernel: &Kernel,
    noise: f64,
    x: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
    z: &Mat<f64>,
) -> (Mat<f64>, Mat<f64>, SparsePosterior) {
    let posterior = SparsePosterior::new(SparseProblem {
        gp: GpProblem::new(kernel, noise, x, y),
        z: z.as_ref(),
        approximation: Approximation::Vfe,
        jitter: JITTER,
    })
    .unwrap();
    assert_eq!(posterior.extra_jitter, 0.0);
    let m = z.nrows();
    let mut kuu = kernel.gram(z.as_ref());
    for i in 0..m {
        kuu[(i, i)] += JITTER;
    }
    let kuf = kernel.cross(z.as_ref(), x);
    let sigma = &kuu + &kuf * kuf.transpose() * (1.0 / noise);
    let l = Cholesky::factor(sigma).unwrap();
    let lk = l.solve_lower(kuu.as_ref());
    let covariance = lk.transpose() * &lk;
    let ly = l.solve_lower((&kuf * y * (1.0 / noise)).as_ref());
    let mean = lk.transpose() * &ly;
    (mean, covariance, posterior)
}

/// One batch's streaming fit at the tests' jitter.
fn fit_batch(
    kernel: &Kernel,
    noise: f64,
    x: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
    z: MatRef<'_, f64>,
    old: Option<&InducingSummary>,
) -> StreamingFit {
    streaming_fit(StreamingProblem {
        kernel,
        noise_variance: noise,
        x,
        y,
        inducing: z,
        old,
        jitter: JITTER,
    })
    .unwrap()
}

fn max_abs_diff(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
    assert_eq!((a.nrows(), a.ncols()), (b.nrows(), b.ncols()));
    let mut worst = 0.0f64;
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            worst = worst.max((a[(i, j)] - b[(i, j)]).abs());
        }
    }
    worst
}

fn max_abs(a: &Mat<f64>) -> f64 {
    max_abs_diff(a, &Mat::zeros(a.nrows(), a.ncols()))
}

#[test]
fn the_first_batch_is_the_vfe_bound_and_posterior() {
    let mut rng = rng(5);
    for expr in ["rbf", "matern52", "rbf + linear"] {
        let (n, m, d) = (40, 9, 3);
        let x = inputs(&mut rng, n, d);
        let y = targets(&mut rng, &x, 0.1);
        let z = inputs(&mut rng, m, d);
        let kernel = random_kernel(&mut rng, expr, d);
        let noise = 0.05;
        let vfe = sparse_objective(
            SparseProblem {
                gp: GpProblem::new(&kernel, noise, x.as_ref(), y.as_ref()),
                z: z.as_ref(),
                approximation: Approximation::Vfe,
                jitter: JITTER,
            },
            false,
            false,
        )
        .unwrap();
        let fit = fit_batch(&kernel, noise, x.as_ref(), y.as_ref(), z.as_ref(), None);
        assert!(
            (fit.value - vfe.value).abs() <= 1e-10 * vfe.value.abs().max(1.0),
            "{expr}: streaming {} against VFE {}",
            fit.value,
            vfe.value
        );
        let (mean, covariance, batch) = batch_q_u(&kernel, noise, x.as_ref(), y.as_ref(), &z);
        let (m_a, s_a) = (
            fit.summary.mean().unwrap(),
            fit.summary.covariance().unwrap(),
        );
        assert!(max_abs_diff(&m_a, &mean) <= 1e-10 * max_abs(&mean));
        assert!(max_abs_diff(&s_a, &covariance) <= 1e-10 * max_abs(&covariance));
        let xs = inputs(&mut rng, 15, d);
        let (a, b) = (
            fit.posterior.predict(xs.as_ref()),
            batch.predict(xs.as_ref()),
        );
        assert!(max_abs_diff(&a.mean, &b.mean) <= 1e-10 * max_abs(&b.mean));
        for (u, v) in a.latent_variance.iter().zip(&b.latent_variance) {
            assert!((u - v).abs() <= 1e-10 * v.max(1e-6), "{u} against {v}");
        }
    }
}

/// Streams `x, y` in `batches` through fixed hyperparameters and inducing
/// inputs; returns the last summary's mean and covariance, and the worst
/// relative disagreement with the batch posterior.
fn stream(
    kernel: &Kernel,
    noise: f64,
    x: &Mat<f64>,
    y: &Mat<f64>,
    z: &Mat<f64>,
    batches: usize,
) -> (f64, f64) {
    let n = x.nrows();
    let mut summary = None;
    for b in 0..batches {
        let (from, to) = (b * n / batches, (b + 1) * n / batches);
        let (xb, yb) = (rows(x, from, to), rows(y, from, to));
        let fit = fit_batch(
            kernel,
            noise,
            xb.as_ref(),
            yb.as_ref(),
            z.as_ref(),
            summary.as_ref(),
        );
        summary = Some(fit.summary);
    }
    let summary = summary.unwrap();
    let (mean, covariance, _) = batch_q_u(kernel, noise, x.as_ref(), y.as_ref(), z);
    let (m_a, s_a) = (summary.mean().unwrap(), summary.covariance().unwrap());
    (
        max_abs_diff(&m_a, &mean) / max_abs(&mean),
        max_abs_diff(&s_a, &covariance) / max_abs(&covariance),
    )
}

#[test]
fn streaming_with_fixed_hyperparameters_is_the_batch_posterior() {
    let mut rng = rng(17);
    for (expr, m, d) in [("rbf", 8, 2), ("matern52", 12, 3), ("rbf", 20, 3)] {
        let n = 90;
        let x = inputs(&mut rng, n, d);
        let y = targets(&mut rng, &x, 0.1);
        let z = inputs(&mut rng, m, d);
        let kernel = random_kernel(&mut rng, expr, d);
        for batches in [2, 3, 9] {
            let (mean, covariance) = stream(&kernel, 0.05, &x, &y, &z, batches);
            assert!(
                mean <= 1e-9 && covariance <= 1e-9,
                "{expr}, M = {m}, d = {d}, {batches} batches: mean {mean:.1e}, covariance {covariance:.1e} (relative)"
            );
        }
    }
}

#[test]
fn the_agreement_at_m_100_and_d_28() {
    // The size gpodo runs on board: stated, with the bound it meets.
    let (n, m, d) = (400, 100, 28);
    let (x, y) = bench_data(n, d);
    let mut rng = rng(3);
    let z = Mat::from_fn(m, d, |i, j| {
        x[((i * 37) % n, j)] + 0.01 * (rng_unit(&mut rng))
    });
    let mut kernel = random_kernel(&mut rng, "rbf", d);
    let mut p = kernel.log_params();
    for (k, v) in p.iter_mut().enumerate() {
        // Lengthscales e^1.5 ≈ 4.5 on the ±1.7 inputs, unit variance.
        *v = if k < d { 1.5 } else { 0.0 };
    }
    kernel.set_log_params(&p);
    let (mean, covariance) = stream(&kernel, 0.01, &x, &y, &z, 10);
    eprintln!(
        "M = 100, d = 28, 10 batches of 40: mean {mean:.1e}, covariance {covariance:.1e} (relative)"
    );
    assert!(
        mean <= 1e-10 && covariance <= 1e-10,
        "mean {mean:.1e}, covariance {covariance:.1e}"
    );
}

fn rng_unit(rng: &mut rand_chacha::ChaCha8Rng) -> f64 {
    use rand::Rng;
    rng.random_range(-1.0..1.0)
}

#[test]
fn with_fixed_hyperparameters_the_batches_bounds_sum_to_the_batch_bound() {
    // log p(y₁, y₂, y₃) = log p(y₁) + log p(y₂ | y₁) + log p(y₃ | y₁, y₂):
    // each streaming bound is one factor, old-data terms included.
    let mut rng = rng(23);
    let (n, m, d) = (60, 10, 2);
    let x = inputs(&mut rng, n, d);
    let y = targets(&mut rng, &x, 0.1);
    let z = inputs(&mut rng, m, d);
    let kernel = random_kernel(&mut rng, "rbf", d);
    let noise = 0.05;
    let all = sparse_objective(
        SparseProblem {
            gp: GpProblem::new(&kernel, noise, x.as_ref(), y.as_ref()),
            z: z.as_ref(),
            approximation: Approximation::Vfe,
            jitter: JITTER,
        },
        false,
        false,
    )
    .unwrap()
    .value;
    let mut summary = None;
    let mut total = 0.0;
    for b in 0..3 {
        let (xb, yb) = (rows(&x, b * 20, b * 20 + 20), rows(&y, b * 20, b * 20 + 20));
        let fit = fit_batch(
            &kernel,
            noise,
            xb.as_ref(),
            yb.as_ref(),
            z.as_ref(),
            summary.as_ref(),
        );
        total += fit.value;
        summary = Some(fit.summary);
    }
    assert!(
        (total - all).abs() <= 1e-10 * all.abs(),
        "sum of the streaming bounds {total}, batch VFE bound {all}"
    );
}

#[test]
fn the_streaming_bounds_gradients_match_finite_differences() {
    use gpodo_regressors::streaming_sparse_gp::streaming_objective;
    let mut rng = rng(41);
    for expr in ["rbf", "matern52", "rbf + linear"] {
        let (n, d) = (30, 3);
        let x = inputs(&mut rng, 2 * n, d);
        let y = targets(&mut rng, &x, 0.1);
        let (x1, y1) = (rows(&x, 0, n), rows(&y, 0, n));
        let (x2, y2) = (rows(&x, n, 2 * n), rows(&y, n, 2 * n));
        // The old batch: its own hyperparameters and inducing inputs.
        let old_kernel = random_kernel(&mut rng, expr, d);
        let za = inputs(&mut rng, 6, d);
        let old = fit_batch(
            &old_kernel,
            0.08,
            x1.as_ref(),
            y1.as_ref(),
            za.as_ref(),
            None,
        )
        .summary;
        // The new batch: other hyperparameters, two old inducing inputs
        // kept and five new ones.
        let kernel = random_kernel(&mut rng, expr, d);
        let fresh = inputs(&mut rng, 5, d);
        let zb = Mat::from_fn(
            7,
            d,
            |i, j| if i < 2 { za[(i, j)] } else { fresh[(i - 2, j)] },
        );
        let noise = 0.05;
        for old in [None, Some(&old)] {
            let at = |k: &Kernel, s: f64, z: &Mat<f64>| {
                fit_batch(k, s, x2.as_ref(), y2.as_ref(), z.as_ref(), old).value
            };
            let eval = streaming_objective(
                StreamingProblem {
                    kernel: &kernel,
                    noise_variance: noise,
                    x: x2.as_ref(),
                    y: y2.as_ref(),
                    inducing: zb.as_ref(),
                    old,
                    jitter: JITTER,
                },
                true,
            )
            .unwrap();
            assert!((eval.value - at(&kernel, noise, &zb)).abs() < 1e-12 * eval.value.abs());
            let analytic = eval.gradient.unwrap();
            let mut theta = kernel.log_params();
            theta.push(noise.ln());
            let h = 1e-5;
            for (k, g) in analytic.iter().enumerate() {
                let value = |delta: f64| {
                    let mut t = theta.clone();
                    t[k] += delta;
                    let mut kk = kernel.clone();
                    kk.set_log_params(&t[..t.len() - 1]);
                    at(&kk, t[t.len() - 1].exp(), &zb)
                };
                let fd = (value(h) - value(-h)) / (2.0 * h);
                assert!(
                    rel_err(*g, fd, 1e-3) < 1e-5,
                    "{expr}, old batch {}: ∂F/∂θ[{k}] analytic {g}, finite differences {fd}",
                    old.is_some()
                );
            }
            let dz = eval.inducing_gradient.unwrap();
            // The kept inducing inputs carry the shared jitter, a constant
            // that moves with them only when they stay put: check the new
            // ones.
            for i in 2..zb.nrows() {
                for j in 0..d {
                    let value = |delta: f64| {
                        let mut z = zb.clone();
                        z[(i, j)] += delta;
                        at(&kernel, noise, &z)
                    };
                    let fd = (value(h) - value(-h)) / (2.0 * h);
                    assert!(
                        rel_err(dz[(i, j)], fd, 1e-3) < 1e-5,
                        "{expr}, old batch {}: ∂F/∂Z[{i},{j}] analytic {}, finite differences {fd}",
                        old.is_some(),
                        dz[(i, j)]
                    );
                }
            }
        }
    }
}

/// A small stream: 40 warm-up rows, then batches of 8, 12 inducing points.
fn stream_params() -> StreamingSparseGpParams {
    StreamingSparseGpParams {
        inducing: InducingParams {
            count: 12,
            ..Default::default()
        },
        warmup_rows: 40,
        batch_rows: 8,
        batch_iters: 8,
        hyperopt: gpodo_regressors::hyperopt::HyperoptParams {
            max_iters: 30,
            ..Default::default()
        },
        ..Default::default()
    }
}

fn feed(model: &mut StreamingSparseGp, x: &Mat<f64>, y: &Mat<f64>, rows: std::ops::Range<usize>) {
    for i in rows {
        let xi: Vec<f64> = (0..x.ncols()).map(|q| x[(i, q)]).collect();
        let yi: Vec<f64> = (0..y.ncols()).map(|q| y[(i, q)]).collect();
        model.update(&xi, &yi).unwrap();
    }
}

#[test]
fn streaming_row_by_row_is_fitting_the_same_rows_and_a_saved_model_goes_on_identically() {
    let mut rng = rng(71);
    let (x, y) = {
        let x = inputs(&mut rng, 120, 3);
        let y = targets(&mut rng, &x, 0.05);
        (x, y)
    };
    let queries = sample_matrix(&inputs(&mut rng, 7, 3));
    // 40 + 5 × 8 = 80 rows: every batch complete.
    let mut fitted = StreamingSparseGp::new(stream_params()).unwrap();
    let head = Mat::from_fn(80, 3, |i, q| x[(i, q)]);
    let head_y = Mat::from_fn(80, y.ncols(), |i, q| y[(i, q)]);
    fitted.fit(&dataset(&head, &head_y)).unwrap();
    let mut streamed = StreamingSparseGp::new(stream_params()).unwrap();
    feed(&mut streamed, &x, &y, 0..39);
    assert!(
        streamed.state().is_none(),
        "the first batch is not complete"
    );
    feed(&mut streamed, &x, &y, 39..80);
    assert_eq!(streamed.state().unwrap().batches, 6);
    assert_eq!(
        fitted.predict(&queries).unwrap(),
        streamed.predict(&queries).unwrap()
    );

    // Three rows of the next batch pending: saved, loaded, and both go on.
    feed(&mut streamed, &x, &y, 80..83);
    let json = serde_json::to_string(streamed.state().unwrap()).unwrap();
    let state: StreamingSparseGpState = serde_json::from_str(&json).unwrap();
    assert_eq!(state.pending.len(), 3);
    let mut loaded = StreamingSparseGp::from_state(state).unwrap();
    assert_eq!(
        loaded.predict(&queries).unwrap(),
        streamed.predict(&queries).unwrap()
    );
    feed(&mut streamed, &x, &y, 83..120);
    feed(&mut loaded, &x, &y, 83..120);
    assert_eq!(
        loaded.predict(&queries).unwrap(),
        streamed.predict(&queries).unwrap()
    );
    assert_eq!(loaded.state().unwrap().batches, 11);
}

/// Rows `from..to` as a dataset.
fn batch(x: &Mat<f64>, y: &Mat<f64>, from: usize, to: usize) -> gpodo_traits::ResidualDataset {
    dataset(&rows(x, from, to), &rows(y, from, to))
}

#[test]
fn batches_the_caller_ends_are_learned_whatever_their_size() {
    let mut rng = rng(73);
    let x = inputs(&mut rng, 90, 3);
    let y = targets(&mut rng, &x, 0.05);
    let queries = sample_matrix(&inputs(&mut rng, 6, 3));
    // Batches of 25 (first), 3, 13 and 9 rows, where the settings say 40
    // and 8: the same as a stream whose settings are 25 and the sizes.
    let mut ended = StreamingSparseGp::new(stream_params()).unwrap();
    ended.update_batch(&batch(&x, &y, 0, 1)).unwrap();
    assert!(ended.state().is_none(), "one row waits for a second");
    ended.update_batch(&batch(&x, &y, 1, 25)).unwrap();
    assert_eq!(ended.state().unwrap().batches, 1);
    ended.update_batch(&batch(&x, &y, 25, 28)).unwrap();
    // Two rows given by `update` wait, and join the next batch.
    feed(&mut ended, &x, &y, 28..30);
    assert_eq!(ended.state().unwrap().pending.len(), 2);
    ended.update_batch(&batch(&x, &y, 30, 41)).unwrap();
    ended.update_batch(&batch(&x, &y, 41, 50)).unwrap();
    assert_eq!(ended.state().unwrap().batches, 4);
    assert_eq!(ended.state().unwrap().rows_seen, 50);

    let mut by_rows = StreamingSparseGp::new(StreamingSparseGpParams {
        warmup_rows: 25,
        batch_rows: 3,
        ..stream_params()
    })
    .unwrap();
    feed(&mut by_rows, &x, &y, 0..28);
    for (from, to, size) in [(28, 41, 13), (41, 50, 9)] {
        let mut state = by_rows.state().unwrap().clone();
        state.params.batch_rows = size;
        by_rows = StreamingSparseGp::from_state(state).unwrap();
        feed(&mut by_rows, &x, &y, from..to);
    }
    assert_eq!(by_rows.state().unwrap().batches, 4);
    assert_eq!(
        ended.predict(&queries).unwrap(),
        by_rows.predict(&queries).unwrap()
    );
}

#[test]
fn the_stream_gives_the_same_numbers_at_one_and_two_threads() {
    let mut rng = rng(72);
    let x = inputs(&mut rng, 100, 3);
    let y = targets(&mut rng, &x, 0.05);
    let queries = sample_matrix(&inputs(&mut rng, 5, 3));
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut model = StreamingSparseGp::new(stream_params()).unwrap();
            feed(&mut model, &x, &y, 0..100);
            model.predict(&queries).unwrap()
        })
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn the_stream_learns_the_function_nearly_as_the_batch_sparse_gp_does() {
    let mut rng = rng(73);
    let x = inputs(&mut rng, 400, 2);
    let y = targets(&mut rng, &x, 0.05);
    let xt = inputs(&mut rng, 200, 2);
    let yt = targets(&mut rng, &xt, 0.0);
    let rmse = |p: &gpodo_traits::Predictions| {
        let mut s = 0.0;
        for i in 0..yt.nrows() {
            for j in 0..yt.ncols() {
                s += (p.mean.get(i, j) - yt[(i, j)]).powi(2);
            }
        }
        (s / (yt.nrows() * yt.ncols()) as f64).sqrt()
    };
    let zero = {
        let mut s = 0.0;
        for i in 0..yt.nrows() {
            for j in 0..yt.ncols() {
                s += yt[(i, j)].powi(2);
            }
        }
        (s / (yt.nrows() * yt.ncols()) as f64).sqrt()
    };
    let mut streamed = StreamingSparseGp::new(StreamingSparseGpParams {
        inducing: InducingParams {
            count: 30,
            ..Default::default()
        },
        warmup_rows: 50,
        batch_rows: 10,
        ..Default::default()
    })
    .unwrap();
    feed(&mut streamed, &x, &y, 0..400);
    let mut batch = SparseGp::new(SparseGpParams {
        inducing: InducingParams {
            count: 30,
            ..Default::default()
        },
        ..Default::default()
    })
    .unwrap();
    batch.fit(&dataset(&x, &y)).unwrap();
    let queries = sample_matrix(&xt);
    let (s, b) = (
        rmse(&streamed.predict(&queries).unwrap()),
        rmse(&batch.predict(&queries).unwrap()),
    );
    eprintln!("held-out RMSE: streamed {s:.4}, batch sparse GP {b:.4}, zero {zero:.4}");
    assert!(
        s < 1.5 * b && s < 0.3 * zero,
        "streamed {s}, batch {b}, zero {zero}"
    );
}

#[test]
fn bad_streaming_settings_are_named() {
    for (params, field) in [
        (
            StreamingSparseGpParams {
                kept_inducing: 1.0,
                ..Default::default()
            },
            "kept_inducing",
        ),
        (
            StreamingSparseGpParams {
                batch_rows: 0,
                ..Default::default()
            },
            "batch_rows",
        ),
        (
            StreamingSparseGpParams {
                warmup_rows: 1,
                ..Default::default()
            },
            "warmup_rows",
        ),
    ] {
        let err = StreamingSparseGp::new(params).unwrap_err().to_string();
        assert!(err.contains(field), "{err}");
    }
}

#[test]
fn a_robot_at_rest_neither_repeats_inducing_inputs_nor_moves_a_batch_past_its_step() {
    // Half the rows repeat the row before (a rover standing still).
    let mut rng = rng(74);
    let x = inputs(&mut rng, 200, 3);
    let x = Mat::from_fn(200, 3, |i, q| x[(i - i % 2, q)]);
    let y = targets(&mut rng, &x, 0.05);
    for fixed in [true, false] {
        let params = StreamingSparseGpParams {
            inducing: InducingParams {
                count: 20,
                fixed,
                ..Default::default()
            },
            ..stream_params()
        };
        let step = params.batch_log_step;
        let mut model = StreamingSparseGp::new(params).unwrap();
        feed(&mut model, &x, &y, 0..40);
        let mut before = model.state().unwrap().clone();
        for b in 0..20 {
            let first = 40 + 8 * b;
            feed(&mut model, &x, &y, first..first + 8);
            let after = model.state().unwrap();
            let mut moved: Vec<f64> = after
                .kernel
                .log_params()
                .iter()
                .zip(before.kernel.log_params())
                .map(|(a, b)| (a - b).abs())
                .collect();
            moved.push((after.noise_variance.ln() - before.noise_variance.ln()).abs());
            assert!(
                moved.iter().all(|m| *m <= step + 1e-9),
                "fixed {fixed}, batch {b}: moved {moved:?}"
            );
            let z = &after.summary.inducing;
            for i in 0..z.nrows() {
                for j in 0..i {
                    let d2: f64 = (0..3).map(|q| (z.get(i, q) - z.get(j, q)).powi(2)).sum();
                    assert!(
                        d2 > 0.0,
                        "fixed {fixed}, batch {b}: inducing inputs {i} and {j} coincide"
                    );
                }
            }
            before = after.clone();
        }
    }
}

//! Exact GP cost (issue: the baseline of every comparison must be fast):
//! one LML + gradient evaluation and a fit at n = 500, 1000, 2000 with
//! d = 18 and 28 inputs, 3 outputs, RBF-ARD; beside them, the dense
//! reference the evaluation is judged against — one Cholesky plus one
//! inverse of the same n × n matrix. The fit is capped at
//! [`FIT_ITERATIONS`] L-BFGS iterations so that ten samples at n = 2000 stay
//! within minutes; fits to convergence are timed against GPy and
//! scikit-learn by `bench/peers/` (see `bench/README.md`). Data are seeded
//! and built outside the timed closures.

#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use faer::Mat;
use gpodo_regressors::exact_gp::cholesky::Cholesky;
use gpodo_regressors::exact_gp::likelihood::log_marginal_likelihood;
use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams};
use gpodo_regressors::kernels::{KernelExpr, KernelInit};
use gpodo_traits::{ResidualDataset, ResidualRegressor, SampleMatrix};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const SIZES: [usize; 3] = [500, 1000, 2000];
const DIMS: [usize; 2] = [18, 28];
/// Iteration cap of the fit benchmark.
const FIT_ITERATIONS: u64 = 25;

/// Standardised-looking inputs and 3 smooth noisy outputs.
fn data(n: usize, d: usize) -> (Mat<f64>, Mat<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(2026);
    let x = Mat::from_fn(n, d, |_, _| rng.random_range(-1.7..1.7));
    let y = Mat::from_fn(n, 3, |i, c| {
        let s: f64 = (0..4).map(|q| x[(i, (q + c) % d)]).sum();
        (0.7 * s).sin() + 0.3 * x[(i, c)] * x[(i, 5)] + rng.random_range(-0.2..0.2)
    });
    (x, y)
}

fn dataset(x: &Mat<f64>, y: &Mat<f64>) -> ResidualDataset {
    let rows = |m: &Mat<f64>| {
        SampleMatrix::from_row_major(
            m.nrows(),
            m.ncols(),
            (0..m.nrows())
                .flat_map(|i| (0..m.ncols()).map(move |j| m[(i, j)]))
                .collect(),
        )
        .unwrap()
    };
    ResidualDataset::new(
        rows(x),
        rows(y),
        (0..x.ncols()).map(|q| format!("x{q}")).collect(),
        (0..3).map(|c| format!("y{c}")).collect(),
    )
    .unwrap()
}

fn evaluation(c: &mut Criterion) {
    let mut group = c.benchmark_group("exact_gp_evaluation");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    for d in DIMS {
        for n in SIZES {
            let (x, y) = data(n, d);
            let kernel = KernelExpr::Leaf("rbf".into()).build(d, &KernelInit::default());
            let label = format!("n{n}_d{d}");
            group.bench_with_input(BenchmarkId::new("lml_and_gradient", &label), &n, |b, _| {
                b.iter(|| {
                    log_marginal_likelihood(&kernel, 0.1, x.as_ref(), y.as_ref(), true).unwrap()
                })
            });
            let mut k = kernel.gram(x.as_ref());
            for i in 0..n {
                k[(i, i)] += 0.1;
            }
            group.bench_with_input(
                BenchmarkId::new("cholesky_and_inverse", &label),
                &n,
                |b, _| b.iter(|| black_box(Cholesky::factor(k.clone()).unwrap().inverse())),
            );
        }
    }
    group.finish();
}

fn fit(c: &mut Criterion) {
    let mut group = c.benchmark_group("exact_gp_fit");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    for d in DIMS {
        for n in SIZES {
            let (x, y) = data(n, d);
            let data = dataset(&x, &y);
            let label = format!("n{n}_d{d}");
            group.bench_with_input(
                BenchmarkId::new("rbf_ard_25_iterations", label),
                &n,
                |b, _| {
                    b.iter(|| {
                        let params = ExactGpParams {
                            max_iters: FIT_ITERATIONS,
                            ..ExactGpParams::default()
                        };
                        let mut gp = ExactGp::new(params).unwrap();
                        black_box(gp.fit(&data).unwrap())
                    })
                },
            );
        }
    }
    group.finish();
}

criterion_group!(benches, evaluation, fit);
criterion_main!(benches);

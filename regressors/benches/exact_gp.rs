//! Exact GP cost (the baseline of every comparison must be fast):
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
use gpodo_regressors::GpProblem;
use gpodo_regressors::dense::recycle;
use gpodo_regressors::exact_gp::cholesky::Cholesky;
use gpodo_regressors::exact_gp::likelihood::log_marginal_likelihood;
use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams};
use gpodo_regressors::hyperopt::HyperoptParams;
use gpodo_regressors::kernels::{KernelExpr, KernelInit, LeafName};
use gpodo_traits::ResidualRegressor;

#[path = "../tests/support/mod.rs"]
mod support;
use support::{bench_data as data, dataset};

const SIZES: [usize; 3] = [500, 1000, 2000];
const DIMS: [usize; 2] = [18, 28];
/// Iteration cap of the fit benchmark.
const FIT_ITERATIONS: u64 = 25;

fn evaluation(c: &mut Criterion) {
    let mut group = c.benchmark_group("exact_gp_evaluation");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    for d in DIMS {
        for n in SIZES {
            let (x, y) = data(n, d);
            let kernel = KernelExpr::Leaf(LeafName::Rbf).build(d, &KernelInit::default());
            let label = format!("n{n}_d{d}");
            group.bench_with_input(BenchmarkId::new("lml_and_gradient", &label), &n, |b, _| {
                b.iter(|| {
                    log_marginal_likelihood(
                        GpProblem::new(&kernel, 0.1, x.as_ref(), y.as_ref()),
                        true,
                    )
                    .unwrap()
                })
            });
            let mut k = kernel.gram(x.as_ref());
            for i in 0..n {
                k[(i, i)] += 0.1;
            }
            group.bench_with_input(
                BenchmarkId::new("cholesky_and_inverse", &label),
                &n,
                // Buffers recycled as an evaluation recycles them.
                |b, _| {
                    b.iter(|| {
                        let c = Cholesky::factor_shifted(&k, 0.0).unwrap();
                        recycle(black_box(c.inverse_lower()));
                        recycle(c.l);
                    })
                },
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
                            hyperopt: HyperoptParams {
                                max_iters: FIT_ITERATIONS,
                                ..HyperoptParams::default()
                            },
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

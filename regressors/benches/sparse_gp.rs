//! Sparse GP cost against the exact GP in the same run: one objective +
//! gradient evaluation (hyperparameters and inducing inputs) at n = 2000
//! and n = 20 000 with m = 100 and 200, d = 28, 3 outputs, RBF-ARD, beside
//! the exact GP's LML + gradient at n = 2000; and a fit capped at
//! [`FIT_ITERATIONS`] L-BFGS iterations, sparse (m = 100) against exact at
//! n = 2000 and sparse alone at n = 20 000. Data are seeded and built
//! outside the timed closures.

#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gpodo_regressors::exact_gp::likelihood::log_marginal_likelihood;
use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams};
use gpodo_regressors::hyperopt::HyperoptParams;
use gpodo_regressors::kernels::{KernelExpr, KernelInit, LeafName};
use gpodo_regressors::sparse_gp::bound::sparse_objective;
use gpodo_regressors::sparse_gp::inducing::place_inducing;
use gpodo_regressors::sparse_gp::{Approximation, InducingParams, SparseGp, SparseGpParams};
use gpodo_regressors::{GpProblem, SparseProblem};
use gpodo_traits::ResidualRegressor;

#[path = "../tests/support/mod.rs"]
mod support;
use support::{bench_data as data, dataset};

const D: usize = 28;
/// Iteration cap of the fit benchmark.
const FIT_ITERATIONS: u64 = 25;

fn evaluation(c: &mut Criterion) {
    let mut group = c.benchmark_group("sparse_gp_evaluation");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    let kernel = KernelExpr::Leaf(LeafName::Rbf).build(D, &KernelInit::default());
    let (x, y) = data(2000, D);
    group.bench_function("exact_lml_and_gradient/n2000", |b| {
        b.iter(|| {
            log_marginal_likelihood(GpProblem::new(&kernel, 0.1, x.as_ref(), y.as_ref()), true)
                .unwrap()
        })
    });
    for n in [2000, 20_000] {
        let (x, y) = data(n, D);
        for m in [100, 200] {
            let inducing = InducingParams {
                count: m,
                ..Default::default()
            };
            let z = place_inducing(x.as_ref(), &inducing, 0);
            for method in [Approximation::Vfe, Approximation::Fitc] {
                let id = BenchmarkId::new(
                    format!("{method:?}_bound_and_gradient"),
                    format!("n{n}_m{m}"),
                );
                group.bench_function(id, |b| {
                    b.iter(|| {
                        sparse_objective(
                            SparseProblem {
                                gp: GpProblem::new(&kernel, 0.1, x.as_ref(), y.as_ref()),
                                z: z.as_ref(),
                                approximation: method,
                                jitter: 1e-6,
                            },
                            true,
                            true,
                        )
                        .unwrap()
                    })
                });
            }
        }
    }
    group.finish();
}

fn fit(c: &mut Criterion) {
    let mut group = c.benchmark_group("sparse_gp_fit");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    let (x, y) = data(2000, D);
    let small = dataset(&x, &y);
    group.bench_function("exact_rbf_25_iterations/n2000", |b| {
        b.iter(|| {
            let mut gp = ExactGp::new(ExactGpParams {
                hyperopt: HyperoptParams {
                    max_iters: FIT_ITERATIONS,
                    ..HyperoptParams::default()
                },
                ..ExactGpParams::default()
            })
            .unwrap();
            black_box(gp.fit(&small).unwrap())
        })
    });
    let (x, y) = data(20_000, D);
    let large = dataset(&x, &y);
    for (n, data) in [(2000, &small), (20_000, &large)] {
        group.bench_function(format!("sparse_vfe_m100_25_iterations/n{n}"), |b| {
            b.iter(|| {
                let mut gp = SparseGp::new(SparseGpParams {
                    hyperopt: HyperoptParams {
                        max_iters: FIT_ITERATIONS,
                        ..HyperoptParams::default()
                    },
                    ..SparseGpParams::default()
                })
                .unwrap();
                black_box(gp.fit(data).unwrap())
            })
        });
    }
    group.finish();
}

criterion_group!(benches, evaluation, fit);
criterion_main!(benches);

//! The exact GP's two solvers per evaluation (LML + gradient, RBF-ARD,
//! d = 28, 3 outputs), where `solver: auto` switches from one to the other:
//! the dense path (one Cholesky factor and its inverse) against iterative
//! solves (batched preconditioned CG, stochastic Lanczos quadrature; 16
//! probes, preconditioner rank 300), at n = 1000 … 6000. The iterative cost
//! depends on how well conditioned `K + σ_n² I` is, so both are timed at a
//! large noise variance (0.9 of the standardised targets' variance, as the
//! simulated testbed's per-sample rows learn) and a small one (0.02, as the
//! ExoTeR table's 1-s means learn). Data are seeded and built outside the
//! timed closures; buffers are kept between evaluations as in a fit.

#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gpodo_regressors::GpProblem;
use gpodo_regressors::dense::SpareLimit;
use gpodo_regressors::exact_gp::iterative::{
    IterativeSettings, IterativeSolver, log_marginal_likelihood_iterative,
};
use gpodo_regressors::exact_gp::likelihood::log_marginal_likelihood;
use gpodo_regressors::kernels::{KernelExpr, KernelInit, LeafName};

#[path = "../tests/support/mod.rs"]
mod support;
use support::bench_data as data;

const SIZES: [usize; 4] = [1000, 2000, 4000, 6000];
const D: usize = 28;

fn solvers(c: &mut Criterion) {
    let mut group = c.benchmark_group("exact_gp_solvers");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    // Lengthscale √d (the default), variance 1.
    let kernel = KernelExpr::Leaf(LeafName::Rbf).build(D, &KernelInit::default());
    for n in SIZES {
        let (x, y) = data(n, D);
        let _spare = SpareLimit::at_least(5 * n * n * 8);
        let solver = IterativeSolver::new(
            n,
            IterativeSettings {
                preconditioner_rank: 300,
                ..IterativeSettings::default()
            },
        );
        for noise in [0.9, 0.02] {
            let label = format!("n{n}_noise{noise}");
            group.bench_with_input(BenchmarkId::new("dense", &label), &n, |b, _| {
                b.iter(|| {
                    log_marginal_likelihood(
                        GpProblem::new(&kernel, noise, x.as_ref(), y.as_ref()),
                        true,
                    )
                    .unwrap()
                })
            });
            group.bench_with_input(BenchmarkId::new("iterative", &label), &n, |b, _| {
                b.iter(|| {
                    log_marginal_likelihood_iterative(
                        GpProblem::new(&kernel, noise, x.as_ref(), y.as_ref()),
                        true,
                        &solver,
                        || false,
                    )
                    .unwrap()
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, solvers);
criterion_main!(benches);

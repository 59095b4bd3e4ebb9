//! Shared fixtures of the regressor tests and benches: seeded random
//! inputs, targets, hyperparameters and weight matrices. The benches load
//! this same file (`#[path]`), so there is one copy.

#![allow(dead_code)]

pub mod gpy_fixture;

use faer::Mat;
use gpodo_regressors::kernels::{Kernel, KernelExpr, KernelInit};
use gpodo_traits::{ResidualDataset, SampleMatrix};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A seeded generator.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// `n × d` inputs uniform in `[-2, 2]`.
pub fn inputs(rng: &mut ChaCha8Rng, n: usize, d: usize) -> Mat<f64> {
    Mat::from_fn(n, d, |_, _| rng.random_range(-2.0..2.0))
}

/// A symmetric `n × n` weight matrix with entries in `[-1, 1]`.
pub fn symmetric(rng: &mut ChaCha8Rng, n: usize) -> Mat<f64> {
    let a = Mat::from_fn(n, n, |_, _| rng.random_range(-1.0..1.0));
    Mat::from_fn(n, n, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]))
}

/// The kernel of `expr` for `d` inputs with random hyperparameters
/// (log-uniform in `[e^-1, e^1]` around 1, lengthscales around 1.5).
pub fn random_kernel(rng: &mut ChaCha8Rng, expr: &str, d: usize) -> Kernel {
    let mut k = KernelExpr::parse(expr)
        .unwrap()
        .build(d, &KernelInit::default());
    let p: Vec<f64> = (0..k.n_params())
        .map(|_| rng.random_range(-1.0..1.0) + 0.4)
        .collect();
    k.set_log_params(&p);
    k
}

/// A smooth 3-output function of the inputs plus seeded noise.
pub fn targets(rng: &mut ChaCha8Rng, x: &Mat<f64>, noise: f64) -> Mat<f64> {
    Mat::from_fn(x.nrows(), 3, |i, c| {
        let v = match c {
            0 => (x[(i, 0)]).sin() + 0.3 * x[(i, 1 % x.ncols())],
            1 => (0.5 * x[(i, 0)]).cos() * x[(i, (2 % x.ncols()))],
            _ => 0.2 * x[(i, 0)] * x[(i, 0)],
        };
        v + noise * rng.random_range(-1.0..1.0)
    })
}

/// The benches' data: standardised-looking inputs and 3 smooth noisy
/// outputs (`d ≥ 6`), from a fixed seed.
pub fn bench_data(n: usize, d: usize) -> (Mat<f64>, Mat<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(2026);
    let x = Mat::from_fn(n, d, |_, _| rng.random_range(-1.7..1.7));
    let y = Mat::from_fn(n, 3, |i, c| {
        let s: f64 = (0..4).map(|q| x[(i, (q + c) % d)]).sum();
        (0.7 * s).sin() + 0.3 * x[(i, c)] * x[(i, 5)] + rng.random_range(-0.2..0.2)
    });
    (x, y)
}

/// Row-major copy of a faer matrix.
pub fn sample_matrix(m: &Mat<f64>) -> SampleMatrix {
    SampleMatrix::from_row_major(
        m.nrows(),
        m.ncols(),
        (0..m.nrows())
            .flat_map(|i| (0..m.ncols()).map(move |j| m[(i, j)]))
            .collect(),
    )
    .unwrap()
}

/// A dataset with named columns.
pub fn dataset(x: &Mat<f64>, y: &Mat<f64>) -> ResidualDataset {
    ResidualDataset::new(
        sample_matrix(x),
        sample_matrix(y),
        (0..x.ncols()).map(|q| format!("x{q}")).collect(),
        (0..y.ncols()).map(|c| format!("y{c}")).collect(),
    )
    .unwrap()
}

/// Relative error with a floor on the scale.
pub fn rel_err(a: f64, b: f64, floor: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(floor)
}

//! Seeded synthetic data shared by the regressor benches.

#![allow(dead_code)]

use faer::Mat;
use gpodo_traits::{ResidualDataset, SampleMatrix};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Standardised-looking inputs and 3 smooth noisy outputs.
pub fn data(n: usize, d: usize) -> (Mat<f64>, Mat<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(2026);
    let x = Mat::from_fn(n, d, |_, _| rng.random_range(-1.7..1.7));
    let y = Mat::from_fn(n, 3, |i, c| {
        let s: f64 = (0..4).map(|q| x[(i, (q + c) % d)]).sum();
        (0.7 * s).sin() + 0.3 * x[(i, c)] * x[(i, 5)] + rng.random_range(-0.2..0.2)
    });
    (x, y)
}

/// Row-major copy of a faer matrix.
pub fn rows(m: &Mat<f64>) -> SampleMatrix {
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
        rows(x),
        rows(y),
        (0..x.ncols()).map(|q| format!("x{q}")).collect(),
        (0..y.ncols()).map(|c| format!("y{c}")).collect(),
    )
    .unwrap()
}

//! ILGR's and the sparse-spectrum GP's per-sample cost (§VI: the on-board
//! budget at 12.5 Hz is 80 ms). ILGR:
//! one online `update` followed by one `predict_row` at d = 28 with three
//! outputs, after warming the model up to its default number of broad
//! local models and, with narrower models, to the 200-model limit; beside
//! the exact GP's one-row prediction (n = 1000, d = 28) in the same run as
//! the baseline every regressor is compared with. Data are seeded and
//! built outside the timed closures.

#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams};
use gpodo_regressors::{Ilgr, IlgrParams, SparseSpectrumGp, SparseSpectrumParams};
use gpodo_traits::{ResidualRegressor, SampleMatrix};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

#[path = "../tests/support/mod.rs"]
mod support;
use support::{bench_data as data, dataset, sample_matrix as rows};

const D: usize = 28;

fn samples(n: usize, seed: u64) -> Vec<(Vec<f64>, [f64; 3])> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let normal = Normal::new(0.0, 1.0).unwrap();
    (0..n)
        .map(|_| {
            let x: Vec<f64> = (0..D).map(|_| normal.sample(&mut rng)).collect();
            let y = [x[0].sin(), 0.5 * x[1], x[2] * x[3]];
            (x, y)
        })
        .collect()
}

fn per_sample(c: &mut Criterion) {
    let mut group = c.benchmark_group("per_sample");
    group
        .sample_size(20)
        .measurement_time(Duration::from_secs(5));
    let (x, y) = data(1000, D);
    let mut gp = ExactGp::new(ExactGpParams {
        optimize: false,
        ..ExactGpParams::default()
    })
    .unwrap();
    gp.fit(&dataset(&x, &y)).unwrap();
    let query = SampleMatrix::from_row_major(1, D, rows(&x).row(3).to_vec()).unwrap();
    group.bench_function("exact_gp_predict_one/n1000", |b| {
        b.iter(|| gp.predict(black_box(&query)).unwrap())
    });
    for (name, init_lengthscale) in [("default", 2.0), ("unit", 1.0), ("narrow", 0.5)] {
        let mut model = Ilgr::new(IlgrParams {
            init_lengthscale,
            target_scale: 1.0,
            ..IlgrParams::default()
        })
        .unwrap();
        for (xs, ys) in samples(20_000, 1) {
            model.update(&xs, &ys).unwrap();
        }
        let stream = samples(4096, 2);
        let models = model.n_local_models();
        let (mut mean, mut var) = ([0.0; 3], [0.0; 3]);
        let mut i = 0;
        let id = BenchmarkId::new("ilgr_update_and_predict", format!("{name}_{models}_models"));
        group.bench_function(id, |b| {
            b.iter(|| {
                let (xs, ys) = &stream[i % stream.len()];
                i += 1;
                model.update(xs, ys).unwrap();
                model.predict_row(xs, &mut mean, &mut var).unwrap();
                black_box((&mean, &var));
            })
        });
    }
    // The sparse-spectrum GP (I-SSGP): one exact rank-one update of its
    // D = 200 features, after a warm-up fit on 200 rows.
    let mut ssgp = SparseSpectrumGp::new(SparseSpectrumParams::default()).unwrap();
    let (wx, wy) = data(200, D);
    ssgp.fit(&dataset(&wx, &wy)).unwrap();
    let stream = samples(4096, 3);
    let mut i = 0;
    group.bench_function("sparse_spectrum_update/d28_p3_D200", |b| {
        b.iter(|| {
            let (xs, ys) = &stream[i % stream.len()];
            i += 1;
            ssgp.update(black_box(xs), black_box(ys)).unwrap();
        })
    });
    // Test, then train, as in the prequential protocol: one prediction
    // (the weights solved from the factor, O(D² p)) and one update.
    let mut i = 0;
    group.bench_function("sparse_spectrum_predict_and_update/d28_p3_D200", |b| {
        b.iter(|| {
            let (xs, ys) = &stream[i % stream.len()];
            i += 1;
            let query = SampleMatrix::from_row_major(1, D, xs.clone()).unwrap();
            black_box(ssgp.predict(&query).unwrap());
            ssgp.update(black_box(xs), black_box(ys)).unwrap();
        })
    });
    group.finish();
}

criterion_group!(benches, per_sample);
criterion_main!(benches);

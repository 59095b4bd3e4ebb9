//! The streaming sparse GP's cost per batch at the size: m = 100
//! inducing points, batches of 10 rows, d = 28, three outputs, after a
//! first batch of 100 rows. Printed: the p50 and p99 over 100 batches of
//! the posterior update (placing the batch's inducing inputs and the
//! optimal `q(b)`) plus the 10 rows' predictions, and of the
//! hyperparameter step (20 L-BFGS iterations on the streaming bound).
//! Criterion times a batch's update alone (`batch_iters: 0`) beside the
//! exact GP's one-row prediction at n = 1000, the baseline measured in the
//! same run. Run with `cargo bench -p gpodo-regressors --bench
//! streaming_sparse_gp`.

#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams};
use gpodo_regressors::{StreamingSparseGp, StreamingSparseGpParams};
use gpodo_traits::{ResidualRegressor, SampleMatrix};

#[path = "../tests/support/mod.rs"]
mod support;
use support::{bench_data as data, dataset, sample_matrix as rows};

const D: usize = 28;
const FIRST: usize = 100;
const BATCH: usize = 10;
const BATCHES: usize = 100;

fn percentile(v: &[f64], p: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[((p / 100.0) * (s.len() - 1) as f64).round() as usize]
}

fn per_batch(c: &mut Criterion) {
    let (x, y) = data(FIRST + (BATCHES + 50) * BATCH, D);
    let (xs, ys) = (rows(&x), rows(&y));
    let row = |i: usize| (xs.row(i).to_vec(), ys.row(i).to_vec());
    let mut model = StreamingSparseGp::new(StreamingSparseGpParams::default()).unwrap();
    for i in 0..FIRST {
        let (xi, yi) = row(i);
        model.update(&xi, &yi).unwrap();
    }
    let mut update_and_predict = Vec::new();
    for b in 0..BATCHES {
        let first = FIRST + b * BATCH;
        for i in first..first + BATCH {
            let (xi, yi) = row(i);
            model.update(&xi, &yi).unwrap();
        }
        let queries = SampleMatrix::from_rows(
            D,
            &(first + BATCH..first + 2 * BATCH)
                .map(|i| xs.row(i))
                .collect::<Vec<_>>(),
        )
        .unwrap();
        let t = Instant::now();
        black_box(model.predict(&queries).unwrap());
        let predict = t.elapsed().as_secs_f64();
        let timing = model.batch_timings()[b];
        update_and_predict.push(timing.update_secs + predict);
    }
    let steps: Vec<f64> = model
        .batch_timings()
        .iter()
        .map(|t| t.hyperparameter_secs)
        .collect();
    eprintln!(
        "streaming sparse GP (m = 100, batches of {BATCH}, d = {D}), over {BATCHES} batches: \
         update + predictions p50 {:.3} ms, p99 {:.3} ms; hyperparameter step p50 {:.1} ms, p99 {:.1} ms",
        percentile(&update_and_predict, 50.0) * 1e3,
        percentile(&update_and_predict, 99.0) * 1e3,
        percentile(&steps, 50.0) * 1e3,
        percentile(&steps, 99.0) * 1e3,
    );

    let mut group = c.benchmark_group("streaming_sparse_gp");
    group
        .sample_size(20)
        .measurement_time(Duration::from_secs(5));
    let (gx, gy) = data(1000, D);
    let mut gp = ExactGp::new(ExactGpParams {
        optimize: false,
        ..ExactGpParams::default()
    })
    .unwrap();
    gp.fit(&dataset(&gx, &gy)).unwrap();
    let query = SampleMatrix::from_row_major(1, D, rows(&gx).row(3).to_vec()).unwrap();
    group.bench_function("exact_gp_predict_one/n1000", |b| {
        b.iter(|| gp.predict(black_box(&query)).unwrap())
    });
    let mut fixed = StreamingSparseGp::new(StreamingSparseGpParams {
        batch_iters: 0,
        ..StreamingSparseGpParams::default()
    })
    .unwrap();
    for i in 0..FIRST + 20 * BATCH {
        let (xi, yi) = row(i);
        fixed.update(&xi, &yi).unwrap();
    }
    let next = FIRST + 20 * BATCH;
    group.bench_function("update_one_batch/m100_d28", |b| {
        b.iter_batched(
            || fixed.clone(),
            |mut m| {
                for i in next..next + BATCH {
                    let (xi, yi) = row(i);
                    m.update(&xi, &yi).unwrap();
                }
                m
            },
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

criterion_group!(benches, per_batch);
criterion_main!(benches);

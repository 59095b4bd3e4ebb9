//! Times each step of one exact-GP evaluation (RBF-ARD unless a kernel
//! expression follows `N`; d = 28 unless a third argument sets it, 3
//! outputs, seeded data): the Gram matrix, the Cholesky factor, the inverse, the
//! log marginal likelihood alone and with its gradient, averaged over 10
//! repetitions, then the ratio of the evaluation to the factor and inverse
//! from interleaved pairs (the median, robust to the machine's drift).
//! Compare with the LAPACK floor of `bench/peers/dense_floor.py`
//! at the same `n`.
//!
//! ```sh
//! cargo run --release -p gpodo-regressors --example evaluation_cost -- 1869
//! cargo run --release -p gpodo-regressors --example evaluation_cost -- 1200 "matern52 + linear"
//! ```

#![allow(clippy::unwrap_used, clippy::expect_used)]
use faer::Mat;
use gpodo_regressors::GpProblem;
use gpodo_regressors::dense::recycle;
use gpodo_regressors::exact_gp::cholesky::Cholesky;
use gpodo_regressors::exact_gp::likelihood::log_marginal_likelihood;
use gpodo_regressors::kernels::{KernelExpr, KernelInit};
use rand::{Rng, SeedableRng};
use std::time::Instant;
/// Prints the mean time of each step at `n` (first argument, default 1869).
fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(1869);
    let d: usize = std::env::args()
        .nth(3)
        .map(|s| s.parse().unwrap())
        .unwrap_or(28);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let x: Mat<f64> = Mat::from_fn(n, d, |_, _| rng.random_range(-1.7..1.7));
    let y = Mat::from_fn(n, 3, |i, c| x[(i, c)].sin() + rng.random_range(-0.2..0.2));
    let expr = std::env::args().nth(2).unwrap_or_else(|| "rbf".into());
    let kernel = KernelExpr::parse(&expr)
        .unwrap()
        .build(d, &KernelInit::default());
    let reps = 10;
    let t = Instant::now();
    for _ in 0..reps {
        // The lower triangles an evaluation forms, buffers recycled as it
        // recycles them.
        std::hint::black_box(kernel.gram_lower_with_cache(x.as_ref())).recycle();
    }
    println!(
        "gram (lower)    {:8.2} ms",
        t.elapsed().as_secs_f64() * 1e3 / reps as f64
    );
    let mut k = kernel.gram(x.as_ref());
    for i in 0..n {
        k[(i, i)] += 0.1;
    }
    // The floor in the evaluation's own conditions: buffers recycled as the
    // evaluation recycles them, the inverse's lower triangle only.
    let t = Instant::now();
    for _ in 0..reps {
        recycle(std::hint::black_box(Cholesky::factor_shifted(&k, 0.0).unwrap()).l);
    }
    let factor = t.elapsed().as_secs_f64() * 1e3 / reps as f64;
    println!("factor          {factor:8.2} ms");
    let c = Cholesky::factor(k.clone()).unwrap();
    let t = Instant::now();
    for _ in 0..reps {
        recycle(std::hint::black_box(c.inverse_lower()));
    }
    let inverse = t.elapsed().as_secs_f64() * 1e3 / reps as f64;
    println!("inverse         {inverse:8.2} ms");
    let t = Instant::now();
    for _ in 0..reps {
        std::hint::black_box(
            log_marginal_likelihood(GpProblem::new(&kernel, 0.1, x.as_ref(), y.as_ref()), false)
                .unwrap(),
        );
    }
    println!(
        "lml only        {:8.2} ms",
        t.elapsed().as_secs_f64() * 1e3 / reps as f64
    );
    let t = Instant::now();
    for _ in 0..reps {
        std::hint::black_box(
            log_marginal_likelihood(GpProblem::new(&kernel, 0.1, x.as_ref(), y.as_ref()), true)
                .unwrap(),
        );
    }
    let evaluation = t.elapsed().as_secs_f64() * 1e3 / reps as f64;
    println!("lml + gradient  {evaluation:8.2} ms");
    println!(
        "ratio to the faer floor (factor + inverse): {:.2}",
        evaluation / (factor + inverse)
    );
    // The same ratio from interleaved pairs (floor, then evaluation), so
    // that the machine's drift between the timings above cancels out.
    let pairs = 3 * reps;
    let mut ratios: Vec<f64> = (0..pairs)
        .map(|_| {
            let t = Instant::now();
            let c = Cholesky::factor_shifted(&k, 0.0).unwrap();
            recycle(std::hint::black_box(c.inverse_lower()));
            recycle(c.l);
            let floor = t.elapsed().as_secs_f64();
            let t = Instant::now();
            std::hint::black_box(
                log_marginal_likelihood(GpProblem::new(&kernel, 0.1, x.as_ref(), y.as_ref()), true)
                    .unwrap(),
            );
            t.elapsed().as_secs_f64() / floor
        })
        .collect();
    ratios.sort_by(f64::total_cmp);
    println!(
        "ratio, median of {pairs} interleaved pairs: {:.2} (quartiles {:.2}, {:.2})",
        ratios[pairs / 2],
        ratios[pairs / 4],
        ratios[3 * pairs / 4]
    );
}

//! The iterative exact GP beside the dense one on a table: z-scores the
//! first `N` rows of a CSV whose last three columns are the targets, fits
//! the dense exact GP (RBF-ARD, outputs sharing kernel and noise) on the
//! first `FIT_ROWS` of them (default `N`), then evaluates the log marginal
//! likelihood and its gradient on all `N` at those hyperparameters, densely
//! and by iterative solves for each preconditioner rank, probe count and
//! seed asked, and prints one line each: the LML difference, the gradient's
//! cosine with the dense one, the CG iterations and the seconds of each
//! evaluation (`DENSE=0` skips the dense evaluation). `FIT_ROWS = 0`
//! evaluates at the start policy's first base instead (variance 1,
//! lengthscale 1, noise 0.01). `VARIANCE_RANKS=64,256` also conditions the
//! GP on the N rows densely and by iterative solves with a Krylov basis of
//! each rank, predicts the next `TEST_ROWS` rows (default 2000) and prints
//! the variances' largest and median relative excess over the exact ones,
//! the means' largest difference and the seconds each took.
//!
//! `cargo run --release -p gpodo-regressors --example iterative_check --
//! FILE.csv N RANK:PROBES[:SEED][,…] [FIT_ROWS]`

use std::time::Instant;

use anyhow::{Context, bail};
use gpodo_regressors::GpProblem;
use gpodo_regressors::exact_gp::iterative::{
    IterativeSettings, IterativeSolver, log_marginal_likelihood_iterative,
};
use gpodo_regressors::exact_gp::likelihood::log_marginal_likelihood;
use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams};
use gpodo_traits::ResidualRegressor;

mod support;
use support::table::Table;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let (path, n, runs, fit_rows) = match args.as_slice() {
        [_, path, n, runs] => (path, n, runs, None),
        [_, path, n, runs, fit] => (path, n, runs, Some(fit)),
        _ => bail!("usage: iterative_check FILE.csv N RANK:PROBES[:SEED][,…] [FIT_ROWS]"),
    };
    let n: usize = n.parse().context("N")?;
    let fit_rows: usize = fit_rows
        .map(|f| f.parse())
        .transpose()
        .context("FIT_ROWS")?
        .unwrap_or(n);
    let test_rows: usize = std::env::var("TEST_ROWS")
        .ok()
        .map(|v| v.parse())
        .transpose()
        .context("TEST_ROWS")?
        .unwrap_or(2000);
    let variance_ranks: Vec<usize> = std::env::var("VARIANCE_RANKS")
        .ok()
        .map(|v| v.split(',').map(str::parse).collect::<Result<_, _>>())
        .transpose()
        .context("VARIANCE_RANKS")?
        .unwrap_or_default();
    let held_out = if variance_ranks.is_empty() {
        0
    } else {
        test_rows
    };
    let table = Table::read(path, n + held_out, n)?;
    let z = &table.rows;
    let n = n.min(z.len());
    let m = z.len() - n;
    let d = table.inputs();
    let data = table.dataset(fit_rows.clamp(2, n))?;
    // FIT_ROWS = 0: no fit, the start policy's first base (variance 1,
    // lengthscale 1, noise 0.01) instead.
    let t = Instant::now();
    let mut gp = ExactGp::new(ExactGpParams {
        standardize: false,
        optimize: fit_rows > 0,
        init: gpodo_regressors::kernels::KernelInit {
            lengthscale: (fit_rows == 0).then_some(1.0),
            ..Default::default()
        },
        ..ExactGpParams::default()
    })?;
    gp.fit(&data)?;
    println!(
        "dense fit on {} rows: {:.1} s",
        data.len(),
        t.elapsed().as_secs_f64()
    );
    let state = gp.state().context("no state")?;
    let group = &state.groups[0];
    let x = faer::Mat::from_fn(n, d, |i, j| z[i][j]);
    let y = faer::Mat::from_fn(n, 3, |i, j| z[i][d + j]);
    let t = Instant::now();
    let dense = if std::env::var("DENSE").as_deref() == Ok("0") {
        None
    } else {
        Some(log_marginal_likelihood(
            GpProblem::new(&group.kernel, group.noise_variance, x.as_ref(), y.as_ref()),
            true,
        )?)
    };
    let dense_secs = t.elapsed().as_secs_f64();
    let dense_lml = dense.as_ref().map_or(f64::NAN, |e| e.lml);
    let g0 = dense.and_then(|e| e.gradient).unwrap_or_default();
    println!(
        "n = {n}: dense LML {dense_lml:.3} ({dense_secs:.2} s per evaluation with its gradient; noise {:.4}; gradient norm {:.3e})",
        group.noise_variance,
        g0.iter().map(|v| v * v).sum::<f64>().sqrt()
    );
    // Buffers are kept from one evaluation to the next, as in a fit: list a
    // setting twice to time it with its buffers warm.
    let _spare = gpodo_regressors::dense::SpareLimit::at_least(3 * n * n * 8);
    for run in runs.split(',') {
        let parts: Vec<&str> = run.split(':').collect();
        let [rank, probes, seed] = match parts.as_slice() {
            [r, p] => [*r, *p, "0"],
            [r, p, s] => [*r, *p, *s],
            _ => bail!("RANK:PROBES[:SEED]"),
        };
        let settings = IterativeSettings {
            preconditioner_rank: rank.parse()?,
            probes: probes.parse()?,
            seed: seed.parse()?,
            ..IterativeSettings::default()
        };
        let solver = IterativeSolver::new(x.nrows(), settings);
        let t = Instant::now();
        let it = log_marginal_likelihood_iterative(
            GpProblem::new(&group.kernel, group.noise_variance, x.as_ref(), y.as_ref()),
            true,
            &solver,
            || false,
        )?;
        let g = it.gradient.unwrap_or_default();
        let dot: f64 = g.iter().zip(&g0).map(|(a, b)| a * b).sum();
        let cosine = dot
            / (g.iter().map(|v| v * v).sum::<f64>().sqrt()
                * g0.iter().map(|v| v * v).sum::<f64>().sqrt());
        println!(
            "rank {rank} probes {probes}: LML {:.3} (Δ {:+.3}), gradient cosine {cosine:.5}, {} CG iterations, {:.2} s",
            it.lml,
            it.lml - dense_lml,
            it.iterations,
            t.elapsed().as_secs_f64()
        );
    }
    if !variance_ranks.is_empty() && m > 0 {
        use gpodo_regressors::exact_gp::posterior::Posterior;
        let xs = faer::Mat::from_fn(m, d, |i, j| z[n + i][j]);
        let t = Instant::now();
        let exact = Posterior::new(
            group.kernel.clone(),
            group.noise_variance,
            x.clone(),
            y.clone(),
        )?;
        let exact_moments = exact.predict(xs.as_ref());
        println!(
            "dense posterior and {m} predictions: {:.2} s",
            t.elapsed().as_secs_f64()
        );
        for rank in variance_ranks {
            let solver = IterativeSolver::new(n, IterativeSettings::default());
            let t = Instant::now();
            let posterior = Posterior::iterative(
                group.kernel.clone(),
                group.noise_variance,
                x.clone(),
                y.clone(),
                &solver,
                rank,
            )?;
            let built = t.elapsed().as_secs_f64();
            let moments = posterior.predict(xs.as_ref());
            let mut excess: Vec<f64> = (0..m)
                .map(|i| {
                    let (a, b) = (
                        moments.latent_variance[i] + moments.noise_variance,
                        exact_moments.latent_variance[i] + exact_moments.noise_variance,
                    );
                    (a - b) / b
                })
                .collect();
            excess.sort_by(f64::total_cmp);
            let mean_gap = (0..m)
                .flat_map(|i| (0..3).map(move |j| (i, j)))
                .map(|(i, j)| (moments.mean[(i, j)] - exact_moments.mean[(i, j)]).abs())
                .fold(0.0, f64::max);
            println!(
                "variance rank {rank}: predictive variance excess over exact: median {:.2e}, largest {:.2e}, smallest {:.2e}; means apart by {mean_gap:.2e} at most; {built:.2} s to condition, {:.2} s to predict",
                excess[m / 2],
                excess[m - 1],
                excess[0],
                t.elapsed().as_secs_f64() - built
            );
        }
    }
    Ok(())
}

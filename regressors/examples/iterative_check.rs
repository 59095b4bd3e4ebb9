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
//! lengthscale 1, noise 0.01).
//!
//! `cargo run --release -p gpodo-regressors --example iterative_check --
//! FILE.csv N RANK:PROBES[:SEED][,…] [FIT_ROWS]`

use std::time::Instant;

use anyhow::{Context, bail};
use gpodo_regressors::exact_gp::iterative::{
    IterativeSettings, IterativeSolver, log_marginal_likelihood_iterative,
};
use gpodo_regressors::exact_gp::likelihood::log_marginal_likelihood;
use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams};
use gpodo_traits::{ResidualDataset, ResidualRegressor, SampleMatrix};

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
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {path}"))?;
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .context("empty file")?
        .split(',')
        .map(String::from)
        .collect();
    let cols = header.len();
    let rows: Vec<Vec<f64>> = lines
        .take(n)
        .map(|l| {
            l.split(',')
                .map(|v| v.trim().parse::<f64>())
                .collect::<Result<Vec<_>, _>>()
        })
        .collect::<Result<_, _>>()
        .context("parsing the rows")?;
    let d = cols - 3;
    let n = rows.len();
    // Every column z-scored over the N rows.
    let mut z = rows.clone();
    for c in 0..cols {
        let mean = rows.iter().map(|r| r[c]).sum::<f64>() / n as f64;
        let sd = (rows.iter().map(|r| (r[c] - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
        let sd = if sd < 1e-12 { 1.0 } else { sd };
        for r in &mut z {
            r[c] = (r[c] - mean) / sd;
        }
    }
    let head = &z[..fit_rows.clamp(2, n)];
    let data = ResidualDataset::new(
        SampleMatrix::from_row_major(
            head.len(),
            d,
            head.iter().flat_map(|r| r[..d].to_vec()).collect(),
        )?,
        SampleMatrix::from_row_major(
            head.len(),
            3,
            head.iter().flat_map(|r| r[d..].to_vec()).collect(),
        )?,
        header[..d].to_vec(),
        header[d..].to_vec(),
    )?;
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
        head.len(),
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
            &group.kernel,
            group.noise_variance,
            x.as_ref(),
            y.as_ref(),
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
            &group.kernel,
            group.noise_variance,
            x.as_ref(),
            y.as_ref(),
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
    Ok(())
}

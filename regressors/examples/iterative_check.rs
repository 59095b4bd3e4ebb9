//! The iterative exact GP beside the dense one on a table: fits the dense
//! exact GP (RBF-ARD, outputs sharing kernel and noise) on the first `N`
//! rows of a CSV whose last three columns are the targets, then evaluates
//! the log marginal likelihood and its gradient at the optimum both ways,
//! for each preconditioner rank and probe count asked, and prints one line
//! each: the LML difference, the gradient's cosine with the dense one, the
//! CG iterations and the seconds of each evaluation.
//!
//! `cargo run --release -p gpodo-regressors --example iterative_check --
//! FILE.csv N RANK:PROBES[,RANK:PROBES…]`

use std::time::Instant;

use anyhow::{Context, bail};
use gpodo_regressors::dense::to_faer;
use gpodo_regressors::exact_gp::iterative::{
    IterativeSettings, IterativeSolver, log_marginal_likelihood_iterative,
};
use gpodo_regressors::exact_gp::likelihood::log_marginal_likelihood;
use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams};
use gpodo_traits::{ResidualDataset, ResidualRegressor, SampleMatrix};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let [_, path, n, runs] = args.as_slice() else {
        bail!("usage: iterative_check FILE.csv N RANK:PROBES[,RANK:PROBES…]");
    };
    let n: usize = n.parse().context("N")?;
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
    let inputs: Vec<f64> = rows.iter().flat_map(|r| r[..d].to_vec()).collect();
    let targets: Vec<f64> = rows.iter().flat_map(|r| r[d..].to_vec()).collect();
    let data = ResidualDataset::new(
        SampleMatrix::from_row_major(rows.len(), d, inputs)?,
        SampleMatrix::from_row_major(rows.len(), 3, targets)?,
        header[..d].to_vec(),
        header[d..].to_vec(),
    )?;
    let t = Instant::now();
    let mut gp = ExactGp::new(ExactGpParams::default())?;
    gp.fit(&data)?;
    println!(
        "dense fit on {} rows: {:.1} s",
        rows.len(),
        t.elapsed().as_secs_f64()
    );
    let state = gp.state().context("no state")?;
    let (x, y) = (to_faer(&state.x_train), to_faer(&state.y_train));
    let group = &state.groups[0];
    let t = Instant::now();
    let dense = log_marginal_likelihood(
        &group.kernel,
        group.noise_variance,
        x.as_ref(),
        y.as_ref(),
        true,
    )?;
    let g0 = dense.gradient.clone().unwrap_or_default();
    println!(
        "dense: LML {:.3} ({:.2} s per evaluation with its gradient; noise {:.4}; gradient norm {:.3e})",
        dense.lml,
        t.elapsed().as_secs_f64(),
        group.noise_variance,
        g0.iter().map(|v| v * v).sum::<f64>().sqrt()
    );
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
            it.lml - dense.lml,
            it.iterations,
            t.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

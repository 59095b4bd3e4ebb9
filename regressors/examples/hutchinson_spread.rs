//! How far an iterative log-likelihood estimate can be off, from the exact
//! spectrum: z-scores the first `N` rows of a CSV whose last three columns
//! are the targets, takes the RBF-ARD kernel at the start policy's
//! lengthscale √d with noise `NOISE` (or, without `NOISE`, fits the dense
//! exact GP there), and for each preconditioner rank `k` computes
//! `A = P^{-1/2} K_y P^{-1/2}` (`P` the rank-`k` pivoted-Cholesky
//! preconditioner) and its eigenvalues. Hutchinson's estimator of
//! `tr log A` has variance `2‖log A‖²_F` per Gaussian probe and
//! `2 Σ_{i≠j} (log A)²_ij` per Rademacher probe; it prints both standard
//! deviations and the log-likelihood's standard error at 16 probes
//! (`p/2 = 1.5` times the log-determinant's). Dense eigendecompositions:
//! about a minute at N = 2000.
//!
//! `[NOISE=0.9] cargo run --release -p gpodo-regressors --example
//! hutchinson_spread -- FILE.csv N [RANK,…]`

use anyhow::{Context, bail};
use gpodo_regressors::exact_gp::iterative::pivoted_cholesky::pivoted_cholesky;
use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams};
use gpodo_traits::ResidualRegressor;
use nalgebra::{DMatrix, DVector, SymmetricEigen};

mod support;
use support::table::Table;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let (path, n, ranks) = match args.as_slice() {
        [_, path, n] => (path, n, "0,100,300,600,1000"),
        [_, path, n, ranks] => (path, n, ranks.as_str()),
        _ => bail!("usage: hutchinson_spread FILE.csv N [RANK,…]"),
    };
    let n: usize = n.parse().context("N")?;
    let ranks: Vec<usize> = ranks
        .split(',')
        .map(str::parse)
        .collect::<Result<_, _>>()
        .context("RANK,…")?;
    let noise: Option<f64> = std::env::var("NOISE")
        .ok()
        .map(|v| v.parse())
        .transpose()
        .context("NOISE")?;
    let table = Table::read(path, n, n)?;
    let (n, d) = (table.rows.len(), table.inputs());
    let data = table.dataset(n)?;
    let mut gp = ExactGp::new(ExactGpParams {
        standardize: false,
        optimize: noise.is_none(),
        noise_variance: noise.unwrap_or(0.01),
        ..ExactGpParams::default()
    })?;
    gp.fit(&data)?;
    let group = &gp.state().context("no state")?.groups[0];
    let s2 = group.noise_variance;
    let x = faer::Mat::from_fn(n, d, |i, j| table.rows[i][j]);
    let k = group.kernel.gram(x.as_ref());
    let ky = DMatrix::from_fn(n, n, |i, j| k[(i, j)] + if i == j { s2 } else { 0.0 });
    println!("n = {n}, noise variance {s2:.4}");
    for rank in ranks {
        let a = if rank == 0 {
            ky.clone()
        } else {
            let l = pivoted_cholesky(k.as_ref(), rank, 1e-10);
            let l = DMatrix::from_fn(n, l.ncols(), |i, j| l[(i, j)]);
            let mut p = &l * l.transpose();
            for i in 0..n {
                p[(i, i)] += s2;
            }
            let ep = SymmetricEigen::new(p);
            let inv_sqrt = &ep.eigenvectors
                * DMatrix::from_diagonal(&ep.eigenvalues.map(|v| 1.0 / v.sqrt()))
                * ep.eigenvectors.transpose();
            &inv_sqrt * &ky * &inv_sqrt
        };
        let e = SymmetricEigen::new(a);
        let logs: DVector<f64> = e.eigenvalues.map(f64::ln);
        let frobenius2: f64 = logs.iter().map(|v| v * v).sum();
        // (log A)_ii = Σ_k V_ik² log λ_k.
        let diagonal2: f64 = (0..n)
            .map(|i| {
                (0..n)
                    .map(|c| e.eigenvectors[(i, c)].powi(2) * logs[c])
                    .sum::<f64>()
                    .powi(2)
            })
            .sum();
        let gaussian = (2.0 * frobenius2).sqrt();
        let rademacher = (2.0 * (frobenius2 - diagonal2)).sqrt();
        println!(
            "rank {rank}: tr log A {:.2}, {} eigenvalues with |log λ| > 1; per probe sd {gaussian:.2} (Gaussian), {rademacher:.2} (Rademacher); LML standard error at 16 probes {:.2} / {:.2} nats",
            logs.iter().sum::<f64>(),
            logs.iter().filter(|v| v.abs() > 1.0).count(),
            1.5 * gaussian / 4.0,
            1.5 * rademacher / 4.0,
        );
    }
    Ok(())
}

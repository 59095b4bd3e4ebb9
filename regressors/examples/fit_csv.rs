//! The gpodo side of the peer benchmark (`bench/peers/`): fits the exact GP
//! (RBF-ARD, outputs sharing kernel and noise, L-BFGS) on a CSV written by
//! `fit_peers.py --write-data` (columns `x0..x{D-1}, y0, y1, y2`, already
//! z-scored) with gpodo's default start policy (lengthscale 1, √D and the
//! median distance, raced), or from the peers' starting point alone
//! (variance 1, lengthscales √D, noise 0.01) when `GPODO_LENGTHSCALE` is
//! set to √D, and prints one JSON line like the peers do.
//!
//! `cargo run --release -p gpodo-regressors --example fit_csv -- FILE.csv`
//! (`GPODO_LENGTHSCALE`, `GPODO_GRAD_TOL`, `GPODO_COST_TOL` and
//! `GPODO_LBFGS_MEMORY` override the start, the stopping rules and the
//! L-BFGS memory; 10 is the peers' scipy default; `GPODO_KERNEL` sets a
//! kernel expression, e.g. `rbf + linear`; `GPODO_RACE` and `GPODO_HALVE`
//! set the start race's iterations and when it halves,
//! `GPODO_PERTURBATIONS` the perturbed candidates per base (2; with
//! `GPODO_LENGTHSCALE` and 0, one start alone, the peers' own), `GPODO_MAX_ITERS`
//! the iteration limit (1000); `GPODO_TRACE=1` prints every optimiser iteration to
//! stderr as `run iteration LML seconds`). The JSON line lists every candidate
//! start with its start and final LML, evaluations and iterations.

use std::time::Instant;

use anyhow::{Context, bail};
use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams};
use gpodo_traits::{FitProgress, ResidualDataset, ResidualRegressor, SampleMatrix};

/// Prints every optimiser iteration to stderr, with the seconds since the
/// fit began.
struct Trace(Instant);

impl FitProgress for Trace {
    fn iteration(&self, start: usize, iteration: u64, objective: f64) -> std::ops::ControlFlow<()> {
        let seconds = self.0.elapsed().as_secs_f64();
        eprintln!("{start} {iteration} {objective} {seconds:.3}");
        std::ops::ControlFlow::Continue(())
    }
}

/// The environment variable `name` parsed, when it is set.
fn env<T>(name: &str) -> anyhow::Result<Option<T>>
where
    T: std::str::FromStr,
    T::Err: std::error::Error + Send + Sync + 'static,
{
    std::env::var(name)
        .ok()
        .map(|v| {
            v.parse()
                .with_context(|| format!("{name}={v}: not a number"))
        })
        .transpose()
}

fn main() -> anyhow::Result<()> {
    let Some(path) = std::env::args().nth(1) else {
        bail!("usage: fit_csv FILE.csv (written by bench/peers/fit_peers.py --write-data)");
    };
    let mut reader = csv::Reader::from_path(&path).with_context(|| format!("opening {path}"))?;
    let header: Vec<String> = reader.headers()?.iter().map(str::to_string).collect();
    let d = header.iter().filter(|h| h.starts_with('x')).count();
    let p = header.len() - d;
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for (line, record) in reader.records().enumerate() {
        let record = record.with_context(|| format!("{path}: line {}", line + 2))?;
        for (j, field) in record.iter().enumerate() {
            let v: f64 = field.parse().with_context(|| {
                format!(
                    "{path}: line {}, column {}: expected a number",
                    line + 2,
                    j + 1
                )
            })?;
            if j < d { xs.push(v) } else { ys.push(v) }
        }
    }
    let n = xs.len() / d;
    let data = ResidualDataset::new(
        SampleMatrix::from_row_major(n, d, xs)?,
        SampleMatrix::from_row_major(n, p, ys)?,
        header[..d].to_vec(),
        header[d..].to_vec(),
    )?;
    let mut params = ExactGpParams::default();
    params.hyperopt.max_iters = 1000;
    if let Some(tol) = env("GPODO_GRAD_TOL")? {
        params.hyperopt.gradient_tolerance = tol;
    }
    if let Some(l) = env("GPODO_LENGTHSCALE")? {
        params.init.lengthscale = Some(l);
    }
    if let Some(tol) = env("GPODO_COST_TOL")? {
        params.hyperopt.relative_cost_tolerance = tol;
    }
    if let Some(m) = env("GPODO_LBFGS_MEMORY")? {
        params.hyperopt.lbfgs_memory = m;
    }
    if let Ok(expr) = std::env::var("GPODO_KERNEL") {
        params.kernel = gpodo_regressors::kernels::KernelExpr::parse(&expr)?.into();
    }
    if let Some(r) = env("GPODO_RACE")? {
        params.hyperopt.start.race_iterations = r;
    }
    if let Some(m) = env("GPODO_MAX_ITERS")? {
        params.hyperopt.max_iters = m;
    }
    if let Some(h) = env("GPODO_HALVE")? {
        params.hyperopt.start.halve_after = Some(h);
    }
    if let Some(k) = env("GPODO_PERTURBATIONS")? {
        params.hyperopt.start.perturbations = k;
    }
    let mut gp = ExactGp::new(params)?;
    if std::env::var("GPODO_TRACE").is_ok_and(|v| v == "1") {
        gp.set_progress(Some(std::sync::Arc::new(Trace(Instant::now()))));
    }
    let start = Instant::now();
    let report = gp.fit(&data)?;
    let seconds = start.elapsed().as_secs_f64();
    let lengthscales: Vec<f64> = report
        .parameters
        .iter()
        .filter(|(k, _)| k.contains("lengthscale"))
        .map(|(_, v)| *v)
        .collect();
    let get = |name: &str| {
        report
            .parameters
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| *v)
    };
    println!(
        "{}",
        serde_json::json!({
            "impl": format!("gpodo {}", env!("CARGO_PKG_VERSION")),
            "n": n, "d": d, "seconds": seconds,
            "lml": report.objective, "evaluations": report.evaluations,
            "variance": get("rbf.variance"), "noise_variance": get("noise_variance"),
            "lengthscales": lengthscales,
            "starts": report.starts,
        })
    );
    Ok(())
}

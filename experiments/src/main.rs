//! `gpodo`: run experiments and simulate the testbed.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use clap::{Parser, Subcommand};
use gpodo_datasets::log::write_log_csv;
use gpodo_datasets::sim::preset::{Preset, SimulatorConfig};
use gpodo_experiments::bench::run_bench;
use gpodo_experiments::bench_report::write_bench_report;
use gpodo_experiments::config::ExperimentConfig;
use gpodo_experiments::pipeline::run_experiment;
use gpodo_experiments::report::write_report;

/// Learning odometry residuals with Gaussian processes, and using them to
/// decide when a rover must look.
#[derive(Parser)]
#[command(name = "gpodo", version, about)]
struct Cli {
    /// Print only warnings and errors.
    #[arg(long, short, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run an experiment file and write results/NAME/report.md and metrics.json.
    Run {
        /// The experiment YAML.
        file: PathBuf,
        /// Output folder (default: results/NAME, NAME from the file).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Benchmark every regressor of an experiment file on the same data
    /// (fit time, prediction and online-update latency, scores, learning
    /// curves) against the exact-GP row; writes results/NAME/bench.md and
    /// bench.json.
    Bench {
        /// The experiment YAML.
        file: PathBuf,
        /// Output folder (default: results/NAME).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Simulate the testbed and write every run as CSV (trajectory format).
    Simulate {
        /// Simulator preset.
        #[arg(long, default_value = "exoter-prl")]
        preset: Preset,
        /// Seed of every random draw.
        #[arg(long, default_value_t = 7)]
        seed: u64,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Override the number of training runs.
        #[arg(long)]
        training_runs: Option<usize>,
        /// Override the training run duration (s).
        #[arg(long)]
        training_run_secs: Option<f64>,
    },
}

fn run(file: &Path, out: Option<PathBuf>) -> anyhow::Result<()> {
    let config = ExperimentConfig::from_path(file)?;
    let base = file.parent().unwrap_or_else(|| Path::new("."));
    let results =
        run_experiment(&config, base).with_context(|| format!("experiment {}", file.display()))?;
    let dir = out.unwrap_or_else(|| PathBuf::from("results").join(&config.name));
    let (md, json) =
        write_report(&results, &dir).with_context(|| format!("writing {}", dir.display()))?;
    for r in &results.regressors {
        tracing::info!(
            regressor = %r.label,
            rmse = r.evaluation.pooled.rmse,
            mae = r.evaluation.pooled.mae,
            "test scores"
        );
    }
    println!("wrote {} and {}", md.display(), json.display());
    Ok(())
}

fn bench(file: &Path, out: Option<PathBuf>) -> anyhow::Result<()> {
    let config = ExperimentConfig::from_path(file)?;
    let base = file.parent().unwrap_or_else(|| Path::new("."));
    let results =
        run_bench(&config, base).with_context(|| format!("benchmark {}", file.display()))?;
    let dir = out.unwrap_or_else(|| PathBuf::from("results").join(&config.name));
    let (md, json) =
        write_bench_report(&results, &dir).with_context(|| format!("writing {}", dir.display()))?;
    println!("wrote {} and {}", md.display(), json.display());
    Ok(())
}

fn simulate(
    preset: Preset,
    seed: u64,
    out: &Path,
    training_runs: Option<usize>,
    training_run_secs: Option<f64>,
) -> anyhow::Result<()> {
    let mut config = SimulatorConfig::preset(preset, seed);
    if let Some(n) = training_runs {
        config.training_runs = n;
    }
    if let Some(s) = training_run_secs {
        config.training_run_secs = s;
    }
    let testbed = config.simulate()?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    for log in testbed.train.iter().chain(&testbed.test) {
        let (csv, camera) = write_log_csv(log, out)?;
        println!(
            "wrote {} ({} samples, {:.1} m) and {}",
            csv.display(),
            log.samples.len(),
            log.path_length_m(),
            camera.display()
        );
    }
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let level = if cli.quiet { "warn" } else { "info" };
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(level)),
        )
        .with_writer(std::io::stderr)
        .init();
    match cli.command {
        Command::Run { file, out } => run(&file, out),
        Command::Bench { file, out } => bench(&file, out),
        Command::Simulate {
            preset,
            seed,
            out,
            training_runs,
            training_run_secs,
        } => simulate(preset, seed, &out, training_runs, training_run_secs),
    }
}

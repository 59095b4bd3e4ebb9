//! `gpodo`: run experiments and sweeps, plan them, report them, benchmark
//! regressors, save a trained model and predict with it, simulate the
//! testbed.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use clap::{Parser, Subcommand};
use gpodo_experiments::commands::simulate::{SimulateOptions, simulate_to};
use gpodo_experiments::config::ExperimentConfig;
use gpodo_experiments::execute::bench::run_bench;
use gpodo_experiments::execute::models::{fit_model, predict_csv};
use gpodo_experiments::plan::load_plan;
use gpodo_experiments::report::bench::write_bench_report;
use gpodo_experiments::report::sweep::write_sweep_report;
use gpodo_experiments::runner::{RunOptions, Shard, results_dir, run_sweep};
use gpodo_testbed::sim::preset::Preset;

/// Learning odometry residuals with Gaussian processes, and using them to
/// decide when a rover must look.
#[derive(Parser)]
#[command(name = "gpodo", version, about)]
struct Cli {
    /// Print only warnings and errors, and no progress bar.
    #[arg(long, short, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run an experiment or sweep file: every run is appended to
    /// results/NAME/runs.jsonl; a single run also writes its full report
    /// (report.md, metrics.json, figures, trajectories), a sweep the
    /// ablation report.
    Run {
        /// The experiment YAML.
        file: PathBuf,
        /// Output folder (default: results/NAME).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Continue a sweep: skip the runs already recorded.
        #[arg(long, conflicts_with = "force")]
        resume: bool,
        /// Start over, replacing this shard's record.
        #[arg(long)]
        force: bool,
        /// Run the i-th of N deterministic slices (`i/N`, from 0). In a
        /// Slurm array task without it, shard SLURM_ARRAY_TASK_ID of the
        /// count the results folder's plan.json records.
        #[arg(long)]
        shard: Option<String>,
    },
    /// Print the runs a file expands to, without running them.
    Plan {
        /// The experiment YAML.
        file: PathBuf,
    },
    /// Write the sweep report of a results folder (merging shards, and
    /// naming missing and duplicate runs).
    Report {
        /// The results folder (results/NAME).
        dir: PathBuf,
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
    /// Fit one regressor of an experiment on its training rows, as `gpodo
    /// run` does, and save the trained model (with the experiment's input
    /// z-scoring and column names) for `gpodo predict` or on-board use.
    Fit {
        /// The experiment YAML.
        file: PathBuf,
        /// The regressor's label, as in the report (e.g. "exact GP: rbf").
        #[arg(long)]
        regressor: String,
        /// Where to write the model (e.g. model.gpodo).
        #[arg(long)]
        save: PathBuf,
    },
    /// Predict with a saved model: mean and variance per output for every
    /// row of a CSV whose header names the model's input columns (any
    /// order; other columns are ignored), e.g. results/NAME/residuals_test.csv.
    Predict {
        /// The model file.
        #[arg(long)]
        model: PathBuf,
        /// The input rows (CSV with a header, raw units).
        #[arg(long)]
        input: PathBuf,
        /// Where to write the predictions (CSV: mean_TARGET..., var_TARGET... per row).
        #[arg(long)]
        out: PathBuf,
    },
    /// Run a saved model as the robot would. Each joint-state message
    /// gives one odometry output (the motion model's twist corrected by
    /// the predicted residual, its covariance the predictive variance; the
    /// authors' mode for a |residual| model) on `/odom/gp`, and the motion
    /// model's alone on `/odom/wheel`. On ROS 2 (a build with the `ros2`
    /// feature) it subscribes to the topic map's joint states and IMU and
    /// publishes those topics and `/diagnostics`; with `--replay` it reads
    /// a recording instead and writes an MCAP (and with `--rows` the input
    /// rows as a CSV `gpodo predict` reads).
    Live {
        /// The model file (version 3, fitted from logs, bags or the
        /// simulator: it says how its rows were made).
        #[arg(long)]
        model: PathBuf,
        /// The robot's rover description (YAML).
        #[arg(long)]
        rover: PathBuf,
        /// The topic map: the joint states, the IMU and how their joints
        /// map to the rover's.
        #[arg(long)]
        topics: PathBuf,
        /// A recording to replay (MCAP or ROS 1, as `gpodo import` reads)
        /// instead of subscribing on ROS 2.
        #[arg(long, requires = "out")]
        replay: Option<PathBuf>,
        /// Where a replay writes the odometry (MCAP).
        #[arg(long, requires = "replay")]
        out: Option<PathBuf>,
        /// Where a replay writes the input rows (CSV).
        #[arg(long, requires = "replay")]
        rows: Option<PathBuf>,
        /// Replay at the recorded speed (default: as fast as it can).
        #[arg(long, requires = "replay")]
        realtime: bool,
        /// The DDS domain on ROS 2 (default: $ROS_DOMAIN_ID, else 0).
        #[arg(long, conflicts_with = "replay")]
        domain_id: Option<u16>,
        /// On ROS 2, stop after this many outputs.
        #[arg(long, conflicts_with = "replay")]
        max_outputs: Option<usize>,
        /// On ROS 2, stop when no input came for this many seconds after
        /// the first.
        #[arg(long, conflicts_with = "replay")]
        idle_exit_secs: Option<f64>,
        /// On ROS 2, an interface DDS may use, by address (repeatable;
        /// default all): `--dds-interface 127.0.0.1` keeps it on this
        /// machine.
        #[arg(long = "dds-interface", conflicts_with = "replay")]
        dds_interfaces: Vec<std::net::IpAddr>,
        /// A gate file: the frame gate in front of a stereo VO, and the
        /// online learner of that VO's poses (see experiments/README.md,
        /// "The gate file"). In a replay, each pair the gate forwards is
        /// answered with the recording's own VO odometry at its stamp.
        #[arg(long)]
        gate: Option<PathBuf>,
        /// The online learner's checkpoint: resumed if it is there, and
        /// written atomically on the gate file's period and on stop
        /// (overrides the file's `checkpoint.path`).
        #[arg(long, requires = "gate")]
        checkpoint: Option<PathBuf>,
        /// In a gated replay, where every decision is written (CSV: the
        /// pair's stamp, processed or skipped, the reason, the
        /// keyframe-threshold scale asked for, the tracking state).
        #[arg(long, requires_all = ["gate", "replay"])]
        decisions: Option<PathBuf>,
    },
    /// Turn ROS bags into the rover-log CSV that `dataset: {kind: logs}`
    /// reads, through a topic map (which topic is the IMU, the ground
    /// truth, the joints; the common clock's rate; the longest gap bridged).
    Import {
        /// The bags (MCAP or ROS 1).
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// The topic map (YAML).
        #[arg(long)]
        topics: PathBuf,
        /// The folder to write NAME.csv into (NAME: each bag's file stem).
        #[arg(long)]
        out: PathBuf,
        /// The robot's description (kinematics/rovers/*.yaml): checks the
        /// wheels' units by comparing the weighted-Jacobian model's speed
        /// with the ground truth's.
        #[arg(long)]
        rover: Option<PathBuf>,
    },
    /// Look inside a ROS bag (ROS 2 MCAP or ROS 1 .bag, recognised by its
    /// first bytes).
    Bag {
        #[command(subcommand)]
        command: BagCommand,
    },
    /// Simulate the testbed and write every run as a rover-log CSV or as a
    /// ROS 2 MCAP bag (with the topic map that imports it back); with
    /// `--camera`, ExoTeR's rendered stereo camera too.
    Simulate {
        /// `csv` (rover-log CSV), `mcap` (ROS 2 bag) or `png` (rover-log
        /// CSV and a folder of PNG stereo pairs per run; needs `--camera`).
        #[arg(long, value_enum, default_value_t = SimulateFormat::Csv)]
        format: SimulateFormat,
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
        /// Cut the test traverse after this many seconds.
        #[arg(long)]
        test_max_secs: Option<f64>,
        /// MCAP only: record wheel positions in encoder ticks, this many
        /// per motor turn (default: the wheel's rad).
        #[arg(long)]
        wheel_ticks_per_turn: Option<f64>,
        /// MCAP only: motor turns per wheel turn, for ticks and motor
        /// rates.
        #[arg(long, default_value_t = 1.0)]
        wheel_gear_ratio: f64,
        /// MCAP only: the unit of recorded wheel rates.
        #[arg(long, value_enum, default_value_t = WheelRateArg::RadPerS)]
        wheel_rate: WheelRateArg,
        /// Leave the IMU out (a robot without one): no IMU topic in a bag,
        /// no IMU columns in a log.
        #[arg(long)]
        no_imu: bool,
        /// Render ExoTeR's mast stereo camera (rectified mono8 pairs with
        /// their CameraInfo in a bag, or PNG pairs with `camera_info` YAML).
        #[arg(long)]
        camera: bool,
        /// With `--camera`: the fraction of the Bumblebee2's 1024 × 768.
        #[arg(long, default_value_t = 0.5)]
        camera_scale: f64,
        /// With `--camera`: frames per second.
        #[arg(long, default_value_t = 2.5)]
        camera_fps: f64,
        /// With `--camera`, MCAP only: a VO trajectory on `/vo/pose`, the
        /// ground truth at each frame (what `gpodo live --gate --replay`
        /// answers forwarded pairs with, standing in for the SLAM behind
        /// the gate).
        #[arg(long, requires = "camera")]
        vo_ground_truth: bool,
    },
}

/// The unit `gpodo simulate` records wheel rates in.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum WheelRateArg {
    /// rad/s of the wheel (ROS's unit).
    RadPerS,
    /// Revolutions per minute of the motor, before the gearbox.
    Rpm,
    /// rad/min of the motor, before the gearbox.
    RadPerMin,
}

/// What `gpodo simulate` writes.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum SimulateFormat {
    /// Rover-log CSV (the `logs` dataset).
    Csv,
    /// ROS 2 MCAP bags (the `bags` dataset) and `topics.yaml`.
    Mcap,
    /// Rover-log CSV and PNG stereo pairs (with `--camera`).
    Png,
}

#[derive(Subcommand)]
enum BagCommand {
    /// Topics, types, message counts, rates and duration (what `ros2 bag
    /// info` shows), and what a topic map needs: each topic's frame ids, a
    /// `JointState`'s joint names, a TF topic's parent → child pairs.
    Info {
        /// The bag.
        file: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        /// Skip damaged MCAP chunks and report what they held, instead of
        /// stopping at the first.
        #[arg(long)]
        skip_damaged: bool,
    },
}

fn run(
    file: &Path,
    out: Option<PathBuf>,
    resume: bool,
    force: bool,
    shard: Option<String>,
    quiet: bool,
) -> anyhow::Result<()> {
    let plan = load_plan(file)?;
    let shard = shard.as_deref().map(Shard::parse).transpose()?;
    let slurm_task = match std::env::var("SLURM_ARRAY_TASK_ID") {
        Ok(id) => Some(id.trim().parse::<usize>().with_context(|| {
            format!("SLURM_ARRAY_TASK_ID `{id}`: expected a task index from 0")
        })?),
        Err(_) => None,
    };
    // A single experiment is simply run again; a sweep keeps its record
    // unless told to resume or start over.
    let force = force || (plan.runs.len() == 1 && !resume);
    let options = RunOptions {
        out,
        resume,
        force,
        shard,
        slurm_task,
        quiet,
    };
    let outcome = run_sweep(&plan, &options).with_context(|| {
        let what = if plan.runs.len() == 1 {
            "experiment"
        } else {
            "sweep"
        };
        format!("{what} {}", file.display())
    })?;
    println!(
        "{} run(s) done in {:.1} s ({} skipped as recorded, {} left to other shards; {} dataset(s) prepared, {} fit(s))",
        outcome.ran,
        outcome.duration_secs,
        outcome.skipped,
        outcome.other_shards,
        outcome.counts.datasets,
        outcome.counts.fits
    );
    let dir = outcome.dir;
    if plan.runs.len() == 1 {
        if let Some((_, reason)) = outcome.failed.first() {
            anyhow::bail!("{reason} (recorded as failed in {})", dir.display());
        }
        println!("wrote {}", dir.join("report.md").display());
        write_sweep_report(&dir, "summary.md")?;
    } else if outcome.complete {
        let report = write_sweep_report(&dir, "report.md")?;
        println!("wrote {} ({} runs)", report.markdown.display(), report.runs);
    } else if outcome.failed.is_empty() {
        println!(
            "the sweep is not complete yet (other shards?); `gpodo report {}` merges what is there",
            dir.display()
        );
    } else {
        for (key, reason) in &outcome.failed {
            eprintln!("run `{key}` failed: {reason}");
        }
        if let Ok(report) = write_sweep_report(&dir, "report.md") {
            println!(
                "wrote {} ({} runs, {} failed)",
                report.markdown.display(),
                report.runs,
                report.failed
            );
        }
        anyhow::bail!(
            "{} of {} run(s) failed and are recorded as failed; the others are recorded. \
             Fix the cause and run `gpodo run {} --resume` to run only the failed ones again",
            outcome.failed.len(),
            outcome.ran,
            file.display()
        );
    }
    Ok(())
}

fn plan(file: &Path) -> anyhow::Result<()> {
    let plan = load_plan(file)?;
    println!(
        "{}: {} run(s) of `{}` ({} seed {}){}",
        file.display(),
        plan.runs.len(),
        plan.name,
        if plan.runs.len() == 1 {
            "experiment"
        } else {
            "sweep"
        },
        plan.seed,
        if plan.replicates.is_empty() {
            String::new()
        } else {
            format!(", seeds {:?}", plan.replicates)
        }
    );
    for d in &plan.dimensions {
        println!("  swept `{}`: {} values", d.name, d.values.len());
    }
    for r in &plan.runs {
        let seed = r
            .seed
            .map_or(String::new(), |s| format!("  [derived seed {s}]"));
        println!("{:4}  {}{seed}", r.index, r.key);
    }
    Ok(())
}

fn report(dir: &Path) -> anyhow::Result<()> {
    let merged = gpodo_experiments::report::sweep::merge_records(dir)?;
    let single = merged.plan.as_ref().is_some_and(|p| p.keys.len() == 1);
    let name = if single { "summary.md" } else { "report.md" };
    let report = write_sweep_report(dir, name)?;
    println!(
        "wrote {} ({} runs, {} missing, {} duplicated)",
        report.markdown.display(),
        report.runs,
        report.missing,
        report.duplicates
    );
    if report.missing > 0 || report.duplicates > 0 {
        anyhow::bail!(
            "{}: {} planned run(s) missing and {} recorded twice (the report names them); `gpodo run FILE --resume` runs the missing ones",
            dir.display(),
            report.missing,
            report.duplicates
        );
    }
    Ok(())
}

fn bench(file: &Path, out: Option<PathBuf>) -> anyhow::Result<()> {
    let config = ExperimentConfig::from_path(file)?;
    let results = run_bench(&config).with_context(|| format!("benchmark {}", file.display()))?;
    let plan_dir = results_dir(
        &load_plan(file)?,
        &RunOptions {
            out,
            ..RunOptions::default()
        },
    );
    let (md, json) = write_bench_report(&results, &plan_dir)
        .with_context(|| format!("writing {}", plan_dir.display()))?;
    println!("wrote {} and {}", md.display(), json.display());
    if !results.failures.is_empty() {
        for (label, reason) in &results.failures {
            eprintln!("regressor `{label}` failed: {reason}");
        }
        anyhow::bail!(
            "{} regressor(s) failed; the others are in {}",
            results.failures.len(),
            md.display()
        );
    }
    Ok(())
}

fn fit(file: &Path, label: &str, save: &Path) -> anyhow::Result<()> {
    let config = ExperimentConfig::from_path(file)?;
    let fitted = fit_model(&config, label).with_context(|| format!("fit {}", file.display()))?;
    fitted.file.save(save)?;
    println!(
        "wrote {} (`{}`, {} training rows; held-out RMSE {:.6}, MAE {:.6} over {} test rows)",
        save.display(),
        fitted.file.label,
        fitted.file.provenance.training_rows,
        fitted.evaluation.pooled.rmse,
        fitted.evaluation.pooled.mae,
        fitted.test_inputs.1.nrows()
    );
    Ok(())
}

fn import(
    files: &[PathBuf],
    topics: &Path,
    out: &Path,
    rover: Option<&Path>,
) -> anyhow::Result<()> {
    use gpodo_experiments::commands::import::{import_bags, read_topic_map, unit_check};
    let map = read_topic_map(topics)?;
    let imported = import_bags(files, &map, out, |one| {
        let (log, report) = (&one.log, &one.report);
        if let Some(path) = &one.vo_tum {
            println!(
                "wrote {} ({} poses; {} of them camera frames of the log; replay it with `frontend: {{vo: {{kind: replay, path: ...}}}}`)",
                path.display(),
                report.vo_poses.len(),
                log.camera_times_secs.len()
            );
        }
        println!(
            "wrote {} ({} rows at {} Hz, {} dropped in gaps; {:.1} s, {:.1} m of ground truth)",
            one.csv.display(),
            report.rows,
            map.rate_hz,
            report.rows_dropped,
            log.duration_secs(),
            log.path_length_m()
        );
        for s in &report.streams {
            println!("  {s}");
        }
        for note in report.gnss_notes() {
            println!("  {note}");
        }
        if !report.damage.is_empty() {
            println!("  {}", report.damage);
        }
    })?;
    let Some(rover) = rover else {
        println!(
            "no unit check: give `--rover` (the robot's description) to compare the wheels' speed with the ground truth's"
        );
        return Ok(());
    };
    let logs: Vec<_> = imported.into_iter().map(|one| one.log).collect();
    match unit_check(&logs, rover)? {
        None => println!(
            "no unit check: fewer than {} seconds drive faster than {} m/s",
            gpodo_datasets::speed_check::MIN_MOVING_WINDOWS,
            gpodo_datasets::speed_check::MOVING_SPEED_MPS
        ),
        Some(ratio) => {
            println!(
                "unit check: the motion model's speed is {ratio:.2}× the ground truth's (median over the moving seconds; plausible within [0.5, 2])"
            );
            if let Some(warning) = gpodo_datasets::speed_check::unit_warning(ratio) {
                tracing::warn!("{warning}");
            }
        }
    }
    Ok(())
}

fn simulate(options: &SimulateOptions, out: &Path) -> anyhow::Result<()> {
    for written in simulate_to(options, out)? {
        println!("{written}");
    }
    Ok(())
}

/// Whether the log may colour its lines: only on a terminal, and never
/// when `NO_COLOR` is set (to anything but the empty string).
fn colour_on_stderr() -> bool {
    use std::io::IsTerminal;
    let no_color = std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty());
    std::io::stderr().is_terminal() && !no_color
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
        .with_ansi(colour_on_stderr())
        .init();
    gpodo_experiments::util::stop::install_ctrl_c()?;
    match cli.command {
        Command::Run {
            file,
            out,
            resume,
            force,
            shard,
        } => match run(&file, out, resume, force, shard, cli.quiet) {
            // Stopped by Ctrl-C: the runner's message, and the status a
            // shell gives an interrupted command.
            Err(e) if gpodo_experiments::util::stop::requested() => {
                eprintln!("{}", e.root_cause());
                std::process::exit(130);
            }
            other => other,
        },
        Command::Plan { file } => plan(&file),
        Command::Report { dir } => report(&dir),
        Command::Bench { file, out } => bench(&file, out),
        Command::Fit {
            file,
            regressor,
            save,
        } => fit(&file, &regressor, &save),
        Command::Import {
            files,
            topics,
            out,
            rover,
        } => import(&files, &topics, &out, rover.as_deref()),
        Command::Bag {
            command:
                BagCommand::Info {
                    file,
                    json,
                    skip_damaged,
                },
        } => {
            use gpodo_datasets::bags::{BagInfo, OnDamage};
            let on_damage = if skip_damaged {
                OnDamage::Skip
            } else {
                OnDamage::Stop
            };
            let info = BagInfo::read_with(&file, on_damage)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&info)?);
            } else {
                print!("{}", info.to_text());
            }
            Ok(())
        }
        Command::Predict { model, input, out } => {
            let rows = predict_csv(&model, &input, &out)?;
            println!("wrote {} ({rows} rows)", out.display());
            Ok(())
        }
        Command::Live {
            model,
            rover,
            topics,
            replay,
            out,
            rows,
            realtime,
            domain_id,
            max_outputs,
            idle_exit_secs,
            dds_interfaces,
            gate,
            checkpoint,
            decisions,
        } => gpodo_experiments::commands::live::live(
            &gpodo_experiments::commands::live::LiveOptions {
                model,
                rover,
                topics,
                replay,
                out,
                rows,
                realtime,
                domain_id,
                max_outputs,
                idle_exit_secs,
                dds_interfaces,
                gate,
                checkpoint,
                decisions,
            },
        ),
        Command::Simulate {
            format,
            preset,
            seed,
            out,
            training_runs,
            training_run_secs,
            test_max_secs,
            wheel_ticks_per_turn,
            wheel_gear_ratio,
            wheel_rate,
            no_imu,
            camera,
            camera_scale,
            camera_fps,
            vo_ground_truth,
        } => {
            use gpodo_datasets::bags::write::{WheelRate, WheelUnits};
            let rate = match wheel_rate {
                WheelRateArg::RadPerS => WheelRate::RadPerSec,
                WheelRateArg::Rpm => WheelRate::MotorRpm,
                WheelRateArg::RadPerMin => WheelRate::MotorRadPerMin,
            };
            let units = WheelUnits::encoders(wheel_ticks_per_turn, wheel_gear_ratio, rate);
            if format != SimulateFormat::Mcap && units != WheelUnits::default() {
                anyhow::bail!(
                    "--wheel-ticks-per-turn and --wheel-rate apply to `--format mcap`; a rover-log CSV is in rad and rad/s"
                );
            }
            let options = SimulateOptions {
                preset,
                seed,
                training_runs,
                training_run_secs,
                test_max_secs,
                format: match format {
                    SimulateFormat::Csv => {
                        gpodo_experiments::commands::simulate::SimulateFormat::Csv
                    }
                    SimulateFormat::Mcap => {
                        gpodo_experiments::commands::simulate::SimulateFormat::Mcap
                    }
                    SimulateFormat::Png => {
                        gpodo_experiments::commands::simulate::SimulateFormat::Png
                    }
                },
                units,
                imu: !no_imu,
                camera: camera.then_some(gpodo_experiments::commands::simulate::CameraOutput {
                    scale: camera_scale,
                    fps: camera_fps,
                    vo_ground_truth,
                }),
            };
            simulate(&options, &out)
        }
    }
}

//! The node's latency per joint-state message: the motion model, the
//! trailing window's row, the saved regressor's prediction with its
//! variance, and the pose, as `LiveModel::process` does them on the robot.
//!
//! Models fitted on a simulated ExoTeR drive's 1-s rows (n = 1869, the
//! size of the authors' ExoTeR table; d = 28): the exact GP, the sparse GP
//! (VFE, 100 inducing points) and ILGR, beside the motion model's step
//! alone, the baseline measured in the same run. Each
//! model's p50 and p99 over 2000 calls are printed too (criterion reports
//! means). Run with `cargo bench -p gpodo-node --bench live_latency`.

#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use gpodo_datasets::residuals::{ResidualConfig, log_steps, residual_dataset_from_steps};
use gpodo_kinematics::spec::MotionModelSpec;
use gpodo_node::diagnostics::percentile;
use gpodo_node::{LiveModel, LiveSettings};
use gpodo_regressors::RegressorSpec;
use gpodo_regressors::model_file::{ModelFile, Provenance, RowRecipe};
use gpodo_testbed::sim::preset::{Preset, SimulatorConfig};
use gpodo_traits::ProprioceptiveSample;

/// Training rows, as in the authors' ExoTeR table.
const ROWS: usize = 1869;

const MODELS: [(&str, &str); 3] = [
    (
        "exact_gp",
        r#"{"kind": "exact_gp", "kernel": "rbf", "hyperopt": {"max_iters": 3}}"#,
    ),
    (
        "sparse_gp",
        r#"{"kind": "sparse_gp", "kernel": "rbf", "inducing": {"count": 100}, "hyperopt": {"max_iters": 3}}"#,
    ),
    ("ilgr", r#"{"kind": "ilgr"}"#),
];

fn exoter_yaml() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../kinematics/rovers/exoter.yaml")
}

/// A model per kind, saved with its row recipe, and the test drive.
fn fitted(
    dir: &Path,
) -> (
    Vec<(&'static str, std::path::PathBuf)>,
    Vec<ProprioceptiveSample>,
) {
    let mut config = SimulatorConfig::preset(Preset::ExoterPrl, 11);
    config.training_runs = 1;
    config.training_run_secs = ROWS as f64 + 2.0;
    config.test_max_secs = 200.0;
    let testbed = config.simulate().unwrap();
    let spec = MotionModelSpec::default();
    let (motion, rover) = spec.build().unwrap();
    let log = &testbed.train[0];
    let steps = log_steps(log, motion.as_ref(), rover.unwrap().wheel_radius_m).unwrap();
    let residuals = ResidualConfig::default();
    let mut train = residual_dataset_from_steps(&[log], &[steps], &residuals).unwrap();
    assert!(train.len() >= ROWS, "{} rows", train.len());
    train = train.select(&(0..ROWS).collect::<Vec<_>>());
    let models = MODELS
        .iter()
        .map(|(name, json)| {
            let regressor: RegressorSpec = serde_json::from_str(json).unwrap();
            let (mut file, _) =
                ModelFile::fit(&regressor, &train, None, Provenance::default()).unwrap();
            file.rows = Some(RowRecipe {
                rate_hz: Some(1.0 / config.dt_secs),
                window_secs: residuals.window_secs,
                absolute_targets: false,
                motion_model: serde_json::to_value(&spec).unwrap(),
            });
            let path = dir.join(format!("{name}.gpodo"));
            file.save(&path).unwrap();
            (*name, path)
        })
        .collect();
    (models, testbed.test[0].samples.clone())
}

/// Feeds the drive round and round, its times moved on each lap.
struct Drive {
    samples: Vec<ProprioceptiveSample>,
    next: usize,
    lap_secs: f64,
}

impl Drive {
    fn sample(&mut self) -> ProprioceptiveSample {
        let n = self.samples.len();
        let mut s = self.samples[self.next % n].clone();
        s.time_secs += (self.next / n) as f64 * self.lap_secs;
        self.next += 1;
        s
    }
}

fn latency(c: &mut Criterion) {
    let tmp = tempfile::tempdir().unwrap();
    let (models, samples) = fitted(tmp.path());
    let lap_secs = samples.last().unwrap().time_secs - samples[0].time_secs + 0.08;
    let mut group = c.benchmark_group("live_process");
    group
        .sample_size(30)
        .measurement_time(Duration::from_secs(4));
    let (motion, _) = MotionModelSpec::default()
        .with_rover(exoter_yaml())
        .build()
        .unwrap();
    let mut k = 0;
    group.bench_function("motion_model_only", |b| {
        b.iter(|| {
            k = (k + 1) % samples.len();
            black_box(motion.estimate(&samples[k], 0.08).unwrap())
        })
    });
    for (name, path) in &models {
        let mut model =
            LiveModel::load(path, &exoter_yaml(), true, false, LiveSettings::default()).unwrap();
        let mut drive = Drive {
            samples: samples.clone(),
            next: 0,
            lap_secs,
        };
        // Past the first window, then 2000 timed calls for the percentiles.
        let mut times = Vec::new();
        for k in 0..2100 {
            let s = drive.sample();
            let t = Instant::now();
            black_box(model.process(&s).unwrap());
            if k >= 100 {
                times.push(t.elapsed().as_secs_f64());
            }
        }
        eprintln!(
            "{name} (n = {ROWS}): p50 {:.4} ms, p99 {:.4} ms over {} calls",
            percentile(&times, 50.0).unwrap() * 1e3,
            percentile(&times, 99.0).unwrap() * 1e3,
            times.len()
        );
        group.bench_function(format!("{name}/n{ROWS}"), |b| {
            b.iter_batched(
                || drive.sample(),
                |s| black_box(model.process(&s).unwrap()),
                criterion::BatchSize::SmallInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, latency);
criterion_main!(benches);

//! Bag import throughput: a field campaign is tens of gigabytes of bags, so
//! `gpodo import` (and `dataset: {kind: bags}`) must read them at disk-like
//! speed. Timed: the whole import (read, decompress, decode, resample onto
//! the common clock) of the shared Husky recording (MCAP and ROS 1 bag, 1.5
//! MB, 16806 messages) and of a simulated ExoTeR run written as a ROS 2
//! MCAP by gpodo's own writer (over 100 MB under `cargo bench`; a short run
//! when the bench binary only checks itself under `cargo test`). Criterion
//! reports bytes of bag per second; the message count of each bag is
//! printed so that messages per second follow.
//!
//! ```text
//! cargo bench -p gpodo-datasets --bench bag_import
//! ```

#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use gpodo_datasets::bags::BagInfo;
use gpodo_datasets::bags::import::{TopicMap, import_bag};
use gpodo_datasets::bags::write::{write_mcap, written_topic_map};
use gpodo_testbed::sim::preset::{Preset, SimulatorConfig};

/// The topic map of `experiments/husky-bags.yaml`.
const HUSKY: &str = "imu: /imu/data
imu_rotation_rpy_rad: [1.5707963267948966, 0, 0]
ground_truth: /fix
odometry: /husky_velocity_controller/odom
rate_hz: 10
max_gap_secs: 0.5
";

fn shared(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/ros")
        .join(name)
}

/// Whether criterion measures (`cargo bench`) rather than checks.
fn measuring() -> bool {
    std::env::args().any(|a| a == "--bench")
}

fn bench_one(c: &mut Criterion, name: &str, path: &Path, map: &TopicMap) {
    let bytes = std::fs::metadata(path).unwrap().len();
    let messages = BagInfo::read(path).unwrap().messages;
    eprintln!("{name}: {:.1} MB, {messages} messages", bytes as f64 / 1e6);
    let mut group = c.benchmark_group("bag_import");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(if bytes > 50_000_000 { 40 } else { 5 }));
    group.throughput(Throughput::Bytes(bytes));
    group.bench_function(name, |b| {
        b.iter(|| black_box(import_bag(path, "x", map).unwrap().0.samples.len()))
    });
    group.finish();
}

fn bag_import(c: &mut Criterion) {
    let husky: TopicMap = serde_saphyr::from_str(HUSKY).unwrap();
    for file in ["husky_test1.mcap", "husky_test1.bag"] {
        bench_one(c, file, &shared(file), &husky);
    }
    // A simulated run: about 5.6 kB of bag per second of driving.
    let secs = if measuring() { 20_000.0 } else { 300.0 };
    let mut sim = SimulatorConfig::preset(Preset::ExoterPrl, 11);
    sim.training_runs = 1;
    sim.training_run_secs = secs;
    let testbed = sim.simulate().unwrap();
    let log = &testbed.train[0];
    let dir = tempfile::tempdir().unwrap();
    let bag = write_mcap(log, dir.path()).unwrap();
    let map = written_topic_map(log, 12.5);
    bench_one(c, "simulated.mcap", &bag.path, &map);
}

criterion_group!(benches, bag_import);
criterion_main!(benches);

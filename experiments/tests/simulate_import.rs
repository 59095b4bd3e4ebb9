//! The library behind `gpodo simulate` and `gpodo import`, without the
//! binary: a simulated testbed written as ROS 2 bags imports back to logs
//! of the same samples, the written topic map reads them, a robot without
//! an IMU stays without one, and bad inputs are refused before anything
//! is written.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use gpodo_datasets::bags::write::WheelUnits;
use gpodo_datasets::sim::preset::Preset;
use gpodo_experiments::error::{ConfigError, PipelineError};
use gpodo_experiments::import::{import_bags, read_topic_map, unit_check};
use gpodo_experiments::simulate::{
    SimulateFormat, SimulateOptions, Written, median_rate_hz, simulate_to,
};

/// One 60-s training run and the test traverse of seed 3.
fn options(format: SimulateFormat, imu: bool) -> SimulateOptions {
    SimulateOptions {
        preset: Preset::ExoterPrl,
        seed: 3,
        training_runs: Some(1),
        training_run_secs: Some(60.0),
        format,
        units: WheelUnits::default(),
        imu,
    }
}

fn bags(written: &[Written]) -> Vec<PathBuf> {
    written
        .iter()
        .filter_map(|w| match w {
            Written::Bag { path, .. } => Some(path.clone()),
            _ => None,
        })
        .collect()
}

fn exoter() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../kinematics/rovers/exoter.yaml")
}

#[test]
fn simulated_bags_import_back_to_logs_of_the_same_samples() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = simulate_to(&options(SimulateFormat::Csv, true), &tmp.path().join("csv")).unwrap();
    let mcap = simulate_to(
        &options(SimulateFormat::Mcap, true),
        &tmp.path().join("mcap"),
    )
    .unwrap();
    // One training run and one test traverse, then the topic map.
    assert_eq!(csv.len(), 2);
    assert_eq!(mcap.len(), 3);
    let Some(Written::TopicMap { path: map_path }) = mcap.last() else {
        panic!("no topic map last in {mcap:?}");
    };
    let map = read_topic_map(map_path).unwrap();
    // The ExoTeR preset samples at 12.5 Hz; the map says so.
    assert_eq!(map.rate_hz, 12.5);

    let mut seen = Vec::new();
    let imported = import_bags(&bags(&mcap), &map, &tmp.path().join("logs"), |one| {
        seen.push(one.csv.clone())
    })
    .unwrap();
    assert_eq!(seen.len(), 2, "each recording is reported as it is written");
    for (one, written) in imported.iter().zip(&csv) {
        let Written::Log {
            samples,
            path_length_m,
            ..
        } = written
        else {
            panic!("not a log: {written:?}");
        };
        assert!(one.csv.is_file(), "{}", one.csv.display());
        assert_eq!(one.log.samples.len(), *samples, "{}", one.source.display());
        assert_eq!(one.report.rows, *samples);
        assert_eq!(median_rate_hz(&one.log), Some(12.5));
        let relative = (one.log.path_length_m() - path_length_m).abs() / path_length_m;
        assert!(relative < 1e-6, "path length off by {relative:e}");
        assert!(one.log.samples.iter().all(|s| s.imu.is_some()));
    }

    // The wheels of the simulated ExoTeR against its ground truth: a slip
    // ratio, never a unit error (a factor of 2π, 60 or a gear ratio).
    let logs: Vec<_> = imported.into_iter().map(|one| one.log).collect();
    let ratio = unit_check(&logs, &exoter())
        .unwrap()
        .expect("enough moving seconds");
    assert!((0.5..=2.0).contains(&ratio), "speed ratio {ratio}");
}

#[test]
fn a_robot_without_an_imu_is_written_and_imported_without_one() {
    let tmp = tempfile::tempdir().unwrap();
    let written = simulate_to(
        &options(SimulateFormat::Mcap, false),
        &tmp.path().join("mcap"),
    )
    .unwrap();
    let map = read_topic_map(&tmp.path().join("mcap/topics.yaml")).unwrap();
    let imported = import_bags(&bags(&written), &map, &tmp.path().join("logs"), |_| {}).unwrap();
    assert_eq!(imported.len(), 2);
    for one in &imported {
        assert!(!one.log.samples.is_empty());
        assert!(one.log.samples.iter().all(|s| s.imu.is_none()));
    }
}

#[test]
fn two_inputs_with_one_name_are_refused_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let written = simulate_to(&options(SimulateFormat::Mcap, true), &tmp.path().join("a")).unwrap();
    let first = bags(&written).remove(0);
    let twin = tmp.path().join("b").join(first.file_name().unwrap());
    std::fs::create_dir_all(twin.parent().unwrap()).unwrap();
    std::fs::copy(&first, &twin).unwrap();
    let map = read_topic_map(&tmp.path().join("a/topics.yaml")).unwrap();
    let out = tmp.path().join("logs");
    let err = import_bags(&[first, twin], &map, &out, |_| {}).unwrap_err();
    assert!(
        matches!(&err, PipelineError::Inconsistent(m) if m.contains("overwrite")),
        "{err}"
    );
    assert!(!out.exists(), "nothing is written");
}

#[test]
fn a_topic_map_that_cannot_be_read_or_parsed_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("topics.yaml");
    std::fs::write(&path, "rate_hz: [fast\n").unwrap();
    let err = read_topic_map(&path).unwrap_err();
    assert!(matches!(err, ConfigError::Parse { .. }), "{err}");
    assert!(err.to_string().contains("topics.yaml"), "{err}");
    let missing = read_topic_map(&tmp.path().join("none.yaml")).unwrap_err();
    assert!(matches!(missing, ConfigError::Io { .. }), "{missing}");
    assert!(missing.to_string().contains("none.yaml"), "{missing}");
}

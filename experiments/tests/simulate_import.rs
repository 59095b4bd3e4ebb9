//! The library behind `gpodo simulate` and `gpodo import`, without the
//! binary: a simulated testbed written as ROS 2 bags imports back to logs
//! of the same samples, the written topic map reads them, a robot without
//! an IMU stays without one, and bad inputs are refused before anything
//! is written.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use gpodo_datasets::bags::write::WheelUnits;
use gpodo_experiments::commands::import::{import_bags, read_topic_map, unit_check};
use gpodo_experiments::commands::simulate::{
    CameraOutput, SimulateFormat, SimulateOptions, Written, median_rate_hz, simulate_to,
};
use gpodo_experiments::error::{ConfigError, PipelineError};
use gpodo_testbed::sim::preset::Preset;

/// One 60-s training run and the test traverse of seed 3.
fn options(format: SimulateFormat, imu: bool) -> SimulateOptions {
    SimulateOptions {
        preset: Preset::ExoterPrl,
        seed: 3,
        training_runs: Some(1),
        training_run_secs: Some(60.0),
        test_max_secs: None,
        format,
        units: WheelUnits::default(),
        imu,
        camera: None,
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

/// 8-s runs with the camera at an eighth of the Bumblebee2's resolution.
fn with_camera(format: SimulateFormat) -> SimulateOptions {
    SimulateOptions {
        training_run_secs: Some(8.0),
        test_max_secs: Some(8.0),
        camera: Some(CameraOutput {
            scale: 0.125,
            fps: 2.5,
            vo_ground_truth: false,
        }),
        ..options(format, true)
    }
}

#[test]
fn the_camera_leaves_the_logs_as_they_are_and_writes_pngs_with_times_and_calibration() {
    let tmp = tempfile::tempdir().unwrap();
    let plain = SimulateOptions {
        training_run_secs: Some(8.0),
        test_max_secs: Some(8.0),
        ..options(SimulateFormat::Csv, true)
    };
    let csv = simulate_to(&plain, &tmp.path().join("csv")).unwrap();
    let png = simulate_to(&with_camera(SimulateFormat::Png), &tmp.path().join("png")).unwrap();
    // Every log is the same bytes with or without the camera.
    let logs = |written: &[Written]| -> Vec<Vec<u8>> {
        written
            .iter()
            .filter_map(|w| match w {
                Written::Log { csv, .. } => Some(std::fs::read(csv).unwrap()),
                _ => None,
            })
            .collect()
    };
    assert_eq!(logs(&csv), logs(&png));
    let frames: Vec<_> = png
        .iter()
        .filter_map(|w| match w {
            Written::Frames { dir, pairs, .. } => Some((dir.clone(), *pairs)),
            _ => None,
        })
        .collect();
    assert_eq!(frames.len(), 2, "{png:?}");
    for (dir, pairs) in frames {
        // 8 s at 2.5 fps from the first sample.
        assert_eq!(pairs, 20, "{}", dir.display());
        let times = std::fs::read_to_string(dir.join("times.csv")).unwrap();
        assert_eq!(times.lines().count(), pairs + 1);
        let left = gpodo_vision::png_io::read_png_gray(&dir.join("left/000019.png")).unwrap();
        assert_eq!((left.width(), left.height()), (128, 96));
        // The right camera's projection carries −f b (f = 838/8 px).
        let right: serde_json::Value =
            serde_saphyr::from_str(&std::fs::read_to_string(dir.join("right.yaml")).unwrap())
                .unwrap();
        let p = &right["projection_matrix"]["data"];
        let tx = p[3].as_f64().unwrap();
        assert!((tx + 104.75 * 0.12043).abs() < 1e-9, "{tx}");
        assert_eq!(right["image_width"].as_u64(), Some(128));
    }
}

#[test]
fn a_bag_with_the_camera_decodes_in_the_ros_reader() {
    let Some(python) = gpodo_testkit::python_with(&["mcap_ros2.reader"], "mcap-ros2-support")
    else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let written = simulate_to(&with_camera(SimulateFormat::Mcap), tmp.path()).unwrap();
    let bag = bags(&written).pop().unwrap();
    let script = "import sys, collections\n\
        from mcap_ros2.reader import read_ros2_messages\n\
        n = collections.Counter()\n\
        for m in read_ros2_messages(sys.argv[1]):\n\
        \x20   t, r = m.channel.topic, m.ros_msg\n\
        \x20   n[t] += 1\n\
        \x20   if t == '/camera/right/image_raw':\n\
        \x20       assert (r.width, r.height, r.encoding, len(r.data)) == (128, 96, 'mono8', 128 * 96), r\n\
        \x20   if t == '/camera/right/camera_info':\n\
        \x20       tx = r.p[3]\n\
        print(n['/camera/left/image_raw'], n['/camera/right/image_raw'], n['/camera/right/camera_info'], tx)\n";
    let text = gpodo_testkit::run_python(&python, script, &[bag.as_os_str()]);
    let fields: Vec<f64> = text
        .split_whitespace()
        .map(|f| f.parse().unwrap())
        .collect();
    assert_eq!(&fields[..3], &[20.0, 20.0, 20.0], "{text}");
    assert!((fields[3] + 104.75 * 0.12043).abs() < 1e-9, "{text}");
}

#[test]
fn a_camera_that_does_not_fit_the_format_is_refused_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let cases = [
        (
            SimulateOptions {
                camera: None,
                ..with_camera(SimulateFormat::Png)
            },
            "png",
        ),
        (with_camera(SimulateFormat::Csv), "CSV"),
        (
            SimulateOptions {
                camera: Some(CameraOutput {
                    scale: 1.5,
                    fps: 2.5,
                    vo_ground_truth: false,
                }),
                ..with_camera(SimulateFormat::Mcap)
            },
            "scale",
        ),
    ];
    for (options, named) in cases {
        let err = simulate_to(&options, &out).unwrap_err();
        assert!(
            matches!(&err, PipelineError::Inconsistent(m) if m.contains(named)),
            "{err}"
        );
        assert!(!out.exists());
    }
}

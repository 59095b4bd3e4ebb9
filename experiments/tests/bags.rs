//! `dataset: {kind: bags}` reads ROS bags through a topic map (tests may
//! read the shared Husky recording in `../shared/data/ros/`): the
//! recording has no joint encoders, so the ExoTeR model refuses it naming
//! the missing wheels; a topic the bag does not have is named with the
//! bag's topics.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

mod common;

use common::{GPODO, gpodo_on};

fn run(dir: &Path, imu_topic: &str) -> String {
    let ros = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/ros");
    let yaml = format!(
        "name: husky
dataset:
  kind: bags
  train: [{train}]
  test: [{test}]
  topics:
    imu: {imu_topic}
    imu_rotation_rpy_rad: [1.5707963267948966, 0, 0]
    ground_truth: /husky_velocity_controller/odom
regressors:
  - kind: zero
",
        train = ros.join("husky_test1.mcap").display(),
        test = ros.join("husky_test1.bag").display()
    );
    let file = dir.join("husky.yaml");
    std::fs::write(&file, yaml).unwrap();
    let out = gpodo_on("run", &file, &dir.join("out"), &[]);
    assert!(!out.status.success());
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn a_bag_dataset_is_imported_and_checked_against_the_motion_model() {
    let tmp = tempfile::tempdir().unwrap();
    let e = run(tmp.path(), "/imu/data");
    assert!(
        e.contains("log `husky_test1`") && e.contains("wheel joints") && e.contains("the log []"),
        "{e}"
    );
    let e = run(tmp.path(), "/imu");
    assert!(
        e.contains("husky_test1.mcap: no topic `/imu`")
            && e.contains("/fix, /husky_velocity_controller/odom, /imu/data"),
        "{e}"
    );
}

/// Table I of a run's metrics.json: per regressor, RMSE and MAE.
fn table_one(out: &Path) -> Vec<(String, f64, f64)> {
    let text = std::fs::read_to_string(out.join("metrics.json")).unwrap();
    let m: serde_json::Value = serde_json::from_str(&text).unwrap();
    m["regressors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let t = &r["evaluation"]["pooled"];
            (
                r["label"].as_str().unwrap().to_string(),
                t["rmse"].as_f64().unwrap(),
                t["mae"].as_f64().unwrap(),
            )
        })
        .collect()
}

#[test]
fn the_husky_example_runs_from_the_mcap_and_the_ros1_bag_alike() {
    let tmp = tempfile::tempdir().unwrap();
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("husky-bags.yaml");
    let out = gpodo_on("run", &example, &tmp.path().join("mcap"), &[]);
    common::assert_succeeded(&out, "");
    // The same experiment on the ROS 1 copy of the recording.
    let ros1 = std::fs::read_to_string(&example)
        .unwrap()
        .replace("husky_test1.mcap", "husky_test1.bag");
    let shared = format!("{}/../../shared", env!("CARGO_MANIFEST_DIR"));
    let copy = tmp.path().join("husky-bags.yaml");
    std::fs::write(&copy, ros1.replace("../../shared", &shared)).unwrap();
    let out = gpodo_on("run", &copy, &tmp.path().join("ros1"), &[]);
    common::assert_succeeded(&out, "");
    let (a, b) = (
        table_one(&tmp.path().join("mcap")),
        table_one(&tmp.path().join("ros1")),
    );
    assert_eq!(a, b);
    let labels: Vec<&str> = a.iter().map(|r| r.0.as_str()).collect();
    assert_eq!(
        labels,
        [
            "parametric only",
            "exact GP: rbf",
            "sparse GP (VFE, m=50): rbf"
        ]
    );
    let report = std::fs::read_to_string(tmp.path().join("mcap/report.md")).unwrap();
    for needle in [
        "husky_test1-train",
        "husky_test1-test",
        "Motion model: reported_odometry",
        "GNSS σ reported by the receiver",
        "How much of the residual is noise",
        "odom_vx",
    ] {
        assert!(
            report.contains(needle),
            "no `{needle}` in the report:\n{report}"
        );
    }
}

#[test]
fn the_unit_check_is_silent_on_the_husky_recording() {
    use gpodo_datasets::bags::import::{TopicMap, import_bag};
    use gpodo_experiments::config::MotionModelSpec;
    // The topic map of experiments/husky-bags.yaml.
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("husky-bags.yaml");
    let config: serde_json::Value =
        serde_saphyr::from_str(&std::fs::read_to_string(&example).unwrap()).unwrap();
    let map: TopicMap = serde_json::from_value(config["dataset"]["topics"].clone()).unwrap();
    let bag = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/ros/husky_test1.mcap");
    let (log, _) = import_bag(&bag, "husky", &map).unwrap();
    let spec = MotionModelSpec::ReportedOdometry {
        rover: None,
        angular: Default::default(),
    };
    let ratio = gpodo_experiments::execute::data::speed_ratio(&spec, &[log])
        .unwrap()
        .unwrap();
    assert!(
        gpodo_datasets::speed_check::unit_warning(ratio).is_none() && (ratio - 1.0).abs() < 0.3,
        "{ratio}"
    );
}

mod synthetic {
    //! `gpodo simulate --format mcap` writes the simulated rover as ROS 2
    //! MCAP bags and the topic map that imports them; read back through
    //! `kind: bags`, they give the residual rows of the same runs written
    //! as rover-log CSV. Python's `mcap-ros2-support` decodes them too.

    use super::{GPODO, common};
    use std::path::Path;
    use std::process::Command;

    fn simulate(format: &str, out: &Path) {
        simulate_with(format, out, &[]);
    }

    fn simulate_with(format: &str, out: &Path, extra: &[&str]) {
        let result = Command::new(GPODO)
            .args([
                "--quiet",
                "simulate",
                "--format",
                format,
                "--seed",
                "3",
                "--training-runs",
                "1",
                "--training-run-secs",
                "60",
                "--out",
            ])
            .arg(out)
            .args(extra)
            .output()
            .unwrap();
        common::assert_succeeded(&result, "");
    }

    /// Writes `csv.yaml` and `bag.yaml` in `dir` and runs both, into
    /// `out-csv` and `out-bag`.
    fn run_csv_and_bag(dir: &Path, csv_yaml: String, bag_yaml: String) {
        for (name, yaml) in [("csv", csv_yaml), ("bag", bag_yaml)] {
            let file = dir.join(format!("{name}.yaml"));
            std::fs::write(&file, yaml).unwrap();
            let out = common::gpodo_on("run", &file, &dir.join(format!("out-{name}")), &[]);
            common::assert_succeeded(&out, &format!("{name}: "));
        }
    }

    /// The header and rows of a residual CSV written by `gpodo run`.
    fn rows(path: &Path) -> (String, Vec<Vec<f64>>) {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        let header = lines.next().unwrap().to_string();
        let rows = lines
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect();
        (header, rows)
    }

    #[test]
    fn simulated_runs_as_mcap_give_the_residual_rows_of_their_csv() {
        let tmp = tempfile::tempdir().unwrap();
        simulate("csv", &tmp.path().join("csv"));
        simulate("mcap", &tmp.path().join("mcap"));
        let topics = std::fs::read_to_string(tmp.path().join("mcap/topics.yaml")).unwrap();
        let common = "motion_model: {kind: weighted_jacobian}\nregressors:\n  - kind: zero\n";
        let csv_yaml = format!(
            "name: csv\ndataset: {{kind: logs, train: [csv/train_01.csv], test: [csv/test.csv]}}\n{common}"
        );
        let indented: String = topics.lines().map(|l| format!("    {l}\n")).collect();
        let bag_yaml = format!(
            "name: bag\ndataset:\n  kind: bags\n  train: [mcap/train_01.mcap]\n  test: [mcap/test.mcap]\n  topics:\n{indented}{common}"
        );
        run_csv_and_bag(tmp.path(), csv_yaml, bag_yaml);
        let report = std::fs::read_to_string(tmp.path().join("out-bag/report.md")).unwrap();
        assert!(
            report.contains("ROS bags at 12.5 Hz")
                && report.contains("train_01: 750 rows, 0 dropped in gaps")
                && report.contains("joints /joint_states: 750 msgs, 0 duplicated"),
            "the report says what the import did:\n{report}"
        );
        for set in ["residuals_train.csv", "residuals_test.csv"] {
            let (h1, a) = rows(&tmp.path().join("out-csv").join(set));
            let (h2, b) = rows(&tmp.path().join("out-bag").join(set));
            assert_eq!(h1, h2);
            assert_eq!(a.len(), b.len(), "{set}");
            // Stamps are whole nanoseconds in a bag: rows agree to rounding.
            let mut worst: f64 = 0.0;
            for (ra, rb) in a.iter().zip(&b) {
                for (x, y) in ra.iter().zip(rb) {
                    worst = worst.max((x - y).abs() / (1.0 + x.abs()));
                }
            }
            assert!(worst < 1e-9, "{set}: largest difference {worst:e}");
        }
    }

    #[test]
    fn the_run_report_gives_the_unit_check_and_warns_on_wheel_speeds_off_by_two_pi() {
        let tmp = tempfile::tempdir().unwrap();
        let out = Command::new(GPODO)
            .args([
                "--quiet",
                "simulate",
                "--format",
                "mcap",
                "--seed",
                "3",
                "--training-runs",
                "1",
                "--training-run-secs",
                "300",
                "--out",
            ])
            .arg(tmp.path().join("mcap"))
            .output()
            .unwrap();
        common::assert_succeeded(&out, "");
        let topics = std::fs::read_to_string(tmp.path().join("mcap/topics.yaml")).unwrap();
        assert!(topics.contains("rate_scale: 1.0"), "{topics}");
        // Wheel rates read as if they were in rpm: 2π too fast.
        let wrong = topics.replace("rate_scale: 1.0", "rate_scale: 6.283185307179586");
        for (name, map, expected) in [
            ("right", topics.as_str(), "the wheels' units are plausible"),
            ("wrong", wrong.as_str(), "**outside [0.5, 2]**"),
        ] {
            let indented: String = map.lines().map(|l| format!("    {l}\n")).collect();
            let yaml = format!(
                "name: {name}\ndataset:\n  kind: bags\n  train: [mcap/train_01.mcap]\n  test: [mcap/test.mcap]\n  topics:\n{indented}motion_model: {{kind: weighted_jacobian}}\nregressors:\n  - kind: zero\n"
            );
            let file = tmp.path().join(format!("{name}.yaml"));
            std::fs::write(&file, yaml).unwrap();
            let out = common::gpodo_on("run", &file, &tmp.path().join(name), &[]);
            common::assert_succeeded(&out, "");
            let report = std::fs::read_to_string(tmp.path().join(name).join("report.md")).unwrap();
            let line = report
                .lines()
                .find(|l| l.starts_with("Unit check:"))
                .unwrap_or_else(|| panic!("{name}: no unit check in\n{report}"));
            assert!(line.contains(expected), "{name}: {line}");
        }
    }

    #[test]
    fn a_recording_without_an_imu_is_imported_and_learned_without_imu_inputs() {
        let tmp = tempfile::tempdir().unwrap();
        simulate_with("mcap", &tmp.path().join("mcap"), &["--no-imu"]);
        let topics = std::fs::read_to_string(tmp.path().join("mcap/topics.yaml")).unwrap();
        assert!(topics.starts_with("imu: null\n"), "{topics}");
        let indented: String = topics.lines().map(|l| format!("    {l}\n")).collect();
        let yaml = format!(
            "name: bag\ndataset:\n  kind: bags\n  train: [mcap/train_01.mcap]\n  test: [mcap/test.mcap]\n  topics:\n{indented}motion_model: {{kind: weighted_jacobian}}\nregressors:\n  - kind: zero\n  - kind: exact_gp\n    kernel: rbf\n"
        );
        let file = tmp.path().join("bag.yaml");
        std::fs::write(&file, yaml).unwrap();
        let out = common::gpodo_on("run", &file, &tmp.path().join("out"), &[]);
        common::assert_succeeded(&out, "");
        let metrics: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(tmp.path().join("out/metrics.json")).unwrap(),
        )
        .unwrap();
        let inputs: Vec<&str> = metrics["dataset"]["input_names"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        // The simulated ExoTeR's 28 inputs less the IMU's 8.
        assert_eq!(inputs.len(), 20, "{inputs:?}");
        assert!(
            !inputs.iter().any(|i| ["roll", "pitch"].contains(i)
                || i.starts_with("acc_")
                || i.starts_with("gyro_")),
            "{inputs:?}"
        );
        assert_eq!(metrics["dataset"]["attitude"], "level");
        let report = std::fs::read_to_string(tmp.path().join("out/report.md")).unwrap();
        assert!(
            report.contains(
                "No IMU: the motion model took its yaw rate from the wheels (solved with the slip"
            ) && report.contains("| exact GP: rbf |")
                && report.contains("Unit check:")
                && !report.contains("outside [0.5, 2]"),
            "{report}"
        );
        // The GP learns something the wheels alone get wrong.
        let rmse = |i: usize| {
            metrics["regressors"][i]["evaluation"]["pooled"]["rmse"]
                .as_f64()
                .unwrap()
        };
        assert!(rmse(1) < rmse(0), "{} against {}", rmse(1), rmse(0));
        // Roll and pitch from the ground truth, when asked, and said.
        let gt_yaml = std::fs::read_to_string(&file).unwrap().replace(
            "motion_model: {kind: weighted_jacobian}",
            "motion_model: {kind: weighted_jacobian, attitude_without_imu: ground_truth}",
        );
        std::fs::write(&file, gt_yaml).unwrap();
        let out = common::gpodo_on("run", &file, &tmp.path().join("out-gt"), &[]);
        common::assert_succeeded(&out, "");
        let report = std::fs::read_to_string(tmp.path().join("out-gt/report.md")).unwrap();
        assert!(
            report.contains("Roll and pitch for the load weighting came from the ground truth"),
            "{report}"
        );
        // `gpodo import` writes a log without IMU columns, which reads back.
        let map = tmp.path().join("mcap/topics.yaml");
        let out = Command::new(GPODO)
            .args(["--quiet", "import"])
            .arg(tmp.path().join("mcap/train_01.mcap"))
            .arg("--topics")
            .arg(&map)
            .arg("--out")
            .arg(tmp.path().join("logs"))
            .output()
            .unwrap();
        common::assert_succeeded(&out, "");
        let csv = std::fs::read_to_string(tmp.path().join("logs/train_01.csv")).unwrap();
        let header = csv.lines().next().unwrap();
        assert!(
            header.starts_with("time_s,gt_x_m,gt_y_m,gt_z_m,gt_qw,gt_qx,gt_qy,gt_qz,wheel_"),
            "{header}"
        );
        let log = gpodo_datasets::log::read_log_csv(&tmp.path().join("logs/train_01.csv")).unwrap();
        assert!(log.samples.iter().all(|s| s.imu.is_none()));
    }

    #[test]
    fn a_damaged_chunk_stops_a_run_at_once_or_is_skipped_and_reported() {
        let tmp = tempfile::tempdir().unwrap();
        simulate("mcap", &tmp.path().join("mcap"));
        let bag = tmp.path().join("mcap/train_01.mcap");
        let mut bytes = std::fs::read(&bag).unwrap();
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let chunk = &summary.chunk_indexes[summary.chunk_indexes.len() / 2];
        let at = (chunk.chunk_start_offset + chunk.chunk_length / 2) as usize;
        bytes[at..at + 8].copy_from_slice(&[0xA5; 8]);
        std::fs::write(&bag, &bytes).unwrap();
        let topics = std::fs::read_to_string(tmp.path().join("mcap/topics.yaml")).unwrap();
        let yaml = |topics: &str| {
            let indented: String = topics.lines().map(|l| format!("    {l}\n")).collect();
            format!(
                "name: bag\ndataset:\n  kind: bags\n  train: [mcap/train_01.mcap]\n  test: [mcap/test.mcap]\n  topics:\n{indented}motion_model: {{kind: weighted_jacobian}}\nregressors:\n  - kind: zero\n"
            )
        };
        let file = tmp.path().join("bag.yaml");
        std::fs::write(&file, yaml(&topics)).unwrap();
        let out = common::gpodo_on("run", &file, &tmp.path().join("stop"), &[]);
        let e = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success()
                && e.contains("train_01.mcap")
                && e.contains(&format!("chunk at byte {}", chunk.chunk_start_offset))
                && e.contains("skip_damaged: true"),
            "{e}"
        );
        assert!(topics.contains("skip_damaged: false"), "{topics}");
        let skipping = topics.replace("skip_damaged: false", "skip_damaged: true");
        std::fs::write(&file, yaml(&skipping)).unwrap();
        let out = common::gpodo_on("run", &file, &tmp.path().join("skip"), &[]);
        common::assert_succeeded(&out, "");
        let report = std::fs::read_to_string(tmp.path().join("skip/report.md")).unwrap();
        let lost = (chunk.message_end_time - chunk.message_start_time) as f64 * 1e-9;
        assert!(
            report.contains("skipped 1 damaged chunk: ")
                && report.contains(&format!("{lost:.3} s of recording lost")),
            "{report}"
        );
    }

    #[test]
    fn mcap_written_by_gpodo_is_decoded_by_mcap_ros2_support() {
        let Some(python) = gpodo_testkit::python_with(&["mcap_ros2.decoder"], "mcap-ros2-support")
        else {
            return;
        };
        let tmp = tempfile::tempdir().unwrap();
        simulate("mcap", &tmp.path().join("mcap"));
        simulate("csv", &tmp.path().join("csv"));
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scripts/read_mcap.py");
        let out = Command::new(&python)
            .arg(&script)
            .arg(tmp.path().join("mcap/train_01.mcap"))
            .output()
            .unwrap();
        common::assert_succeeded(&out, "");
        let decoded: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let log = gpodo_datasets::log::read_log_csv(&tmp.path().join("csv/train_01.csv")).unwrap();
        let n = log.samples.len() as u64;
        for topic in ["/joint_states", "/imu/data", "/ground_truth/pose", "/tf"] {
            assert_eq!(decoded["counts"][topic].as_u64(), Some(n), "{topic}");
        }
        // Message 10 of each topic, as Python decoded it, against the log.
        let k = 10;
        let (s, p) = (&log.samples[k], &log.ground_truth[k]);
        let f = |v: &serde_json::Value| v.as_f64().unwrap();
        let j = &decoded["joint_states"];
        assert_eq!(j["name"][0], "fl_wheel");
        assert_eq!(j["name"][6], "fl_steer");
        assert_eq!(j["name"][12], "rear_bogie");
        assert_eq!(f(&j["velocity"][0]), s.wheels[0].rate_radps);
        assert_eq!(f(&j["position"][12]), s.bogies[2].position_rad);
        let imu = &decoded["imu"];
        assert_eq!(f(&imu["angular_velocity"][2]), s.imu.unwrap().gyro_radps.z);
        assert_eq!(
            f(&imu["linear_acceleration"][0]),
            s.imu.unwrap().accel_mps2.x
        );
        let pose = &decoded["pose"];
        assert_eq!(pose["frame_id"], "world");
        assert_eq!(f(&pose["position"][1]), p.translation.vector.y);
        assert_eq!(f(&pose["orientation"][3]), p.rotation.w);
        let tf = &decoded["tf"];
        assert_eq!(
            (tf["parent"].as_str(), tf["child"].as_str()),
            (Some("world"), Some("base_link"))
        );
        assert_eq!(f(&tf["translation"][0]), p.translation.vector.x);
        // The stamp: the written epoch plus the log time, in nanoseconds.
        let ns = decoded["imu"]["stamp_ns"].as_u64().unwrap();
        let expected = gpodo_datasets::bags::write::EPOCH_NS + (s.time_secs * 1e9).round() as u64;
        assert_eq!(ns, expected);
    }

    /// The Table II rows of a run: label, frames and RMSE.
    fn table_two(out: &Path) -> Vec<(String, u64, f64)> {
        let text = std::fs::read_to_string(out.join("metrics.json")).unwrap();
        let m: serde_json::Value = serde_json::from_str(&text).unwrap();
        m["schemes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| {
                (
                    s["label"].as_str().unwrap().to_string(),
                    s["run"]["frames"].as_u64().unwrap(),
                    s["run"]["metrics"]["rmse_m"].as_f64().unwrap(),
                )
            })
            .collect()
    }

    #[test]
    fn a_recorded_vo_topic_is_replayed_in_table_two_as_its_tum_file_is() {
        use gpodo_datasets::bags::write::{write_mcap_with_vo, written_topic_map};
        use gpodo_frontends::tum::{StampedPose, format_tum};
        use nalgebra::{Isometry3, Translation3};

        let tmp = tempfile::tempdir().unwrap();
        simulate("csv", &tmp.path().join("csv"));
        let read = |run: &str| {
            gpodo_datasets::log::read_log_csv(&tmp.path().join(format!("csv/{run}.csv"))).unwrap()
        };
        let (train, test) = (read("train_01"), read("test"));
        // A drifting visual odometry: the ground truth at the camera
        // frames, off by 1 mm more per frame.
        let vo: Vec<(f64, Isometry3<f64>)> = test
            .camera_times_secs
            .iter()
            .enumerate()
            .map(|(k, &t)| {
                let i = test
                    .samples
                    .partition_point(|s| s.time_secs < t)
                    .min(test.samples.len() - 1);
                let drift = Translation3::new(1e-3 * k as f64, 0.0, 0.0);
                (
                    t,
                    Isometry3::from_parts(drift, Default::default()) * test.ground_truth[i],
                )
            })
            .collect();
        let bags = tmp.path().join("mcap");
        std::fs::create_dir_all(&bags).unwrap();
        write_mcap_with_vo(&train, &bags, &[]).unwrap();
        write_mcap_with_vo(&test, &bags, &vo).unwrap();
        let poses: Vec<StampedPose> = vo
            .iter()
            .map(|&(time_secs, pose)| StampedPose { time_secs, pose })
            .collect();
        std::fs::write(tmp.path().join("test.vo.tum"), format_tum("vo", &poses)).unwrap();
        let mut map = written_topic_map(&train, 12.5);
        map.vo = Some("/vo/pose".into());
        let topics: String = serde_saphyr::to_string(&map)
            .unwrap()
            .lines()
            .map(|l| format!("    {l}\n"))
            .collect();
        let rest = "motion_model: {kind: weighted_jacobian}
regressors:
  - kind: zero
schemes:
  - label: 1 fps
    selector: { kind: fixed_rate, fps: 1.0 }
  - label: 0.5 fps
    selector: { kind: fixed_rate, fps: 0.5 }
";
        let csv_yaml = format!(
            "name: csv\ndataset: {{kind: logs, train: [csv/train_01.csv], test: [csv/test.csv]}}\nfrontend: {{vo: {{kind: replay, path: test.vo.tum}}}}\n{rest}"
        );
        let bag_yaml = format!(
            "name: bag\ndataset:\n  kind: bags\n  train: [mcap/train_01.mcap]\n  test: [mcap/test.mcap]\n  topics:\n{topics}frontend: {{vo: {{kind: replay}}}}\n{rest}"
        );
        run_csv_and_bag(tmp.path(), csv_yaml, bag_yaml);
        let (a, b) = (
            table_two(&tmp.path().join("out-csv")),
            table_two(&tmp.path().join("out-bag")),
        );
        assert_eq!(a.len(), 2);
        for (x, y) in a.iter().zip(&b) {
            assert_eq!((&x.0, x.1), (&y.0, y.1));
            assert!((x.2 - y.2).abs() < 1e-9 * x.2, "{x:?} against {y:?}");
        }
        // Without a `vo` topic, a replay needs its file: said before running.
        let file = tmp.path().join("no-vo.yaml");
        let text = std::fs::read_to_string(tmp.path().join("bag.yaml"))
            .unwrap()
            .replace("vo: /vo/pose", "vo: null");
        std::fs::write(&file, text).unwrap();
        let out = common::gpodo_on("run", &file, &tmp.path().join("out-no-vo"), &[]);
        let e = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success()
                && e.contains("a replayed VO without a `path` at")
                && e.contains("no-vo.yaml:"),
            "{e}"
        );
    }
}

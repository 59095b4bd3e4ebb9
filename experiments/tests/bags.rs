//! `dataset: {kind: bags}` reads ROS bags through a topic map (issue 17
//! allows tests to read the shared Husky recording): the recording has no
//! joint encoders, so the ExoTeR model refuses it naming the missing
//! wheels; a topic the bag does not have is named with the bag's topics.

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
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The same experiment on the ROS 1 copy of the recording.
    let ros1 = std::fs::read_to_string(&example)
        .unwrap()
        .replace("husky_test1.mcap", "husky_test1.bag");
    let shared = format!("{}/../../shared", env!("CARGO_MANIFEST_DIR"));
    let copy = tmp.path().join("husky-bags.yaml");
    std::fs::write(&copy, ros1.replace("../../shared", &shared)).unwrap();
    let out = gpodo_on("run", &copy, &tmp.path().join("ros1"), &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
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

mod synthetic {
    //! A simulated ExoTeR run written as a ROS 2 MCAP (JointState, Imu and
    //! Odometry in CDR, encoded here by hand) and read back through `kind:
    //! bags` gives the parametric model the same residuals as the same run
    //! read as a rover-log CSV.

    use super::GPODO;
    use gpodo_datasets::log::{RoverLog, read_log_csv};
    use nalgebra::UnitQuaternion;
    use std::collections::BTreeMap;
    use std::path::Path;
    use std::process::Command;

    /// Little-endian CDR, aligned from after the 4-byte header.
    struct Cdr(Vec<u8>);

    impl Cdr {
        fn new() -> Self {
            Self(vec![0, 1, 0, 0])
        }
        fn align(&mut self, n: usize) {
            while !(self.0.len() - 4).is_multiple_of(n) {
                self.0.push(0);
            }
        }
        fn u32(&mut self, v: u32) {
            self.align(4);
            self.0.extend(v.to_le_bytes());
        }
        fn f64(&mut self, v: f64) {
            self.align(8);
            self.0.extend(v.to_le_bytes());
        }
        fn f64s(&mut self, v: &[f64]) {
            for x in v {
                self.f64(*x);
            }
        }
        fn string(&mut self, s: &str) {
            self.u32(s.len() as u32 + 1);
            self.0.extend(s.as_bytes());
            self.0.push(0);
        }
        fn header(&mut self, t: f64) {
            let ns = (t * 1e9).round() as i64;
            self.u32((ns / 1_000_000_000) as u32);
            self.u32((ns % 1_000_000_000) as u32);
            self.string("base_link");
        }
    }

    const EPOCH: f64 = 1_700_000_000.0;

    fn write_mcap(log: &RoverLog, path: &Path) {
        let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
        let mut w = mcap::Writer::new(file).unwrap();
        let none = BTreeMap::new();
        let channel = |w: &mut mcap::Writer<_>, ty: &str, topic: &str| {
            let schema = w.add_schema(ty, "ros2msg", b"").unwrap();
            w.add_channel(schema, topic, "cdr", &none).unwrap()
        };
        let joints = channel(&mut w, "sensor_msgs/msg/JointState", "/joint_states");
        let imu = channel(&mut w, "sensor_msgs/msg/Imu", "/imu");
        let odom = channel(&mut w, "nav_msgs/msg/Odometry", "/gt");
        let names: Vec<String> = log
            .wheel_names
            .iter()
            .map(|n| format!("wheel_{n}"))
            .chain(log.steer_names.iter().map(|n| format!("steer_{n}")))
            .chain(log.bogie_names.iter().map(|n| format!("bogie_{n}")))
            .collect();
        for (k, (s, pose)) in log.samples.iter().zip(&log.ground_truth).enumerate() {
            let t = EPOCH + s.time_secs;
            let all = s.wheels.iter().chain(&s.steering).chain(&s.bogies);
            let mut m = Cdr::new();
            m.header(t);
            m.u32(names.len() as u32);
            for n in &names {
                m.string(n);
            }
            let (pos, rate): (Vec<f64>, Vec<f64>) =
                all.map(|j| (j.position_rad, j.rate_radps)).unzip();
            m.u32(pos.len() as u32);
            m.f64s(&pos);
            m.u32(rate.len() as u32);
            m.f64s(&rate);
            m.u32(0);
            let yaw = pose.rotation.euler_angles().2;
            let q = UnitQuaternion::from_euler_angles(s.imu.roll_rad, s.imu.pitch_rad, yaw);
            let mut i = Cdr::new();
            i.header(t);
            i.f64s(&[q.i, q.j, q.k, q.w]);
            i.f64s(&[0.0; 9]);
            i.f64s(s.imu.gyro_radps.as_slice());
            i.f64s(&[0.0; 9]);
            i.f64s(s.imu.accel_mps2.as_slice());
            i.f64s(&[0.0; 9]);
            let mut o = Cdr::new();
            o.header(t);
            o.string("base_link");
            let r = pose.rotation;
            o.f64s(pose.translation.vector.as_slice());
            o.f64s(&[r.i, r.j, r.k, r.w]);
            o.f64s(&[0.0; 36]);
            o.f64s(&[0.0; 6]);
            o.f64s(&[0.0; 36]);
            let ns = (t * 1e9).round() as u64;
            for (channel_id, data) in [(joints, m.0), (imu, i.0), (odom, o.0)] {
                let header = mcap::records::MessageHeader {
                    channel_id,
                    sequence: k as u32,
                    log_time: ns,
                    publish_time: ns,
                };
                w.write_to_known_channel(&header, &data).unwrap();
            }
        }
        w.finish().unwrap();
    }

    fn parametric_rmse(dir: &Path) -> f64 {
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap())
                .unwrap();
        m["regressors"][0]["evaluation"]["pooled"]["rmse"]
            .as_f64()
            .unwrap()
    }

    #[test]
    fn a_simulated_run_as_mcap_gives_the_residuals_of_its_csv() {
        let tmp = tempfile::tempdir().unwrap();
        let logs = tmp.path().join("logs");
        let out = Command::new(GPODO)
            .args([
                "--quiet",
                "simulate",
                "--seed",
                "3",
                "--training-runs",
                "1",
                "--training-run-secs",
                "60",
                "--out",
            ])
            .arg(&logs)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        for run in ["train_01", "test"] {
            let log = read_log_csv(&logs.join(format!("{run}.csv"))).unwrap();
            write_mcap(&log, &tmp.path().join(format!("{run}.mcap")));
        }
        let joints = |prefix: &str, names: &[&str]| {
            names
                .iter()
                .map(|n| format!("{n}: {{joint: {prefix}_{n}}}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let common = "motion_model: {kind: weighted_jacobian}\nregressors:\n  - kind: zero\n";
        let csv_yaml = format!(
            "name: csv\ndataset: {{kind: logs, train: [logs/train_01.csv], test: [logs/test.csv]}}\n{common}"
        );
        let bag_yaml = format!(
            "name: bag\ndataset:\n  kind: bags\n  train: [train_01.mcap]\n  test: [test.mcap]\n  topics:\n    imu: /imu\n    ground_truth: /gt\n    rate_hz: 12.5\n    max_gap_secs: 0.1\n    joints: {{topic: /joint_states, wheels: {{{}}}, steering: {{{}}}, bogies: {{{}}}}}\n{common}",
            joints("wheel", &["fl", "fr", "ml", "mr", "rl", "rr"]),
            joints("steer", &["fl", "fr", "rl", "rr"]),
            joints("bogie", &["left", "right", "rear"]),
        );
        let mut rmse = Vec::new();
        for (name, yaml) in [("csv", csv_yaml), ("bag", bag_yaml)] {
            let file = tmp.path().join(format!("{name}.yaml"));
            std::fs::write(&file, yaml).unwrap();
            let dir = tmp.path().join(format!("out-{name}"));
            let out = super::gpodo_on("run", &file, &dir, &[]);
            assert!(
                out.status.success(),
                "{name}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            rmse.push(parametric_rmse(&dir));
            if name == "bag" {
                let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
                assert!(
                    report.contains("ROS bags at 12.5 Hz")
                        && report.contains("train_01: 750 rows, 0 dropped in gaps")
                        && report.contains("joints /joint_states: 750 msgs, 0 duplicated"),
                    "the report says what the import did"
                );
            }
        }
        eprintln!("parametric residual RMSE: CSV {} MCAP {}", rmse[0], rmse[1]);
        assert!(
            (rmse[0] - rmse[1]).abs() <= 1e-6 * rmse[0],
            "the parametric model's residual RMSE: CSV {} against MCAP {}",
            rmse[0],
            rmse[1]
        );
    }
}

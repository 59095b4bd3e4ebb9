//! `dataset: {kind: bags}` reads ROS bags through a topic map (issue 17
//! allows tests to read the shared Husky recording): the recording has no
//! joint encoders, so the ExoTeR model refuses it naming the missing
//! wheels; a topic the bag does not have is named with the bag's topics.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;
use std::process::Command;

const GPODO: &str = env!("CARGO_BIN_EXE_gpodo");

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
    let out = Command::new(GPODO)
        .args(["--quiet", "run"])
        .arg(&file)
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .unwrap();
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

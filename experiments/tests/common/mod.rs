//! Helpers shared by the integration tests that run the `gpodo` binary.

#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

/// The binary under test.
pub const GPODO: &str = env!("CARGO_BIN_EXE_gpodo");

/// `gpodo --quiet COMMAND FILE --out DIR EXTRA…`, outside any Slurm array
/// (a task id would make a run one shard of its sweep).
pub fn gpodo_on(command: &str, file: &Path, out: &Path, extra: &[&str]) -> Output {
    Command::new(GPODO)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .args(["--quiet", command])
        .arg(file)
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .expect("the gpodo binary runs")
}

/// Fails the test with the command's stderr (prefixed by `what`) unless it
/// succeeded.
pub fn assert_succeeded(out: &Output, what: &str) {
    assert!(
        out.status.success(),
        "{what}{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The Python with NumPy the plugin tests run (`GPODO_PYTHON`, else
/// `python3`), or `None` after saying why, unless `GPODO_REQUIRE_PYTHON` is
/// set (as CI sets it), which makes its absence a failure.
pub fn python() -> Option<String> {
    gpodo_testkit::python_with(&["numpy"], "NumPy")
}

/// ExoTeR's rover description.
pub fn exoter() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../kinematics/rovers/exoter.yaml")
}

/// `gpodo --quiet ARGS…`.
pub fn gpodo_quiet(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(GPODO)
        .arg("--quiet")
        .args(args)
        .output()
        .unwrap()
}

/// The `nav_msgs/Odometry` messages on `topic` of the bag at `bag`.
pub fn bag_odometry(bag: &Path, topic: &str) -> Vec<gpodo_datasets::bags::messages::Odometry> {
    use gpodo_datasets::bags::messages::RosMessage;
    gpodo_datasets::bags::topic::read_topic(bag, topic, "odometry", &["nav_msgs/Odometry"])
        .unwrap()
        .into_iter()
        .map(|s| match s.message {
            RosMessage::Odometry(o) => o,
            other => panic!("not odometry: {other:?}"),
        })
        .collect()
}

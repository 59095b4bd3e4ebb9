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

/// Fits an exact GP (RBF, `max_iters` hyperparameter iterations) on the
/// bag `train`, tested on `bag`, read through the topic map at `topics`,
/// with `gpodo fit`; the model is saved to `dir/m.gpodo`, its path
/// returned.
pub fn fit_bag_model(
    dir: &Path,
    topics: &Path,
    train: &Path,
    bag: &Path,
    max_iters: usize,
) -> std::path::PathBuf {
    let indented: String = std::fs::read_to_string(topics)
        .unwrap()
        .lines()
        .map(|l| format!("    {l}\n"))
        .collect();
    let experiment = dir.join("bag.yaml");
    std::fs::write(
        &experiment,
        format!(
            "name: bag\ndataset:\n  kind: bags\n  train: [{}]\n  test: [{}]\n  topics:\n{indented}motion_model: {{kind: weighted_jacobian}}\nregressors:\n  - {{kind: exact_gp, kernel: rbf, hyperopt: {{max_iters: {max_iters}}}}}\n",
            train.display(),
            bag.display()
        ),
    )
    .unwrap();
    let model = dir.join("m.gpodo");
    let regressor = format!("exact GP: rbf [hyperopt.max_iters={max_iters}]");
    let out = gpodo_quiet(&[
        "fit".as_ref(),
        experiment.as_os_str(),
        "--regressor".as_ref(),
        regressor.as_ref(),
        "--save".as_ref(),
        model.as_os_str(),
    ]);
    assert_succeeded(&out, "gpodo fit: ");
    model
}

/// `gpodo --quiet live` replaying `bag` through `model` on ExoTeR with the
/// topic map `topics` and the gate file `gate`, its odometry to `out` and
/// its decisions to `decisions`.
pub fn gpodo_live_gated(
    model: &Path,
    topics: &Path,
    bag: &Path,
    out: &Path,
    gate: &Path,
    decisions: &Path,
) -> Output {
    gpodo_quiet(&[
        "live".as_ref(),
        "--model".as_ref(),
        model.as_os_str(),
        "--rover".as_ref(),
        exoter().as_os_str(),
        "--topics".as_ref(),
        topics.as_os_str(),
        "--replay".as_ref(),
        bag.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--gate".as_ref(),
        gate.as_os_str(),
        "--decisions".as_ref(),
        decisions.as_os_str(),
    ])
}

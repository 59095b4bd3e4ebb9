//! The third stage: running what the plan says. [`data`] turns a dataset
//! specification into residual rows (simulating or loading, the motion
//! model, dead reckoning, standardisation); [`fit`] trains and scores one
//! regressor; [`traverses`] builds the front end's view of each test run;
//! [`schemes`] runs Table II through [`gpodo_frontends::scheme::run_scheme`];
//! [`shared`] does each of these once per distinct input across a sweep and
//! assembles every run's [`results::ExperimentResults`]; [`records`] is the
//! line each run appends to `runs.jsonl`; [`bench`](mod@bench) times every
//! regressor on the same rows for `gpodo bench`; [`models`] saves a
//! trained model (`gpodo fit`) and predicts with one (`gpodo predict`).

pub mod bench;
pub mod calibration;
pub(crate) mod camera;
pub mod data;
pub mod feature_supply;
pub mod fit;
pub mod latency;
pub mod models;
pub mod odometry;
pub mod prequential;
pub mod records;
pub mod results;
pub mod schemes;
pub mod shared;
pub mod traverses;

/// The code version: `git describe --always --dirty` when available.
pub fn code_version() -> String {
    std::process::Command::new("git")
        .args(["describe", "--always", "--dirty"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|| env!("CARGO_PKG_VERSION").to_string())
}

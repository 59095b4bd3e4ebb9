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

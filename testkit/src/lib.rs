//! What gpodo's tests share across crates: the Python interpreter they run
//! peers (OpenCV, the ROS ecosystem's MCAP reader) and plug-ins in.

use std::process::Command;

/// The Python the tests run (`GPODO_PYTHON`, else `python3`) when it can
/// import every module of `modules`. Otherwise `None`, after printing
/// `SKIPPED` and why, unless `GPODO_REQUIRE_PYTHON` is set (as CI sets it),
/// which makes the absence a failure. `what` names the packages in the
/// messages (`"NumPy"`, `"OpenCV (opencv-python-headless)"`).
///
/// # Panics
/// When `GPODO_REQUIRE_PYTHON` is set and the interpreter cannot import
/// `modules`.
pub fn python_with(modules: &[&str], what: &str) -> Option<String> {
    let python = std::env::var("GPODO_PYTHON").unwrap_or_else(|_| "python3".into());
    let imports = format!("import {}", modules.join(", "));
    let ok = Command::new(&python)
        .args(["-c", &imports])
        .output()
        .is_ok_and(|o| o.status.success());
    if ok {
        return Some(python);
    }
    assert!(
        std::env::var_os("GPODO_REQUIRE_PYTHON").is_none(),
        "GPODO_REQUIRE_PYTHON is set but `{python}` cannot `{imports}` ({what})"
    );
    eprintln!("SKIPPED: no `{python}` with {what} (set GPODO_PYTHON to one)");
    None
}

/// Runs `script` (Python source) in `python` with `args` as `sys.argv[1:]`
/// and returns what it printed.
///
/// # Panics
/// When the interpreter cannot start, the script fails (its standard
/// error is the message), or it prints anything but UTF-8.
pub fn run_python(python: &str, script: &str, args: &[&std::ffi::OsStr]) -> String {
    let out = Command::new(python)
        .args(["-c", script])
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot start `{python}`: {e}"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap_or_else(|e| panic!("`{python}` printed non-UTF-8: {e}"))
}

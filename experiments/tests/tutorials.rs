//! The tutorials stay true: every `bash` block of `docs/tutorials/*.md`
//! (but the index) runs, in order, in a fresh folder laid out as the
//! repository (the tutorials copied, `plugins/`, `kinematics/` and
//! `experiments/` linked), with the built `gpodo` first on the `PATH`, and
//! must succeed. A tutorial marked `<!-- tutorial: needs python3 with
//! NumPy -->` is skipped (and says so) when no such Python is found,
//! unless `GPODO_REQUIRE_PYTHON` is set, as CI sets it; `GPODO_PYTHON`
//! names the interpreter whose folder goes on the `PATH`.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

mod common;

use common::GPODO;

const NEEDS_PYTHON: &str = "<!-- tutorial: needs python3 with NumPy -->";

fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// The `bash` blocks of a Markdown text, in order.
fn bash_blocks(markdown: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in markdown.lines() {
        match (&mut current, line.trim_end()) {
            (None, "```bash") => current = Some(String::new()),
            (Some(_), "```") => blocks.extend(current.take()),
            (Some(block), _) => {
                block.push_str(line);
                block.push('\n');
            }
            (None, _) => {}
        }
    }
    blocks
}

/// The `PATH` the tutorials run with: the built `gpodo`'s folder, then
/// `GPODO_PYTHON`'s folder when it names one, then the inherited `PATH`.
fn tutorial_path() -> OsString {
    let mut dirs = vec![Path::new(GPODO).parent().unwrap().to_path_buf()];
    if let Ok(python) = std::env::var("GPODO_PYTHON")
        && let Some(dir) = Path::new(&python).parent()
        && !dir.as_os_str().is_empty()
    {
        dirs.push(dir.to_path_buf());
    }
    dirs.extend(std::env::split_paths(
        &std::env::var_os("PATH").unwrap_or_default(),
    ));
    std::env::join_paths(dirs).unwrap()
}

fn python_with_numpy(path: &OsString) -> bool {
    Command::new("python3")
        .args(["-c", "import numpy"])
        .env("PATH", path)
        .output()
        .is_ok_and(|o| o.status.success())
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

/// A folder laid out as the repository for the tutorials: its own copy of
/// `docs/tutorials` (so that paths like `../../tutorial` stay inside it)
/// and links to the folders they read.
fn workspace(repo: &Path) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    copy_dir(
        &repo.join("docs/tutorials"),
        &dir.path().join("docs/tutorials"),
    );
    for shared in ["plugins", "kinematics", "experiments"] {
        std::os::unix::fs::symlink(repo.join(shared), dir.path().join(shared)).unwrap();
    }
    dir
}

#[test]
fn every_tutorial_command_runs() {
    let repo = repository();
    let mut tutorials: Vec<PathBuf> = std::fs::read_dir(repo.join("docs/tutorials"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .filter(|p| p.file_name().is_some_and(|n| n != "README.md"))
        .collect();
    tutorials.sort();
    assert!(tutorials.len() >= 4, "tutorials found: {tutorials:?}");
    let path = tutorial_path();
    let python = python_with_numpy(&path);
    let start = Instant::now();
    for tutorial in &tutorials {
        let text = std::fs::read_to_string(tutorial).unwrap();
        let name = tutorial.file_name().unwrap().to_string_lossy();
        if text.contains(NEEDS_PYTHON) && !python {
            assert!(
                std::env::var_os("GPODO_REQUIRE_PYTHON").is_none(),
                "{name} needs a python3 with NumPy (GPODO_REQUIRE_PYTHON is set)"
            );
            eprintln!("SKIPPED {name}: no python3 with NumPy (set GPODO_PYTHON to one)");
            continue;
        }
        let blocks = bash_blocks(&text);
        assert!(!blocks.is_empty(), "{name} has no bash block");
        let dir = workspace(&repo);
        for block in blocks {
            let out = Command::new("bash")
                .args(["-euo", "pipefail", "-c", &block])
                .current_dir(dir.path())
                .env("PATH", &path)
                .env_remove("RUST_BACKTRACE")
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "{name}: the block\n{block}\nfailed ({}):\n{}\n{}",
                out.status,
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }
    eprintln!(
        "{} tutorials ran in {:.1} s",
        tutorials.len(),
        start.elapsed().as_secs_f64()
    );
}

#[test]
fn bash_blocks_are_found_in_order_and_other_blocks_are_not() {
    let text = "x\n```bash\na\nb\n```\n```yaml\nc: 1\n```\n```bash\nd\n```\n";
    assert_eq!(bash_blocks(text), vec!["a\nb\n", "d\n"]);
}

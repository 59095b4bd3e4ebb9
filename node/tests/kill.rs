//! `kill -9` loses at most one checkpoint period of learning: a process
//! runs the node's learner on its worker thread, checkpointing every
//! 0.5 s, and is handed targets until it is killed with SIGKILL. A learner
//! resumed from what it left has learned all but at most the targets of
//! the last period (and a margin for a loaded machine), and predicts
//! exactly as a learner fed those same targets from the start.
//!
//! The process is this test binary itself, running the ignored test
//! `learner_process` (which does nothing unless the parent sets
//! `GPODO_KILL_TEST_DIR`).

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{fresh_learner, learner_identity, learner_target as target};
use gpodo_frontends::online::OnlineMode;
use gpodo_node::learner::{LearnerIdentity, LiveLearner};
use gpodo_node::learner_worker::{CheckpointPolicy, LearnerWorker};

/// Seconds between checkpoints.
const EVERY_SECS: f64 = 0.5;
/// Targets handed over a second.
const RATE_HZ: f64 = 100.0;

fn identity() -> LearnerIdentity {
    learner_identity("0".repeat(64))
}

fn fresh() -> LiveLearner {
    fresh_learner(identity())
}

/// The process the test kills: hands the worker a target every
/// 1 / `RATE_HZ` s and prints how many it has handed, until killed.
#[test]
#[ignore = "run by `the_learner_survives_kill_9` as the process it kills"]
fn learner_process() {
    let Ok(dir) = std::env::var("GPODO_KILL_TEST_DIR") else {
        return;
    };
    let worker = LearnerWorker::spawn(
        fresh(),
        Some(CheckpointPolicy {
            path: Path::new(&dir).join("learner.json"),
            every_secs: EVERY_SECS,
        }),
    );
    for i in 0..100_000 {
        worker.learn(target(i));
        println!("handed {}", i + 1);
        std::thread::sleep(Duration::from_secs_f64(1.0 / RATE_HZ));
    }
}

#[test]
fn the_learner_survives_kill_9() {
    let tmp = tempfile::tempdir().unwrap();
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args(["--ignored", "--exact", "learner_process", "--nocapture"])
        .env("GPODO_KILL_TEST_DIR", tmp.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let stdout = BufReader::new(child.stdout.take().unwrap());
    let started = Instant::now();
    let mut handed = 0;
    for line in stdout.lines() {
        let line = line.unwrap();
        if let Some(n) = line.strip_prefix("handed ") {
            handed = n.parse().unwrap();
        }
        // 2.75 s of learning: five checkpoints, and half a period since.
        if handed >= 275 {
            break;
        }
        assert!(started.elapsed() < Duration::from_secs(60), "no progress");
    }
    // SIGKILL: no handler runs, no last checkpoint.
    child.kill().unwrap();
    child.wait().unwrap();

    let resumed = LiveLearner::resume(
        &tmp.path().join("learner.json"),
        OnlineMode::Update,
        1e-4,
        identity(),
        "ilgr",
    )
    .unwrap();
    let kept = resumed.targets_learned();
    let lost = handed - kept;
    println!("handed {handed}, kept {kept}: lost {lost}");
    // At most one period's targets, and as much again for a loaded machine.
    let allowed = (2.0 * EVERY_SECS * RATE_HZ) as u64;
    assert!(kept > 0 && lost <= allowed, "handed {handed}, kept {kept}");
    let mut reference = fresh();
    for i in 0..kept as usize {
        reference.learn(&target(i)).unwrap();
    }
    for x in [[0.2, 0.5], [-0.7, 0.1], [0.9, -0.9]] {
        let (a, b) = (resumed.predict(&x).unwrap(), reference.predict(&x).unwrap());
        assert!((a.mean - b.mean).abs().max() <= 1e-12, "{a:?} {b:?}");
        assert!((a.variance - b.variance).abs().max() <= 1e-12);
    }
}

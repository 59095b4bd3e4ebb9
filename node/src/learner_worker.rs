//! The live learner on a worker thread: the odometry path hands it
//! targets and never waits for it; predictions come from the state it
//! published last. It writes a checkpoint every `every_secs` of learning
//! and when it stops (its sender dropped, as on SIGINT or SIGTERM).
//!
//! In replay the learner runs in lock-step instead ([`LiveLearner`]
//! itself), so that its state is the offline scheme's.

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender, channel};
use std::sync::{Arc, RwLock};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use gpodo_frontends::FrontendError;
use gpodo_frontends::prediction::ResidualPrediction;
use gpodo_frontends::vo_target::VoTarget;

use crate::learner::LiveLearner;

/// Where and how often the worker writes its checkpoint.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckpointPolicy {
    /// The checkpoint file.
    pub path: PathBuf,
    /// Seconds between checkpoints while learning (default 30).
    pub every_secs: f64,
}

/// What the worker did, when it stopped.
pub struct WorkerSummary {
    /// The learner as it ended.
    pub learner: LiveLearner,
    /// Checkpoints written.
    pub checkpoints: u64,
    /// The last error learning or checkpointing (the worker goes on after
    /// one: a target the model refuses, or a full disk).
    pub last_error: Option<String>,
}

/// The learner on its thread.
pub struct LearnerWorker {
    targets: Option<Sender<VoTarget>>,
    latest: Arc<RwLock<Arc<LiveLearner>>>,
    checkpoints: Arc<AtomicU64>,
    handle: Option<JoinHandle<WorkerSummary>>,
}

impl LearnerWorker {
    /// Starts `learner` on a thread, checkpointing as `checkpoint` says.
    pub fn spawn(learner: LiveLearner, checkpoint: Option<CheckpointPolicy>) -> Self {
        let latest = Arc::new(RwLock::new(Arc::new(learner.clone())));
        let (tx, rx) = channel();
        let published = Arc::clone(&latest);
        let checkpoints = Arc::new(AtomicU64::new(0));
        let written = Arc::clone(&checkpoints);
        let handle = std::thread::spawn(move || {
            run(learner, &rx, &published, &written, checkpoint.as_ref())
        });
        Self {
            targets: Some(tx),
            latest,
            checkpoints,
            handle: Some(handle),
        }
    }

    /// Hands a target to the learner; never waits.
    pub fn learn(&self, target: VoTarget) {
        if let Some(tx) = &self.targets {
            // A worker that has stopped takes no more targets.
            let _ = tx.send(target);
        }
    }

    /// The prediction on a raw row from the state published last.
    ///
    /// # Errors
    /// What the model reports.
    pub fn predict(&self, row: &[f64]) -> Result<ResidualPrediction, FrontendError> {
        self.latest().predict(row)
    }

    /// Targets learned by the state published last.
    pub fn targets_learned(&self) -> u64 {
        self.latest().targets_learned()
    }

    /// Checkpoints written so far.
    pub fn checkpoints(&self) -> u64 {
        self.checkpoints.load(Ordering::Relaxed)
    }

    /// The learner's input columns, in the model's order.
    pub fn input_names(&self) -> Vec<String> {
        self.latest().input_names().to_vec()
    }

    /// Where the learner started from.
    pub fn start(&self) -> crate::learner::LearnerStart {
        self.latest().start()
    }

    /// The state published last (a worker that panicked while publishing
    /// left a whole one: the swap is one pointer).
    fn latest(&self) -> Arc<LiveLearner> {
        match self.latest.read() {
            Ok(guard) => Arc::clone(&guard),
            Err(poisoned) => Arc::clone(&poisoned.into_inner()),
        }
    }

    /// Stops the worker after the targets already handed over, writing a
    /// last checkpoint; returns what it did (`None` if its thread
    /// panicked).
    pub fn stop(mut self) -> Option<WorkerSummary> {
        self.targets = None;
        self.handle.take().and_then(|h| h.join().ok())
    }
}

impl Drop for LearnerWorker {
    fn drop(&mut self) {
        self.targets = None;
        if let Some(handle) = self.handle.take() {
            let _ = handle.join();
        }
    }
}

fn run(
    mut learner: LiveLearner,
    rx: &Receiver<VoTarget>,
    latest: &RwLock<Arc<LiveLearner>>,
    written: &AtomicU64,
    checkpoint: Option<&CheckpointPolicy>,
) -> WorkerSummary {
    let mut summary_error = None;
    let mut last_written = Instant::now();
    let write = |learner: &LiveLearner, error: &mut Option<String>| {
        if let Some(policy) = checkpoint {
            match learner.checkpoint(&policy.path) {
                Ok(true) => {
                    written.fetch_add(1, Ordering::Relaxed);
                }
                Ok(false) => {}
                Err(e) => *error = Some(e.to_string()),
            }
        }
    };
    let period = checkpoint.map(|p| Duration::from_secs_f64(p.every_secs.max(0.0)));
    loop {
        let wait = period.map_or(Duration::from_secs(3600), |p| {
            p.saturating_sub(last_written.elapsed())
        });
        match rx.recv_timeout(wait) {
            Ok(target) => {
                if let Err(e) = learner.learn(&target) {
                    summary_error = Some(e.to_string());
                }
                let snapshot = Arc::new(learner.clone());
                match latest.write() {
                    Ok(mut guard) => *guard = snapshot,
                    Err(poisoned) => *poisoned.into_inner() = snapshot,
                }
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => break,
        }
        if period.is_some_and(|p| last_written.elapsed() >= p) {
            write(&learner, &mut summary_error);
            last_written = Instant::now();
        }
    }
    write(&learner, &mut summary_error);
    WorkerSummary {
        learner,
        checkpoints: written.load(Ordering::Relaxed),
        last_error: summary_error,
    }
}

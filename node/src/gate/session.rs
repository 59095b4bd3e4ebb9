//! The gate and the learner in the node: what the node does with each
//! message of the gate's topics and with each odometry output, whether
//! the messages come over DDS or from a recording.
//!
//! * Each odometry output ends a step: the motion model's twist of the
//!   output before it, over the time between them. The gate is driven
//!   along the steps lazily, up to each pair's stamp when it is decided,
//!   so a policy reads the odometry up to the frame, as offline.
//! * The residual the selector reads is put in force either at every
//!   output, predicted on its row ([`PredictionClock::Sample`]), or at the
//!   end of each regressor window on the offline grid, predicted on that
//!   window's row ([`PredictionClock::Windows`], [`super::windows`]): the
//!   offline front end's clock, so a replay makes its decisions.
//! * With a learner, the residual the node publishes on `/odom/gp` is the
//!   learner's ([`RowResidual`]): its prior (a zero residual with the
//!   prior variance) before it has learned, its model after.
//! * Image and camera-info messages are paired by stamp; each pair is
//!   decided once, and a pair chosen is handed back to be forwarded
//!   unchanged.
//! * Each VO pose is made into a target when it closes an interval, and
//!   the target is learned: in lock-step in replay, on the worker thread
//!   live.

use gpodo_datasets::bags::messages::Odometry;
use gpodo_frontends::FrontendError;
use gpodo_frontends::prediction::ResidualPrediction;
use gpodo_frontends::vo_target::VoTarget;
use std::collections::VecDeque;

use crate::NodeError;
use crate::diagnostics::{OK, WARN};
use crate::gate::pairing::{
    PairingFaults, PairingSettings, Part, PartHeader, StereoPair, StereoPairer,
};
use crate::gate::report::{LearnerReport, gate_status};
use crate::gate::windows::GridWindows;

mod drive;
use crate::gate::{GateCounts, GateDecision, LiveGate, PoseOutcome};
use crate::learner::{LearnerStart, LiveLearner};
use crate::learner_worker::{LearnerWorker, WorkerSummary};
use crate::pipeline::RowResidual;
use drive::{Sample, Step};
use gpodo_datasets::bags::write::DiagnosticStatus;

/// Where the learner runs.
pub enum Learning {
    /// In lock-step with the messages (replay and tests): each target is
    /// learned before the next message.
    LockStep(Box<LiveLearner>),
    /// On a worker thread (live): the odometry path never waits for it.
    Worker(LearnerWorker),
}

impl Learning {
    fn predict(&self, row: &[f64]) -> Result<ResidualPrediction, FrontendError> {
        match self {
            Self::LockStep(l) => l.predict(row),
            Self::Worker(w) => w.predict(row),
        }
    }

    fn learn(&mut self, target: VoTarget) -> Result<(), FrontendError> {
        match self {
            Self::LockStep(l) => l.learn(&target),
            Self::Worker(w) => {
                w.learn(target);
                Ok(())
            }
        }
    }

    fn report(&self) -> LearnerReport {
        match self {
            Self::LockStep(l) => LearnerReport {
                start: l.start(),
                targets_learned: l.targets_learned(),
                checkpoints: 0,
            },
            Self::Worker(w) => LearnerReport {
                start: w.start(),
                targets_learned: w.targets_learned(),
                checkpoints: w.checkpoints(),
            },
        }
    }
}

/// When the gate puts a new residual prediction in force.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PredictionClock {
    /// At every odometry output, predicted on the row the node publishes
    /// with (its trailing window).
    Sample,
    /// At the end of each window of `window_secs` on the grid from the
    /// first output, as the offline front end does: the learner's
    /// prediction on that window's row, or without a learner the saved
    /// model's on the row of the first output at or after the window's
    /// end (its trailing window); a target's inputs are those of the
    /// windows its interval spans. Each prediction starts a new block of
    /// fully correlated drift in what the policy reads, so the blocks are
    /// windows, as offline, not samples.
    Windows {
        /// The windows' length (s): the learner's rows'.
        window_secs: f64,
    },
}

/// Faults the session counts beyond the pairing's and the gate's.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SessionFaults {
    /// Times an image topic went silent (no message for the set time
    /// while the other image topic went on).
    pub silent_image_topics: u64,
    /// Messages on the gate's topics that could not be decoded.
    pub undecodable: u64,
    /// Targets the learner refused (in lock-step; the worker reports its
    /// own when it stops).
    pub learn_errors: u64,
    /// Predictions the gate could not put in force while driving to a
    /// pair.
    pub predictions_refused: u64,
    /// VO poses of another child frame than the gate expects.
    pub other_child_frame: u64,
}

/// How the learner ended.
pub enum LearnerEnd {
    /// No learner.
    None,
    /// The lock-step learner.
    LockStep(Box<LiveLearner>),
    /// The worker's summary (`None` if its thread panicked).
    Worker(Option<Box<WorkerSummary>>),
}

/// The gate, its pairing and its learner in the node.
pub struct GateSession<T> {
    gate: LiveGate,
    pairer: StereoPairer<T>,
    learner: Option<Learning>,
    /// Per learner input, its column in the node's rows.
    learner_columns: Vec<usize>,
    /// The previous output.
    previous: Option<Sample>,
    /// The step the gate is being driven along, and how far (s).
    step: Option<Step>,
    driven_secs: f64,
    /// The regressor windows (the window clock).
    windows: Option<GridWindows>,
    /// Targets formed, waiting for their windows to close (the window
    /// clock).
    waiting: VecDeque<VoTarget>,
    /// The saved model's prediction on the last output's row (the window
    /// clock without a learner).
    saved: Option<ResidualPrediction>,
    image_silent_secs: f64,
    /// The VO's `child_frame_id` the gate expects, if it checks.
    child_frame_id: Option<String>,
    /// Per image topic (left, right): when its last message came (node
    /// clock, s) and whether its silence has been counted.
    image_seen: [(Option<f64>, bool); 2],
    faults: SessionFaults,
}

impl<T> GateSession<T> {
    /// The gate `gate` pairing as `pairing` says, with `learner` learning
    /// from its targets on the node's rows of `node_columns` and
    /// predictions put in force on `clock`; an image topic silent for
    /// `image_silent_secs` while the other goes on is a fault.
    ///
    /// # Errors
    /// [`NodeError::Topics`] when the learner reads a column the node's
    /// rows do not have, or the window clock has no window.
    pub fn new(
        mut gate: LiveGate,
        pairing: PairingSettings,
        learner: Option<Learning>,
        node_columns: &[String],
        clock: PredictionClock,
        image_silent_secs: f64,
    ) -> Result<Self, NodeError> {
        let windows = match clock {
            PredictionClock::Sample => None,
            PredictionClock::Windows { window_secs } => {
                if !(window_secs.is_finite() && window_secs > 0.0) {
                    return Err(NodeError::Topics(format!(
                        "predictions on the window clock need rows averaged over a window; these have {window_secs} s"
                    )));
                }
                Some(GridWindows::new(window_secs))
            }
        };
        if windows.is_some() {
            gate.attribute_inputs_later();
        }
        let names: Vec<String> = match &learner {
            Some(Learning::LockStep(l)) => l.input_names().to_vec(),
            Some(Learning::Worker(w)) => w.input_names(),
            None => Vec::new(),
        };
        let learner_columns = names
            .iter()
            .map(|name| {
                node_columns.iter().position(|c| c == name).ok_or_else(|| {
                    NodeError::Topics(format!(
                        "the learner reads `{name}`, which this robot's rows do not have ({node_columns:?})"
                    ))
                })
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            gate,
            pairer: StereoPairer::new(pairing),
            learner,
            learner_columns,
            previous: None,
            step: None,
            driven_secs: f64::NEG_INFINITY,
            windows,
            waiting: VecDeque::new(),
            saved: None,
            image_silent_secs,
            child_frame_id: None,
            image_seen: [(None, false); 2],
            faults: SessionFaults::default(),
        })
    }

    /// Poses are used only when the VO's `child_frame_id` is `frame`
    /// (the frame `body_from_child` is the transform of); others are
    /// counted and not used.
    #[must_use]
    pub fn with_child_frame_id(mut self, frame: Option<String>) -> Self {
        self.child_frame_id = frame;
        self
    }

    /// Messages kept per camera topic while they wait for their partners.
    pub fn history_depth(&self) -> usize {
        self.pairer.settings().history_depth
    }

    /// Whether a learner runs (its residual is then the one published).
    pub fn learns(&self) -> bool {
        self.learner.is_some()
    }

    /// The residual the node publishes, when a learner runs.
    pub fn residual(&self) -> Option<&dyn RowResidual> {
        self.learner.as_ref().map(|_| self as &dyn RowResidual)
    }

    /// The learner's inputs of a node row.
    fn learner_row(&self, row: &[f64]) -> Vec<f64> {
        self.learner_columns.iter().map(|&c| row[c]).collect()
    }

    /// One image or camera-info message received at `now_secs` on the
    /// node's clock: the pair it completes, if it does.
    pub fn part(
        &mut self,
        part: Part,
        header: PartHeader,
        message: T,
        now_secs: f64,
    ) -> Option<StereoPair<T>> {
        match part {
            Part::LeftImage => self.image_seen[0] = (Some(now_secs), false),
            Part::RightImage => self.image_seen[1] = (Some(now_secs), false),
            Part::LeftInfo | Part::RightInfo => {}
        }
        self.pairer.push(part, header, message)
    }

    /// The gate's decision on `pair` at `now_secs`, on the odometry
    /// driven up to its stamp (as far as the outputs so far reach), with
    /// the pair when it is to be forwarded. A prediction due on the way
    /// that the gate's odometry cannot use, or that the learner failed
    /// to make, is counted and the one in force kept.
    pub fn decide(
        &mut self,
        pair: StereoPair<T>,
        now_secs: f64,
    ) -> (GateDecision, Option<StereoPair<T>>) {
        if self.drive_to(self.gate.secs(pair.stamp_ns)).is_err() {
            self.faults.predictions_refused += 1;
        }
        let decision = self.gate.decide(pair.stamp_ns, now_secs);
        let forwarded = decision.processed.then_some(pair);
        (decision, forwarded)
    }

    /// A message on the gate's topics that could not be decoded.
    pub fn undecodable(&mut self) {
        self.faults.undecodable += 1;
    }

    /// The VO's odometry: learned from when it closes a target interval.
    pub fn vo_odometry(&mut self, m: &Odometry) -> PoseOutcome {
        if self
            .child_frame_id
            .as_ref()
            .is_some_and(|f| *f != m.child_frame_id)
        {
            self.faults.other_child_frame += 1;
            return PoseOutcome::OtherFrame;
        }
        let c = &m.pose_covariance;
        let variances = if c.len() == 36 {
            [c[0], c[7], c[14]]
        } else {
            [0.0; 3]
        };
        let outcome = self.gate.vo_pose(
            m.header.stamp_ns,
            m.pose.position,
            m.pose.orientation,
            variances,
        );
        if let PoseOutcome::Target(target) = &outcome {
            if self.windows.is_some() {
                self.waiting.push_back(target.clone());
                self.learn_waiting();
            } else if let Some(learner) = self.learner.as_mut()
                && learner.learn(target.clone()).is_err()
            {
                self.faults.learn_errors += 1;
            }
        }
        outcome
    }

    /// The VO's Bool status topic.
    pub fn vo_status(&mut self, lost: bool) {
        self.gate.reported_lost(lost);
    }

    /// Counts an image topic gone silent at `now_secs` (once per silence).
    pub fn watch(&mut self, now_secs: f64) {
        let other_recent = |k: usize, seen: &[(Option<f64>, bool); 2]| {
            seen[1 - k]
                .0
                .is_some_and(|t| now_secs - t < self.image_silent_secs)
        };
        for k in 0..2 {
            let (last, counted) = self.image_seen[k];
            if !counted
                && last.is_some_and(|t| now_secs - t >= self.image_silent_secs)
                && other_recent(k, &self.image_seen)
            {
                self.image_seen[k].1 = true;
                self.faults.silent_image_topics += 1;
            }
        }
    }

    /// The residual prediction in force for the policy.
    pub fn prediction(&self) -> &ResidualPrediction {
        self.gate.prediction()
    }

    /// The gate's counts.
    pub fn counts(&self) -> GateCounts {
        self.gate.counts()
    }

    /// The pairing's faults.
    pub fn pairing_faults(&self) -> PairingFaults {
        self.pairer.faults()
    }

    /// The session's own faults.
    pub fn faults(&self) -> SessionFaults {
        self.faults
    }

    /// What the learner has done.
    pub fn learner_report(&self) -> Option<LearnerReport> {
        self.learner.as_ref().map(Learning::report)
    }

    /// Where the learner started (none without one).
    pub fn learner_start(&self) -> Option<LearnerStart> {
        self.learner_report().map(|r| r.start)
    }

    /// The gate's status for `/diagnostics`.
    pub fn status(&self) -> DiagnosticStatus {
        let mut status = gate_status(
            self.gate.policy(),
            &self.gate.counts(),
            &self.pairer.faults(),
            self.learner_report().as_ref(),
        );
        let f = self.faults;
        status.values.extend([
            (
                "image topics gone silent".to_string(),
                f.silent_image_topics.to_string(),
            ),
            (
                "gate messages undecodable".to_string(),
                f.undecodable.to_string(),
            ),
            ("targets refused".to_string(), f.learn_errors.to_string()),
            (
                "predictions refused".to_string(),
                f.predictions_refused.to_string(),
            ),
            (
                "VO poses of another child frame".to_string(),
                f.other_child_frame.to_string(),
            ),
        ]);
        let faults = f.silent_image_topics
            + f.undecodable
            + f.learn_errors
            + f.predictions_refused
            + f.other_child_frame;
        if faults > 0 && status.level == OK {
            status.level = WARN;
            status.message = format!(
                "{} image topics gone silent, {} undecodable, {} targets refused, {} predictions refused, {} VO poses of another child frame",
                f.silent_image_topics,
                f.undecodable,
                f.learn_errors,
                f.predictions_refused,
                f.other_child_frame
            );
        }
        status
    }

    /// Ends the session: the gate is driven to the last output; on the
    /// window clock the windows still open are closed with the steps they
    /// have, and the targets waiting for them learned; a worker is stopped
    /// after the targets handed to it, writing its last checkpoint.
    pub fn finish(mut self) -> LearnerEnd {
        if let Some(end) = self.step.as_ref().map(|s| s.end_secs) {
            // A prediction the odometry cannot use changes nothing learned.
            let _ = self.drive_to(end);
        }
        if let Some(windows) = self.windows.as_mut() {
            windows.close_all();
            self.learn_waiting();
        }
        match self.learner {
            None => LearnerEnd::None,
            Some(Learning::LockStep(l)) => LearnerEnd::LockStep(l),
            Some(Learning::Worker(w)) => LearnerEnd::Worker(w.stop().map(Box::new)),
        }
    }
}

impl<T> RowResidual for GateSession<T> {
    fn residual(&self, row: &[f64]) -> Result<([f64; 3], [f64; 3]), String> {
        let Some(learner) = &self.learner else {
            return Err("no learner".into());
        };
        let p = learner
            .predict(&self.learner_row(row))
            .map_err(|e| e.to_string())?;
        Ok((p.mean.into(), p.variance.into()))
    }
}

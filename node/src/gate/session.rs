//! The gate and the learner in the node: what the node does with each
//! message of the gate's topics and with each odometry output, whether
//! the messages come over DDS or from a recording.
//!
//! * Each odometry output drives the gate with the motion model's twist
//!   over the step before it and the row in force, and puts the residual
//!   predicted on that row in force for the selector.
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
use gpodo_traits::BodyTwist;
use nalgebra::Vector3;

use crate::NodeError;
use crate::diagnostics::{OK, WARN};
use crate::gate::pairing::{
    PairingFaults, PairingSettings, Part, PartHeader, StereoPair, StereoPairer,
};
use crate::gate::report::{LearnerReport, gate_status};
use crate::gate::{GateCounts, GateDecision, LiveGate, PoseOutcome};
use crate::learner::{LearnerStart, LiveLearner};
use crate::learner_worker::{LearnerWorker, WorkerSummary};
use crate::pipeline::{LiveOutput, RowResidual};
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
    /// The previous output's time, the motion model's twist and the
    /// learner's inputs of its row.
    previous: Option<(f64, BodyTwist, Option<Vec<f64>>)>,
    image_silent_secs: f64,
    /// Per image topic (left, right): when its last message came (node
    /// clock, s) and whether its silence has been counted.
    image_seen: [(Option<f64>, bool); 2],
    faults: SessionFaults,
}

impl<T> GateSession<T> {
    /// The gate `gate` pairing as `pairing` says, with `learner` learning
    /// from its targets on the node's rows of `node_columns`; an image
    /// topic silent for `image_silent_secs` while the other goes on is a
    /// fault.
    ///
    /// # Errors
    /// [`NodeError::Topics`] when the learner reads a column the node's
    /// rows do not have.
    pub fn new(
        gate: LiveGate,
        pairing: PairingSettings,
        learner: Option<Learning>,
        node_columns: &[String],
        image_silent_secs: f64,
    ) -> Result<Self, NodeError> {
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
            image_silent_secs,
            image_seen: [(None, false); 2],
            faults: SessionFaults::default(),
        })
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

    /// One odometry output: the gate drives the step before it with the
    /// previous output's twist, and the residual predicted on its row is
    /// put in force.
    ///
    /// # Errors
    /// A prediction the gate's odometry cannot use.
    pub fn output(&mut self, out: &LiveOutput) -> Result<(), FrontendError> {
        if let Some((time, twist, inputs)) = self.previous.take() {
            self.gate
                .drive(&twist, out.time_secs - time, inputs.as_deref());
        }
        let inputs = out
            .row
            .as_deref()
            .filter(|_| self.learner.is_some())
            .map(|row| self.learner_row(row));
        self.previous = Some((out.time_secs, out.uncorrected, inputs));
        if let Some((mean, variance)) = out.residual {
            self.gate.predict(ResidualPrediction {
                mean: Vector3::from(mean),
                variance: Vector3::from(variance),
                absolute: None,
            })?;
        }
        Ok(())
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

    /// The gate's decision on `pair` at `now_secs`, with the pair when it
    /// is to be forwarded.
    pub fn decide(
        &mut self,
        pair: StereoPair<T>,
        now_secs: f64,
    ) -> (GateDecision, Option<StereoPair<T>>) {
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
        if let (PoseOutcome::Target(target), Some(learner)) = (&outcome, self.learner.as_mut())
            && learner.learn(target.clone()).is_err()
        {
            self.faults.learn_errors += 1;
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
        ]);
        if f.silent_image_topics + f.undecodable + f.learn_errors > 0 && status.level == OK {
            status.level = WARN;
            status.message = format!(
                "{} image topics gone silent, {} undecodable, {} targets refused",
                f.silent_image_topics, f.undecodable, f.learn_errors
            );
        }
        status
    }

    /// Ends the session: a worker is stopped after the targets handed to
    /// it, writing its last checkpoint.
    pub fn finish(self) -> LearnerEnd {
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

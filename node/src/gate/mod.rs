//! The live frame gate: which stereo pairs a visual odometry gets, decided
//! per pair by a frontends [`FrameSelector`] from the odometry driven
//! since the last pair it got and the residual prediction in force, and
//! the VO's poses for those pairs made into residual targets for an
//! online learner.
//!
//! * [`pairing`]: the left and right images and their camera infos paired
//!   by stamp, never by pixels;
//! * [`lost`]: whether the VO is lost, from its odometry or a Bool topic;
//! * [`report`]: each decision and the gate's counts as
//!   `diagnostic_msgs/DiagnosticStatus`;
//! * [`session`]: the gate, its pairing and its learner in the node, fed
//!   each message and each odometry output;
//! * [`topics`]: the topics it reads and publishes.
//!
//! [`LiveGate`] keeps what the selector reads with the offline front
//! end's own [`GateState`], and forms targets with its
//! [`TargetInterval`]; while the VO is lost, the selector's lost-tracking
//! rule ([`gpodo_frontends::gating::WhileLost`], built by
//! [`gpodo_frontends::scheme::causal_selector`]) looks every
//! `lost_frame_period_secs`, as offline. A keyframe-threshold scale the
//! policy asks for cannot be applied to an external SLAM: it is reported
//! with the decision.

pub mod lost;
pub mod pairing;
pub mod report;
pub mod session;
pub mod topics;
pub mod windows;

use std::collections::VecDeque;

use gpodo_frontends::FrontendError;
use gpodo_frontends::gate::GateState;
use gpodo_frontends::odometry::OdometryInterval;
use gpodo_frontends::params::OnlineTargetParams;
use gpodo_frontends::prediction::ResidualPrediction;
use gpodo_frontends::vo_target::{NoTarget, TargetInterval, VoTarget};
use gpodo_traits::{BodyTwist, FrameDecision, FrameSelector};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};

use lost::{LostDetector, LostReason, LostSettings, PoseVerdict};

/// When a VO pose is a jump, not learned from (a gate file's `jump:`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct JumpSettings {
    /// A displacement off the motion model's by more than this many
    /// standard deviations (of the odometry's and the VO's position
    /// covariances together) is a jump (default 5).
    pub max_sigmas: f64,
    /// And by more than this (m; default 0.25): a floor for covariances
    /// that claim too much.
    pub min_jump_m: f64,
}

impl Default for JumpSettings {
    fn default() -> Self {
        Self {
            max_sigmas: 5.0,
            min_jump_m: 0.25,
        }
    }
}

/// How the gate decides and learns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveGateSettings {
    /// When the VO counts as lost.
    pub lost: LostSettings,
    /// How long a target interval spans.
    pub targets: OnlineTargetParams,
    /// When a pose is a jump.
    pub jump: JumpSettings,
    /// The VO's child frame in the body frame (`body_from_child`;
    /// identity when the VO's `child_frame_id` is the body's).
    pub body_from_child: Isometry3<f64>,
}

impl Default for LiveGateSettings {
    fn default() -> Self {
        Self {
            lost: LostSettings::default(),
            targets: OnlineTargetParams::default(),
            jump: JumpSettings::default(),
            body_from_child: Isometry3::identity(),
        }
    }
}

/// The gate's decision on one pair.
#[derive(Debug, Clone, PartialEq)]
pub struct GateDecision {
    /// The pair's stamp (ns).
    pub stamp_ns: i64,
    /// Whether the pair is forwarded to the VO.
    pub processed: bool,
    /// Why: the policy's name, or the loss it looks more often for.
    pub reason: String,
    /// The keyframe-threshold scale the policy asked for (1: unchanged),
    /// which an external SLAM cannot be given.
    pub keyframe_threshold_scale: Option<f64>,
    /// Whether the VO was lost when the pair came.
    pub tracking_lost: Option<LostReason>,
}

/// What one VO pose gave.
#[derive(Debug, Clone, PartialEq)]
pub enum PoseOutcome {
    /// A residual target to learn.
    Target(VoTarget),
    /// A pose, no target yet (or none from its interval, and why).
    Pose(Option<NoTarget>),
    /// The VO says it is lost.
    Lost(LostReason),
    /// A jump (relocalisation, reset, or implausible displacement): not
    /// learned from, a new interval starts at it.
    Jump,
    /// A pose for no pair the gate forwarded.
    Unexpected,
    /// A pose of another child frame than the one the gate expects
    /// (`child_frame_id`): not used, since `body_from_child` is not its
    /// transform.
    OtherFrame,
}

/// What the gate counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct GateCounts {
    /// Pairs decided.
    pub decided: u64,
    /// Pairs forwarded.
    pub forwarded: u64,
    /// Forwarded pairs the VO gave no pose for.
    pub unanswered: u64,
    /// Poses that said the VO was lost.
    pub lost_poses: u64,
    /// Jumps.
    pub jumps: u64,
    /// Poses for pairs not forwarded.
    pub unexpected_poses: u64,
    /// Targets formed.
    pub targets: u64,
}

/// The gate.
pub struct LiveGate {
    settings: LiveGateSettings,
    state: GateState,
    selector: Box<dyn FrameSelector>,
    lost: LostDetector,
    /// Forwarded pairs waiting for their pose: stamp and odometry since
    /// the previous forwarded pair.
    awaiting: VecDeque<(i64, OdometryInterval)>,
    target: Option<TargetInterval>,
    last_pose: Option<Isometry3<f64>>,
    counts: GateCounts,
    /// Whether the targets' inputs are attributed by the caller (the
    /// gate is then driven without them).
    inputs_later: bool,
    /// The stamp its times count from (ns).
    origin_ns: i64,
}

impl LiveGate {
    /// A gate running `selector` (built by
    /// [`gpodo_frontends::scheme::causal_selector`]) on the odometry
    /// `state` keeps.
    pub fn new(
        selector: Box<dyn FrameSelector>,
        state: GateState,
        settings: LiveGateSettings,
    ) -> Self {
        let mut selector = selector;
        selector.reset();
        Self {
            lost: LostDetector::new(settings.lost),
            settings,
            state,
            selector,
            awaiting: VecDeque::new(),
            target: None,
            last_pose: None,
            counts: GateCounts::default(),
            inputs_later: false,
            origin_ns: 0,
        }
    }

    /// Drives `dt_secs` with the motion model's `twist` and the regressor
    /// inputs of the row in force.
    pub fn drive(&mut self, twist: &BodyTwist, dt_secs: f64, inputs: Option<&[f64]>) {
        self.state.drive(twist, dt_secs, inputs);
    }

    /// A new residual prediction is in force.
    ///
    /// # Errors
    /// A prediction the odometry mode cannot use.
    pub fn predict(&mut self, prediction: ResidualPrediction) -> Result<(), FrontendError> {
        self.state.predict(prediction)
    }

    /// The Bool topic said the VO is lost (`true`) or tracking.
    pub fn reported_lost(&mut self, lost: bool) {
        self.lost.reported(lost);
    }

    /// Decides the pair stamped `stamp_ns` (its time counted from the
    /// origin), at `now_secs` on the node's clock.
    pub fn decide(&mut self, stamp_ns: i64, now_secs: f64) -> GateDecision {
        let time_secs = self.secs(stamp_ns);
        let lost = self.lost.lost(now_secs);
        let ctx = self.state.context(time_secs, lost.is_some());
        let decision = self.selector.decide(&ctx);
        self.counts.decided += 1;
        let reason = match lost {
            Some(why) => format!("{} (tracking lost: {})", self.selector.name(), why.as_str()),
            None => self.selector.name().to_string(),
        };
        let keyframe_threshold_scale = match decision {
            FrameDecision::Process {
                keyframe_threshold_scale,
            } => {
                let interval = self.state.processed(time_secs);
                self.awaiting.push_back((stamp_ns, interval));
                self.lost.forwarded(now_secs);
                self.counts.forwarded += 1;
                Some(keyframe_threshold_scale)
            }
            FrameDecision::Skip => None,
        };
        GateDecision {
            stamp_ns,
            processed: keyframe_threshold_scale.is_some(),
            reason,
            keyframe_threshold_scale,
            tracking_lost: lost,
        }
    }

    /// The VO's pose for the pair stamped `stamp_ns`: the child frame's
    /// position and orientation quaternion as received (x, y, z, w) in the
    /// VO's world, and its position variances.
    pub fn vo_pose(
        &mut self,
        stamp_ns: i64,
        position: [f64; 3],
        quaternion_xyzw: [f64; 4],
        position_variances: [f64; 3],
    ) -> PoseOutcome {
        // Forwarded pairs older than this one got no pose: the VO was
        // lost on them, and no interval spans them.
        while self.awaiting.front().is_some_and(|(s, _)| *s < stamp_ns) {
            self.awaiting.pop_front();
            self.counts.unanswered += 1;
            self.target = None;
            self.last_pose = None;
        }
        let Some((_, interval)) = self
            .awaiting
            .front()
            .is_some_and(|(s, _)| *s == stamp_ns)
            .then(|| self.awaiting.pop_front())
            .flatten()
        else {
            self.counts.unexpected_poses += 1;
            return PoseOutcome::Unexpected;
        };
        if let PoseVerdict::Lost(reason) = self.lost.pose(quaternion_xyzw, position_variances) {
            self.counts.lost_poses += 1;
            self.target = None;
            self.last_pose = None;
            return PoseOutcome::Lost(reason);
        }
        let [x, y, z, w] = quaternion_xyzw;
        let q = Quaternion::new(w, x, y, z);
        // A quaternion received unit to 1e-6 is used as it is, so the
        // targets are formed from the pose the VO computed (a VO composing
        // rotations drifts off unit: the statistical tracker's chain by
        // 1e-9 over a minute); any other is normalised.
        let rotation = if (q.norm_squared() - 1.0).abs() < 1e-6 {
            UnitQuaternion::new_unchecked(q)
        } else {
            UnitQuaternion::from_quaternion(q)
        };
        let child = Isometry3::from_parts(
            Translation3::new(position[0], position[1], position[2]),
            rotation,
        );
        let pose = child * self.settings.body_from_child.inverse();
        let time_secs = self.secs(stamp_ns);
        let previous = self.last_pose.replace(pose);
        if let Some(previous) = previous
            && self.is_jump(&previous, &pose, &interval, position_variances)
        {
            self.counts.jumps += 1;
            self.target = Some(TargetInterval::open(time_secs, Some(pose)));
            return PoseOutcome::Jump;
        }
        let Some(target) = self.target.as_mut() else {
            self.target = Some(TargetInterval::open(time_secs, Some(pose)));
            return PoseOutcome::Pose(None);
        };
        target.add(
            &interval.raw_relative,
            interval.mean_inputs.as_deref(),
            interval.duration_secs,
        );
        let limits = self.settings.targets;
        if !target.is_ready(time_secs, &limits) {
            return PoseOutcome::Pose(Some(NoTarget::TooShort));
        }
        let closed = if self.inputs_later {
            target.close_without_inputs(time_secs, Some(&pose), &limits)
        } else {
            target.close(time_secs, Some(&pose), &limits)
        };
        self.target = Some(TargetInterval::open(time_secs, Some(pose)));
        match closed {
            Ok(t) => {
                self.counts.targets += 1;
                PoseOutcome::Target(t)
            }
            Err(why) => PoseOutcome::Pose(Some(why)),
        }
    }

    /// Whether `pose` after `previous` is a jump against the motion
    /// model's odometry over `interval`: a reset to the origin, or a
    /// displacement off the odometry's beyond the settings.
    fn is_jump(
        &self,
        previous: &Isometry3<f64>,
        pose: &Isometry3<f64>,
        interval: &OdometryInterval,
        vo_variances: [f64; 3],
    ) -> bool {
        let to_origin = pose.translation.vector == Vector3::zeros()
            && pose.rotation.angle() == 0.0
            && previous.translation.vector != Vector3::zeros();
        let visual = previous.inverse() * pose;
        let off = (visual.translation.vector - interval.relative.translation.vector).norm();
        let odometry_var = interval.covariance.fixed_view::<3, 3>(3, 3).trace();
        let variance = odometry_var + vo_variances.iter().map(|v| v.max(0.0)).sum::<f64>();
        let j = &self.settings.jump;
        to_origin || (off > j.min_jump_m && off > j.max_sigmas * variance.sqrt())
    }

    /// What the gate counted.
    pub fn counts(&self) -> GateCounts {
        self.counts
    }

    /// The residual prediction in force.
    pub fn prediction(&self) -> &ResidualPrediction {
        self.state.prediction()
    }

    /// The caller attributes the targets' inputs (the window clock of
    /// [`session::GateSession`]): targets are formed without them.
    pub(crate) fn attribute_inputs_later(&mut self) {
        self.inputs_later = true;
    }

    /// Times count from the stamp `origin_ns` (the node's clock: that of
    /// the odometry it is driven with); from 0 unless set.
    pub fn set_origin_ns(&mut self, origin_ns: i64) {
        self.origin_ns = origin_ns;
    }

    /// A stamp's time on the gate's clock (s).
    pub fn secs(&self, stamp_ns: i64) -> f64 {
        (stamp_ns - self.origin_ns) as f64 * 1e-9
    }

    /// How the gate decides and learns.
    pub fn settings(&self) -> &LiveGateSettings {
        &self.settings
    }

    /// The selector's name.
    pub fn policy(&self) -> &str {
        self.selector.name()
    }
}

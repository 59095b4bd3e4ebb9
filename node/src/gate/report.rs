//! What the gate publishes about itself, as
//! `diagnostic_msgs/DiagnosticStatus` key-values (which `ros2 topic echo`
//! shows without a package): each decision on the decisions topic, and its
//! counts on `/diagnostics`, every fault among them.

use gpodo_datasets::bags::write::DiagnosticStatus;

use super::pairing::PairingFaults;
use super::{GateCounts, GateDecision};
use crate::diagnostics::{OK, WARN};
use crate::learner::LearnerStart;

/// A stamp as ROS writes it: seconds and nanoseconds.
fn stamp(ns: i64) -> String {
    format!(
        "{}.{:09}",
        ns.div_euclid(1_000_000_000),
        ns.rem_euclid(1_000_000_000)
    )
}

/// One decision: the pair's stamp, processed or skipped, why, the
/// keyframe-threshold scale the policy asked for (which an external SLAM
/// is not given), and whether the VO was lost.
pub fn decision_status(decision: &GateDecision) -> DiagnosticStatus {
    let processed = if decision.processed {
        "processed"
    } else {
        "skipped"
    };
    DiagnosticStatus {
        level: OK,
        name: "gpodo gate: decision".into(),
        message: processed.into(),
        hardware_id: String::new(),
        values: vec![
            ("stamp".into(), stamp(decision.stamp_ns)),
            ("decision".into(), processed.into()),
            ("reason".into(), decision.reason.clone()),
            (
                "keyframe threshold scale".into(),
                decision
                    .keyframe_threshold_scale
                    .map_or_else(String::new, |s| format!("{s}")),
            ),
            (
                "tracking".into(),
                decision
                    .tracking_lost
                    .map_or_else(|| "ok".to_string(), |r| format!("lost: {}", r.as_str())),
            ),
        ],
    }
}

/// What the learner has done, for the gate's status.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LearnerReport {
    /// Where it started.
    pub start: LearnerStart,
    /// Targets learned (with a resumed checkpoint's).
    pub targets_learned: u64,
    /// Checkpoints written.
    pub checkpoints: u64,
}

/// The gate's counts since it started: a warning while any fault has been
/// seen (a pair with a half missing, messages out of order, a camera info
/// that does not match its image, poses for no pair, jumps).
pub fn gate_status(
    policy: &str,
    counts: &GateCounts,
    faults: &PairingFaults,
    learner: Option<&LearnerReport>,
) -> DiagnosticStatus {
    let mut warnings = Vec::new();
    let mut warn = |n: u64, what: &str| {
        if n > 0 {
            warnings.push(format!("{n} {what}"));
        }
    };
    warn(faults.unpaired_images, "images without their pair");
    warn(faults.unpaired_infos, "camera infos without their image");
    warn(faults.out_of_order, "messages out of order");
    warn(
        faults.info_mismatch,
        "camera infos not matching their image",
    );
    warn(counts.unexpected_poses, "VO poses for no forwarded pair");
    warn(counts.jumps, "VO jumps (not learned from)");
    let mut values = vec![
        ("policy".to_string(), policy.to_string()),
        ("pairs decided".into(), counts.decided.to_string()),
        ("pairs forwarded".into(), counts.forwarded.to_string()),
        (
            "pairs the VO did not answer".into(),
            counts.unanswered.to_string(),
        ),
        ("VO poses saying lost".into(), counts.lost_poses.to_string()),
        ("VO jumps".into(), counts.jumps.to_string()),
        (
            "VO poses for no pair".into(),
            counts.unexpected_poses.to_string(),
        ),
        ("targets formed".into(), counts.targets.to_string()),
        (
            "images without pair".into(),
            faults.unpaired_images.to_string(),
        ),
        (
            "infos without image".into(),
            faults.unpaired_infos.to_string(),
        ),
        (
            "messages out of order".into(),
            faults.out_of_order.to_string(),
        ),
        (
            "infos not matching".into(),
            faults.info_mismatch.to_string(),
        ),
    ];
    if let Some(l) = learner {
        let start = match l.start {
            LearnerStart::Empty => "empty".to_string(),
            LearnerStart::SavedModel => "saved model".to_string(),
            LearnerStart::Checkpoint(n) => format!("checkpoint ({n} targets)"),
        };
        values.push(("learner started from".into(), start));
        values.push(("targets learned".into(), l.targets_learned.to_string()));
        values.push(("checkpoints written".into(), l.checkpoints.to_string()));
    }
    DiagnosticStatus {
        level: if warnings.is_empty() { OK } else { WARN },
        name: "gpodo gate".into(),
        message: if warnings.is_empty() {
            "ok".into()
        } else {
            warnings.join("; ")
        },
        hardware_id: String::new(),
        values,
    }
}

#[cfg(test)]
mod tests {
    use super::super::lost::LostReason;
    use super::*;

    #[test]
    fn a_decision_reads_as_ros_writes_stamps() {
        let d = GateDecision {
            stamp_ns: 12_000_000_345,
            processed: true,
            reason: "while_lost[uncertainty_budget] (tracking lost: vo null pose)".into(),
            keyframe_threshold_scale: Some(0.5),
            tracking_lost: Some(LostReason::NullPose),
        };
        let s = decision_status(&d);
        let value = |k: &str| {
            s.values
                .iter()
                .find(|(key, _)| key == k)
                .map(|(_, v)| v.clone())
        };
        assert_eq!(value("stamp").as_deref(), Some("12.000000345"));
        assert_eq!(value("decision").as_deref(), Some("processed"));
        assert_eq!(value("keyframe threshold scale").as_deref(), Some("0.5"));
        assert_eq!(value("tracking").as_deref(), Some("lost: vo null pose"));
    }

    #[test]
    fn faults_make_a_warning_that_names_them() {
        let counts = GateCounts {
            decided: 10,
            forwarded: 4,
            ..GateCounts::default()
        };
        let clean = gate_status("fixed_rate", &counts, &PairingFaults::default(), None);
        assert_eq!((clean.level, clean.message.as_str()), (OK, "ok"));
        let faults = PairingFaults {
            unpaired_images: 2,
            info_mismatch: 1,
            ..PairingFaults::default()
        };
        let learner = LearnerReport {
            start: LearnerStart::Checkpoint(120),
            targets_learned: 130,
            checkpoints: 3,
        };
        let s = gate_status("fixed_rate", &counts, &faults, Some(&learner));
        assert_eq!(s.level, WARN);
        assert_eq!(
            s.message,
            "2 images without their pair; 1 camera infos not matching their image"
        );
        assert!(s.values.contains(&(
            "learner started from".into(),
            "checkpoint (120 targets)".into()
        )));
    }
}

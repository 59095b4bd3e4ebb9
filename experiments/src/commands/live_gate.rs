//! `gpodo live --gate FILE`: the gate file made into the node's gate
//! session, with its learner on a worker thread (on ROS 2) or in
//! lock-step (in a replay), checkpointed to the `--checkpoint` flag's
//! path, else the file's; and, in a replay, the VO in the loop answered
//! from the recording's own VO topic.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use gpodo_datasets::bags::messages::{Odometry, RosMessage, Twist};
use gpodo_node::gate::GateDecision;
use gpodo_node::gate::pairing::Part;
use gpodo_node::gate::session::{GateSession, LearnerEnd, Learning, PredictionClock};
use gpodo_node::learner::LearnerStart;
use gpodo_node::learner_worker::{CheckpointPolicy, LearnerWorker};

use crate::config::gate::{GateFile, Predictions};

/// Where the learner runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Learner {
    /// On a worker thread (live).
    Worker,
    /// In lock-step with the messages (replay).
    LockStep,
}

/// An image topic silent this long while the other goes on is a fault
/// (s): six frames of a 2.5 fps camera.
const IMAGE_SILENT_SECS: f64 = 2.4;

/// The gate file, and the session it made.
pub struct LiveGateRun<T> {
    /// The gate file.
    pub file: GateFile,
    /// The gate, its pairing and its learner.
    pub session: GateSession<T>,
    /// Where the learner's checkpoint is written.
    pub checkpoint: Option<PathBuf>,
}

impl<T> LiveGateRun<T> {
    /// Builds the gate file at `path` for the model `model` (loaded from
    /// `model_path`) on the rover described at `rover_path`, its learner
    /// run as `learner` says and checkpointed to `checkpoint`, else to the
    /// file's path.
    ///
    /// # Errors
    /// A gate file, rover or model that cannot be read or used, named; a
    /// checkpoint that does not match; an online learner beside a model of
    /// |residual|.
    pub fn build(
        path: &Path,
        rover_path: &Path,
        model_path: &Path,
        checkpoint: Option<&Path>,
        model: &gpodo_node::LiveModel,
        learner: Learner,
    ) -> anyhow::Result<Self> {
        let file = crate::plan::gate::load_gate(path)?;
        let rover =
            std::fs::read(rover_path).with_context(|| format!("{}", rover_path.display()))?;
        let saved = gpodo_regressors::model_file::ModelFile::load(model_path)
            .map_err(|e| anyhow::anyhow!("{}: {e}", model_path.display()))?;
        let checkpoint = checkpoint.map(Path::to_path_buf).or_else(|| {
            file.checkpoint
                .path
                .as_ref()
                .map(|p| path.parent().map_or_else(|| p.clone(), |dir| dir.join(p)))
        });
        let built = crate::commands::gate::build_gate(
            &file,
            &rover,
            Some(&saved),
            checkpoint.as_deref(),
            model.columns(),
        )
        .with_context(|| format!("the gate file {}", path.display()))?;
        if built.learner.is_some() && model.mode() == gpodo_node::OdometryMode::Authors {
            anyhow::bail!(
                "{}: the model predicts |residual| (the authors' mode), which an online learner of the residual cannot replace; give a model of the residual",
                model_path.display()
            );
        }
        let learning = built.learner.map(|l| {
            match l.start() {
                LearnerStart::Checkpoint(n) => tracing::info!(
                    "the learner resumes its checkpoint {} ({n} targets learned)",
                    checkpoint
                        .as_deref()
                        .map_or(String::new(), |p| p.display().to_string())
                ),
                LearnerStart::SavedModel => {
                    tracing::info!("the learner goes on from {}", model_path.display());
                }
                LearnerStart::Empty => tracing::info!(
                    "the learner starts empty: /odom/gp carries its prior variance until it learns"
                ),
            }
            match learner {
                Learner::Worker => {
                    let policy = checkpoint.clone().map(|p| CheckpointPolicy {
                        path: p,
                        every_secs: file.checkpoint.every_secs,
                    });
                    Learning::Worker(LearnerWorker::spawn(l, policy))
                }
                Learner::LockStep => Learning::LockStep(Box::new(l)),
            }
        });
        let clock = match (file.predictions, model.window_secs()) {
            (Some(Predictions::EverySample), _) | (None, None) => PredictionClock::Sample,
            (Some(Predictions::Windows) | None, Some(window_secs)) => {
                PredictionClock::Windows { window_secs }
            }
            (Some(Predictions::Windows), None) => anyhow::bail!(
                "{}: `predictions: windows` needs rows averaged over a window; {} has one row per sample",
                path.display(),
                model_path.display()
            ),
        };
        let session = GateSession::new(
            built.gate,
            built.pairing,
            learning,
            model.columns(),
            clock,
            IMAGE_SILENT_SECS,
        )
        .with_context(|| format!("the gate file {}", path.display()))?
        .with_child_frame_id(file.vo_child_frame_id.clone());
        tracing::info!(
            "gating {} and {} onto {} and {}; decisions on {}",
            file.topics.left_image,
            file.topics.right_image,
            file.topics.gated(Part::LeftImage),
            file.topics.gated(Part::RightImage),
            file.topics.decisions,
        );
        Ok(Self {
            file,
            session,
            checkpoint,
        })
    }

    /// Stops the learner (a worker writes its last checkpoint; a lock-step
    /// learner is written here) and says what it did.
    pub fn finish(self) {
        let counts = self.session.counts();
        println!(
            "gate: {} targets formed, {} VO jumps not learned from, {} poses saying lost",
            counts.targets, counts.jumps, counts.lost_poses
        );
        let to = self
            .checkpoint
            .as_deref()
            .map_or(String::new(), |p| format!(" to {}", p.display()));
        match self.session.finish() {
            LearnerEnd::Worker(Some(summary)) => {
                println!(
                    "learner: {} targets learned, {} checkpoints written{to}",
                    summary.learner.targets_learned(),
                    summary.checkpoints,
                );
                if let Some(e) = summary.last_error {
                    tracing::warn!("the learner's last error: {e}");
                }
            }
            LearnerEnd::Worker(None) => {
                tracing::error!(
                    "the learner's thread failed; its last checkpoint is what was saved"
                );
            }
            LearnerEnd::LockStep(learner) => {
                let written = match &self.checkpoint {
                    Some(path) => match learner.checkpoint(path) {
                        Ok(w) => w,
                        Err(e) => {
                            tracing::error!("the learner's checkpoint: {e}");
                            false
                        }
                    },
                    None => false,
                };
                println!(
                    "learner: {} targets learned{}",
                    learner.targets_learned(),
                    if written {
                        format!(", written{to}")
                    } else {
                        String::new()
                    }
                );
            }
            LearnerEnd::None => {}
        }
    }
}

/// The recording's VO on `topic`, by stamp: what a replay's VO in the
/// loop answers a forwarded pair with (none at a stamp: the VO gave
/// nothing for that pair). `nav_msgs/Odometry` is taken as it is; a
/// `geometry_msgs/PoseStamped` (as ORB-SLAM3's wrappers publish) as an
/// odometry of that pose with no covariance.
///
/// # Errors
/// A bag without the topic, or with another type on it.
pub fn recorded_vo(bag: &Path, topic: &str) -> anyhow::Result<BTreeMap<i64, Odometry>> {
    let messages = gpodo_datasets::bags::topic::read_topic(
        bag,
        topic,
        "the VO",
        &["nav_msgs/Odometry", "geometry_msgs/PoseStamped"],
    )
    .with_context(|| {
        format!(
            "{}: a gated replay answers each forwarded pair with the recording's VO on `{topic}` (the gate file's `topics.vo_odometry`)",
            bag.display()
        )
    })?;
    Ok(messages
        .into_iter()
        .filter_map(|s| match s.message {
            RosMessage::Odometry(o) => Some((o.header.stamp_ns, o)),
            RosMessage::PoseStamped(header, pose) => Some((
                header.stamp_ns,
                Odometry {
                    header,
                    child_frame_id: String::new(),
                    pose,
                    pose_covariance: vec![0.0; 36],
                    twist: Twist {
                        linear: [0.0; 3],
                        angular: [0.0; 3],
                    },
                    twist_covariance: vec![0.0; 36],
                },
            )),
            _ => None,
        })
        .collect())
}

/// Every decision as CSV: the pair's stamp (ns), processed or skipped,
/// the reason, the keyframe-threshold scale asked for, the tracking state.
pub fn decisions_csv(decisions: &[GateDecision]) -> String {
    let mut csv = String::from("stamp_ns,decision,reason,keyframe_threshold_scale,tracking\n");
    for d in decisions {
        let _ = writeln!(
            csv,
            "{},{},\"{}\",{},{}",
            d.stamp_ns,
            if d.processed { "processed" } else { "skipped" },
            d.reason.replace('"', "\"\""),
            d.keyframe_threshold_scale
                .map_or_else(String::new, |s| s.to_string()),
            d.tracking_lost.map_or("ok", |r| r.as_str()),
        );
    }
    csv
}

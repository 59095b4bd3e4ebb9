//! A gate file made into the node's objects: the live gate with its
//! selector (built as the offline schemes build theirs), the pairing, and
//! the online learner, started from a checkpoint, from a saved model of an
//! online kind, or empty.

use std::path::Path;

use anyhow::Context as _;
use gpodo_frontends::gate::GateState;
use gpodo_frontends::odometry_mode::OdometryMode;
use gpodo_frontends::params::FrontendParams;
use gpodo_frontends::scheme::causal_selector;
use gpodo_node::checkpoint::sha256_hex;
use gpodo_node::gate::lost::LostSettings;
use gpodo_node::gate::pairing::PairingSettings;
use gpodo_node::gate::{JumpSettings, LiveGate, LiveGateSettings};
use gpodo_node::learner::{LearnerIdentity, LearnerStart, LiveLearner};
use gpodo_regressors::model_file::ModelFile;
use gpodo_regressors::online_model::OnlineModel;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

use crate::config::gate::GateFile;

/// The node's gate, pairing and learner, as a gate file describes them.
pub struct BuiltGate {
    /// The gate.
    pub gate: LiveGate,
    /// How pairs are matched.
    pub pairing: PairingSettings,
    /// The online learner, when the file has `online:`.
    pub learner: Option<LiveLearner>,
}

/// Builds the gate file `gate` for the rover whose description file holds
/// `rover_description`: a learner resumes the checkpoint at `checkpoint`
/// if one is there, else goes on from `model` if it is of an online kind,
/// else starts empty with `columns` as its inputs.
///
/// # Errors
/// A selector that cannot be built; a checkpoint that cannot be read or
/// does not match (naming the field); a learner that cannot be built.
pub fn build_gate(
    gate: &GateFile,
    rover_description: &[u8],
    model: Option<&ModelFile>,
    checkpoint: Option<&Path>,
    columns: &[String],
) -> anyhow::Result<BuiltGate> {
    let mode = OdometryMode::default();
    let selector = causal_selector(
        &gate.selector.for_odometry(&mode)?,
        gate.lost_frame_period_secs,
        None,
    )?;
    let state = GateState::new(
        FrontendParams::default().odometry,
        mode,
        gate.initial_residual_variance,
    );
    let body_from_child = gate.body_from_child.map_or_else(Isometry3::identity, |p| {
        let [x, y, z, w] = p.rotation_xyzw;
        Isometry3::from_parts(
            Translation3::from(p.translation_m),
            UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
        )
    });
    let settings = LiveGateSettings {
        lost: LostSettings {
            silent_secs: gate.lost.silent_secs,
            covariance_at_least: gate.lost.covariance_at_least,
        },
        targets: gate.targets,
        jump: JumpSettings {
            max_sigmas: gate.jump.max_sigmas,
            min_jump_m: gate.jump.min_jump_m,
        },
        body_from_child,
    };
    let pairing = PairingSettings {
        tolerance_ns: (gate.pairing.tolerance_secs * 1e9).round() as i64,
        history_depth: gate.pairing.history_depth,
    };
    let learner = match &gate.online {
        None => None,
        Some(online) => {
            let online_mode = online
                .mode()
                .map_err(|(field, expected)| anyhow::anyhow!("`{field}`: expected {expected}"))?;
            let rover_sha256 = sha256_hex(rover_description);
            let saved = model.filter(|m| OnlineModel::from_state(&m.state).is_ok());
            let (identity, kind) = match saved {
                Some(m) => (
                    LearnerIdentity {
                        label: m.label.clone(),
                        input_names: m.input_names.clone(),
                        input_standardizer: m.input_standardizer.clone(),
                        rows: m.rows.clone(),
                        rover_sha256: rover_sha256.clone(),
                    },
                    OnlineModel::from_state(&m.state)?.kind(),
                ),
                None => (
                    LearnerIdentity {
                        label: format!("online: {}", online.regressor.label()),
                        input_names: columns.to_vec(),
                        input_standardizer: None,
                        rows: model.and_then(|m| m.rows.clone()),
                        rover_sha256: rover_sha256.clone(),
                    },
                    OnlineModel::from_spec(&online.regressor)?.kind(),
                ),
            };
            let variance = gate.initial_residual_variance;
            Some(match (checkpoint.filter(|p| p.exists()), saved) {
                (Some(path), _) => LiveLearner::resume(path, online_mode, variance, identity, kind)
                    .context("the learner's checkpoint")?,
                (None, Some(file)) => {
                    LiveLearner::from_saved_model(file, online_mode, variance, rover_sha256)?
                }
                (None, None) => LiveLearner::new(
                    OnlineModel::from_spec(&online.regressor)?,
                    online_mode,
                    variance,
                    identity,
                    LearnerStart::Empty,
                )?,
            })
        }
    };
    Ok(BuiltGate {
        gate: LiveGate::new(selector, state, settings),
        pairing,
        learner,
    })
}

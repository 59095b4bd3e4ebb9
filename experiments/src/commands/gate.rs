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
use gpodo_node::gate::{LiveGate, LiveGateSettings};
use gpodo_node::learner::{LearnerIdentity, LearnerStart, LiveLearner};
use gpodo_regressors::RegressorSpec;
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
        jump: gate.jump,
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
            // A saved model of an online kind is what the learner goes on
            // from; otherwise it starts from the file's spec.
            let saved = model.and_then(|m| OnlineModel::kind_of(&m.state).map(|kind| (m, kind)));
            let variance = gate.initial_residual_variance;
            Some(match (checkpoint.filter(|p| p.exists()), saved) {
                (Some(path), Some((m, kind))) => {
                    let identity = LearnerIdentity::of_saved_model(m, rover_sha256);
                    LiveLearner::resume(path, online_mode, variance, identity, kind)
                        .context("the learner's checkpoint")?
                }
                (Some(path), None) => {
                    let kind = OnlineModel::from_spec(&online.regressor)?.kind();
                    let identity = empty_identity(&online.regressor, columns, model, rover_sha256);
                    LiveLearner::resume(path, online_mode, variance, identity, kind)
                        .context("the learner's checkpoint")?
                }
                (None, Some((m, _))) => {
                    LiveLearner::from_saved_model(m, online_mode, variance, rover_sha256)?
                }
                (None, None) => LiveLearner::new(
                    OnlineModel::from_spec(&online.regressor)?,
                    online_mode,
                    variance,
                    empty_identity(&online.regressor, columns, model, rover_sha256),
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

/// The identity of a learner of `spec` starting empty on `columns`, with
/// the row recipe of `model` if one was given, and its input scaling when
/// it reads the same columns (as the offline schemes' online learners
/// learn on the trained model's standardised inputs).
fn empty_identity(
    spec: &RegressorSpec,
    columns: &[String],
    model: Option<&ModelFile>,
    rover_sha256: String,
) -> LearnerIdentity {
    LearnerIdentity {
        label: format!("online: {}", spec.label()),
        input_names: columns.to_vec(),
        input_standardizer: model
            .filter(|m| m.input_names == columns)
            .and_then(|m| m.input_standardizer.clone()),
        rows: model.and_then(|m| m.rows.clone()),
        rover_sha256,
    }
}

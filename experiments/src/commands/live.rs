//! `gpodo live`: a saved model run as on the robot, from a recording
//! (`--replay`) or on ROS 2 (a build with the `ros2` feature); with
//! `--gate`, the frame gate and its online learner too
//! ([`crate::commands::live_gate`]).

use std::path::{Path, PathBuf};

use anyhow::Context as _;

use crate::commands::live_gate::{Learner, LiveGateRun};
use crate::commands::replay_frontend::{FrontEndVo, RecordedTraverse, ReplayFrontEnd};

/// What `gpodo live` was asked.
#[derive(Debug, Clone, Default)]
pub struct LiveOptions {
    /// The model file.
    pub model: PathBuf,
    /// The rover description.
    pub rover: PathBuf,
    /// The topic map.
    pub topics: PathBuf,
    /// A recording to replay instead of subscribing.
    pub replay: Option<PathBuf>,
    /// Where a replay writes its odometry (MCAP).
    pub out: Option<PathBuf>,
    /// Where a replay writes its input rows (CSV).
    pub rows: Option<PathBuf>,
    /// Replay at the recorded speed rather than as fast as it can.
    pub realtime: bool,
    /// The DDS domain (default `$ROS_DOMAIN_ID`, else 0).
    pub domain_id: Option<u16>,
    /// On ROS 2, stop after this many outputs.
    pub max_outputs: Option<usize>,
    /// On ROS 2, stop after this many seconds without input.
    pub idle_exit_secs: Option<f64>,
    /// On ROS 2, the network interfaces DDS uses (empty: all).
    pub dds_interfaces: Vec<std::net::IpAddr>,
    /// The gate file: the frame gate and its online learner, on ROS 2 or
    /// in a replay.
    pub gate: Option<PathBuf>,
    /// The learner's checkpoint (overrides the gate file's
    /// `checkpoint.path`).
    pub checkpoint: Option<PathBuf>,
    /// In a gated replay, where every decision is written (CSV).
    pub decisions: Option<PathBuf>,
}

/// Runs `gpodo live`.
///
/// # Errors
/// A model, rover, topic map or recording that cannot be used, named;
/// DDS failing; ROS 2 asked of a build without it.
pub fn live(options: &LiveOptions) -> anyhow::Result<()> {
    let map = crate::commands::import::read_topic_map(&options.topics)?;
    let description = gpodo_kinematics::RoverDescription::from_path(&options.rover)
        .map_err(|e| anyhow::anyhow!("{}: {e}", options.rover.display()))?;
    let mut model = gpodo_node::LiveModel::load(
        &options.model,
        &options.rover,
        map.imu.is_some(),
        false,
        gpodo_node::LiveSettings::default(),
    )?;
    match (&options.replay, &options.out) {
        (Some(bag), Some(out)) => {
            let pace = if options.realtime {
                gpodo_node::replay::Pace::Recorded
            } else {
                gpodo_node::replay::Pace::Fast
            };
            replay(options, bag, out, pace, &map, &description, &mut model)
        }
        (Some(_), None) => anyhow::bail!("`--replay` needs `--out`, the MCAP to write"),
        _ => on_ros2(options, &map, &description, &mut model),
    }
}

fn replay(
    options: &LiveOptions,
    bag: &Path,
    out: &Path,
    pace: gpodo_node::replay::Pace,
    map: &gpodo_datasets::bags::import::TopicMap,
    description: &gpodo_kinematics::RoverDescription,
    model: &mut gpodo_node::LiveModel,
) -> anyhow::Result<()> {
    let rows = options.rows.as_deref();
    let playback = gpodo_node::replay::Playback {
        pace,
        stop: &crate::util::stop::requested,
    };
    let mut gate = match &options.gate {
        Some(path) => Some(LiveGateRun::<(usize, usize)>::build(
            path,
            &options.rover,
            &options.model,
            options.checkpoint.as_deref(),
            model,
            Learner::LockStep,
        )?),
        None => None,
    };
    // The VO behind the gate: the offline schemes' front end on the
    // recording (`replay_frontend:`), else the recording's VO topic.
    let frontend = gate.as_ref().and_then(|g| g.file.replay_frontend.clone());
    let child_frame_id = gate
        .as_ref()
        .and_then(|g| g.file.vo_child_frame_id.clone())
        .unwrap_or_default();
    let traverse = match (&gate, &frontend) {
        (Some(g), Some(f)) => {
            let saved = gpodo_regressors::model_file::ModelFile::load(&options.model)
                .map_err(|e| anyhow::anyhow!("{}: {e}", options.model.display()))?;
            Some(
                RecordedTraverse::load(bag, map, &g.file.topics, &saved, &options.rover, f)
                    .context("the gate file's `replay_frontend`")?,
            )
        }
        _ => None,
    };
    let recorded = match (&gate, &traverse) {
        (Some(g), None) => {
            crate::commands::live_gate::recorded_vo(bag, &g.file.topics.vo_odometry)?
        }
        _ => Default::default(),
    };
    let mut behind = match (&traverse, &frontend) {
        (Some(t), Some(f)) => Some((t.vo(f)?, ReplayFrontEnd::no_model(&t.traverse, f))),
        _ => None,
    };
    let mut front_end =
        match (&traverse, &frontend, behind.as_mut()) {
            (Some(t), Some(f), Some((tracker, no_model))) => Some(
                gpodo_frontends::run::FrontEnd::new(&t.traverse, f, no_model, tracker.as_mut())?,
            ),
            _ => None,
        };
    let mut answers = match (front_end.as_mut(), &traverse) {
        (Some(fe), Some(t)) => Some(FrontEndVo::new(fe, t, &child_frame_id)),
        _ => None,
    };
    let mut vo = |pair: &gpodo_node::replay::RecordedPair<'_>,
                  decision: &gpodo_node::gate::GateDecision| match answers.as_mut()
    {
        Some(a) => a.answer(pair, decision),
        None => recorded.get(&pair.stamp_ns).cloned(),
    };
    let gated = gate.as_mut().map(|g| gpodo_node::replay::GatedReplay {
        topics: &g.file.topics,
        session: &mut g.session,
        vo: &mut vo,
    });
    let summary =
        gpodo_node::replay::replay_gated(bag, map, description, model, out, rows, playback, gated);
    if let Some(g) = gate {
        g.finish();
    }
    let summary = summary?;
    if let Some(a) = answers {
        if let Some(e) = a.error {
            anyhow::bail!("the replay's front end: {e}");
        }
        println!(
            "the front end behind the gate: {} pairs processed, {} of them lost",
            a.processed.len(),
            a.lost
        );
    }
    if let Some(path) = &options.decisions {
        let csv = crate::commands::live_gate::decisions_csv(&summary.decisions);
        std::fs::write(path, csv).with_context(|| format!("{}", path.display()))?;
        let forwarded = summary.decisions.iter().filter(|d| d.processed).count();
        println!(
            "wrote {} ({} pairs decided, {forwarded} forwarded)",
            path.display(),
            summary.decisions.len()
        );
    }
    if summary.stopped {
        println!("stopped before the recording's end; what was replayed is kept");
    }
    for reason in summary.skipped.iter().take(5) {
        tracing::warn!("joint state not used: {reason}");
    }
    if summary.skipped.len() > 5 {
        tracing::warn!("{} more joint states not used", summary.skipped.len() - 5);
    }
    for (input, rows) in &summary.out_of_range {
        tracing::warn!("`{input}` outside the training range in {rows} rows");
    }
    println!(
        "wrote {} ({} odometry messages on each of {}, from {} joint states and {} IMU messages)",
        out.display(),
        summary.outputs,
        gpodo_node::replay::OUTPUT_TOPICS.join(" and "),
        summary.joint_messages,
        summary.imu_messages
    );
    if let Some(rows) = rows {
        println!("wrote {} ({} rows)", rows.display(), summary.rows);
    }
    if let Some((p50, p99)) = summary.latency_secs {
        println!(
            "latency of an output: p50 {:.3} ms, p99 {:.3} ms; the node's work sustains {:.0} joint states a second",
            p50 * 1e3,
            p99 * 1e3,
            summary.outputs as f64 / summary.processing_secs.max(1e-12)
        );
    }
    Ok(())
}

/// The domain: the option, else `$ROS_DOMAIN_ID`, else 0.
fn domain_id(option: Option<u16>) -> anyhow::Result<u16> {
    match (option, std::env::var("ROS_DOMAIN_ID")) {
        (Some(d), _) => Ok(d),
        (None, Ok(v)) if !v.trim().is_empty() => v
            .trim()
            .parse()
            .with_context(|| format!("ROS_DOMAIN_ID={v:?}: expected a domain id (0–232)")),
        _ => Ok(0),
    }
}

#[cfg(feature = "ros2")]
fn on_ros2(
    options: &LiveOptions,
    map: &gpodo_datasets::bags::import::TopicMap,
    description: &gpodo_kinematics::RoverDescription,
    model: &mut gpodo_node::LiveModel,
) -> anyhow::Result<()> {
    use gpodo_node::ros2::{DIAGNOSTICS_TOPIC, Ros2Settings, run};
    let settings = Ros2Settings {
        domain_id: domain_id(options.domain_id)?,
        max_outputs: options.max_outputs,
        idle_exit_secs: options.idle_exit_secs,
        interfaces: options.dds_interfaces.clone(),
        ..Ros2Settings::default()
    };
    let joints = map.joints.as_ref().map_or("", |j| j.topic.as_str());
    tracing::info!(
        "on ROS 2 (DDS domain {}): {} from {joints}{}, publishing {} and {DIAGNOSTICS_TOPIC}",
        settings.domain_id,
        model.summary().label,
        map.imu
            .as_ref()
            .map_or(String::new(), |t| format!(" and {t}")),
        gpodo_node::replay::OUTPUT_TOPICS.join(", "),
    );
    let mut gate = match &options.gate {
        Some(path) => Some(LiveGateRun::build(
            path,
            &options.rover,
            &options.model,
            options.checkpoint.as_deref(),
            model,
            Learner::Worker,
        )?),
        None => None,
    };
    let ros2_gate = gate.as_mut().map(|g| gpodo_node::ros2::Ros2Gate {
        topics: &g.file.topics,
        status_topic: g.file.lost.status_topic.as_deref(),
        session: &mut g.session,
    });
    let summary = run(
        map,
        description,
        model,
        &settings,
        ros2_gate,
        &crate::util::stop::requested,
    );
    // The learner's last checkpoint is written whatever ended the run.
    if let Some(g) = gate {
        if let Some(t) = summary.as_ref().ok().and_then(|s| s.gate) {
            println!(
                "gate: {} pairs decided, {} forwarded ({} before the odometry reached them), {} VO poses",
                t.decided, t.forwarded, t.decided_before_odometry, t.vo_messages
            );
        }
        g.finish();
    }
    let summary = summary?;
    if let Some(reason) = &summary.last_skip {
        tracing::warn!(
            "{} joint states not used; the last: {reason}",
            summary.skipped
        );
    }
    if summary.undecodable > 0 {
        tracing::warn!("{} messages could not be decoded", summary.undecodable);
    }
    let latency = summary.latency_secs.map_or(String::new(), |(p50, p99)| {
        format!("; latency p50 {:.3} ms, p99 {:.3} ms", p50 * 1e3, p99 * 1e3)
    });
    println!(
        "published {} odometry messages on each of {}, from {} joint states and {} IMU messages{latency}",
        summary.outputs,
        gpodo_node::replay::OUTPUT_TOPICS.join(" and "),
        summary.joint_messages,
        summary.imu_messages
    );
    Ok(())
}

#[cfg(not(feature = "ros2"))]
fn on_ros2(
    options: &LiveOptions,
    _map: &gpodo_datasets::bags::import::TopicMap,
    _description: &gpodo_kinematics::RoverDescription,
    _model: &mut gpodo_node::LiveModel,
) -> anyhow::Result<()> {
    domain_id(options.domain_id)?;
    anyhow::bail!(
        "this gpodo was built without ROS 2: give `--replay BAG --out OUT.mcap`, or build it with `cargo build --release --features ros2`"
    )
}

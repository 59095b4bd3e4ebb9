//! A recording fed to the live pipeline as a robot's topics would feed
//! it: every joint-state message drives one output, the IMU's latest
//! message is held, and the outputs go to an MCAP (`/odom/gp`, the
//! published odometry; `/odom/wheel`, the motion model's alone) and, when
//! asked, the input rows to a CSV in the columns `gpodo predict` reads
//! (after a `time_secs` column).

use std::fmt::Write as _;
use std::path::Path;

use gpodo_datasets::bags::OnDamage;
use gpodo_datasets::bags::import::{TimeSource, TopicMap};
use gpodo_datasets::bags::messages::RosMessage;
use gpodo_datasets::bags::topic::{TopicRequest, read_topics};
use gpodo_datasets::bags::write::{OdometryMcap, odometry_message};
use gpodo_kinematics::RoverDescription;

use crate::NodeError;
use crate::diagnostics::percentile;
use crate::feed::LiveFeed;
use crate::pipeline::{LiveModel, LiveOutput};

/// The topics a replay writes, in [`OdometryMcap`] order.
pub const OUTPUT_TOPICS: [&str; 2] = ["/odom/gp", "/odom/wheel"];

/// What a replay did.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplaySummary {
    /// Joint-state messages read.
    pub joint_messages: usize,
    /// IMU messages read.
    pub imu_messages: usize,
    /// Odometry messages written per topic.
    pub outputs: usize,
    /// Rows written (every output but the first of a windowed model).
    pub rows: usize,
    /// Joint-state messages not used, each with its reason.
    pub skipped: Vec<String>,
    /// Per model input, how many rows had it outside the training range.
    pub out_of_range: std::collections::BTreeMap<String, usize>,
    /// The latency of an output, p50 and p99 (s): from a joint-state
    /// message in hand to its two odometry messages encoded, as on the
    /// robot (writing the MCAP not included).
    pub latency_secs: Option<(f64, f64)>,
    /// The node's work summed over the outputs (s): outputs over this is
    /// the highest joint-state rate it sustains on this machine.
    pub processing_secs: f64,
    /// Whether `stop` ended the replay before the recording's end (what was
    /// written up to then is kept, finished as a readable MCAP).
    pub stopped: bool,
}

fn io_error(path: &Path, e: impl std::fmt::Display) -> NodeError {
    NodeError::Model {
        path: path.to_path_buf(),
        detail: e.to_string(),
    }
}

/// How fast a recording is replayed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Pace {
    /// As fast as it can.
    #[default]
    Fast,
    /// At the recorded speed: each message when its stamp says, counted
    /// from the first.
    Recorded,
}

/// How a replay runs: its pace, and what it asks before each message
/// whether to stop there (at recorded speed, also while it waits).
#[derive(Clone, Copy)]
pub struct Playback<'a> {
    /// As fast as it can, or at recorded speed.
    pub pace: Pace,
    /// Whether to stop now (the CLI's Ctrl-C and SIGTERM).
    pub stop: &'a dyn Fn() -> bool,
}

impl Playback<'static> {
    /// At `pace`, to the recording's end.
    pub fn to_the_end(pace: Pace) -> Self {
        fn never() -> bool {
            false
        }
        Self { pace, stop: &never }
    }
}

/// Replays `bag` through `model` on the rover `rover`, reading its topics
/// as `map` says, at `pace`; writes the odometry to `out` and the rows to
/// `rows`, as `playback` says: once its `stop` says so, the replay ends
/// there and finishes what it wrote.
///
/// # Errors
/// A bag, topic map or output that cannot be used, named; a message that
/// cannot be used is skipped and counted instead.
pub fn replay(
    bag: &Path,
    map: &TopicMap,
    rover: &RoverDescription,
    model: &mut LiveModel,
    out: &Path,
    rows: Option<&Path>,
    playback: Playback<'_>,
) -> Result<ReplaySummary, NodeError> {
    let Playback { pace, stop } = playback;
    let joints = map
        .joints
        .as_ref()
        .ok_or_else(|| io_error(bag, "the topic map has no `joints:`, which drive the node"))?;
    let mut requests = vec![TopicRequest {
        topic: &joints.topic,
        role: "joints",
        expected: &["sensor_msgs/JointState"],
        optional: false,
    }];
    if let Some(imu) = &map.imu {
        requests.push(TopicRequest {
            topic: imu,
            role: "imu",
            expected: &["sensor_msgs/Imu"],
            optional: false,
        });
    }
    let (messages, _) =
        read_topics(bag, &requests, OnDamage::Stop).map_err(|e| io_error(bag, e))?;
    // Every message by its time (the IMU first at a tie, so a joint state
    // sees the IMU reading of its own instant).
    let stamp = |s: &gpodo_datasets::bags::topic::Stamped, header_ns: i64| match map.time {
        TimeSource::Header => header_ns,
        TimeSource::Receive => s.log_time_ns as i64,
    };
    let mut order: Vec<(i64, usize, usize)> = Vec::new();
    for (topic, list) in messages.iter().enumerate() {
        for (k, s) in list.iter().enumerate() {
            let header_ns = match &s.message {
                RosMessage::JointState(m) => m.header.stamp_ns,
                RosMessage::Imu(m) => m.header.stamp_ns,
                _ => continue,
            };
            order.push((stamp(s, header_ns), usize::from(topic == 0), k));
            // (IMU messages sort with 0, joint states with 1.)
        }
    }
    order.sort_unstable();
    let mut mcap = OdometryMcap::new(out, &OUTPUT_TOPICS).map_err(|e| io_error(out, e))?;
    let mut csv = String::new();
    if rows.is_some() {
        csv.push_str("time_secs");
        for c in model.columns() {
            csv.push(',');
            csv.push_str(c);
        }
        csv.push('\n');
    }
    let mut summary = ReplaySummary {
        joint_messages: messages[0].len(),
        imu_messages: messages.get(1).map_or(0, Vec::len),
        outputs: 0,
        rows: 0,
        skipped: Vec::new(),
        out_of_range: std::collections::BTreeMap::new(),
        latency_secs: None,
        processing_secs: 0.0,
        stopped: false,
    };
    let mut latencies = Vec::new();
    let mut feed = LiveFeed::new(map, rover, model)?;
    let started = std::time::Instant::now();
    let first_ns = order.first().map_or(0, |o| o.0);
    // The longest sleep between two looks at `stop` at recorded speed.
    const STOP_POLL: std::time::Duration = std::time::Duration::from_millis(20);
    for (ns, is_joint, k) in order {
        if pace == Pace::Recorded {
            let due = std::time::Duration::from_nanos(u64::try_from(ns - first_ns).unwrap_or(0));
            while let Some(wait) = due.checked_sub(started.elapsed()) {
                if stop() {
                    break;
                }
                std::thread::sleep(wait.min(STOP_POLL));
            }
        }
        if stop() {
            summary.stopped = true;
            break;
        }
        let stamped = &messages[1 - is_joint][k];
        let receive_ns = stamped.log_time_ns as i64;
        match &stamped.message {
            RosMessage::Imu(m) if is_joint == 0 => feed.imu(m, receive_ns),
            RosMessage::JointState(m) if is_joint == 1 => {
                let taken = std::time::Instant::now();
                let fed = match feed.joints(m, receive_ns) {
                    Ok(f) => f,
                    Err(reason) => {
                        summary.skipped.push(reason);
                        continue;
                    }
                };
                let output = &fed.output;
                let stamp = u64::try_from(fed.stamp_ns).unwrap_or(0);
                let [gp, wheel] = output_messages(stamp, output);
                latencies.push(taken.elapsed().as_secs_f64());
                mcap.write(0, stamp, &gp)
                    .and_then(|()| mcap.write(1, stamp, &wheel))
                    .map_err(|e| io_error(out, e))?;
                summary.outputs += 1;
                for name in &output.out_of_range {
                    *summary.out_of_range.entry(name.clone()).or_default() += 1;
                }
                if let (Some(_), Some(row)) = (rows, &output.row) {
                    let _ = write!(csv, "{}", output.time_secs);
                    for v in row {
                        let _ = write!(csv, ",{v}");
                    }
                    csv.push('\n');
                    summary.rows += 1;
                }
            }
            _ => {}
        }
    }
    summary.latency_secs = percentile(&latencies, 50.0).zip(percentile(&latencies, 99.0));
    summary.processing_secs = latencies.iter().sum();
    mcap.finish().map_err(|e| io_error(out, e))?;
    if let Some(path) = rows {
        let tmp = path.with_extension("csv.partial");
        std::fs::write(&tmp, csv)
            .and_then(|()| std::fs::rename(&tmp, path))
            .map_err(|e| io_error(path, e))?;
    }
    Ok(summary)
}

/// The CDR of the two odometry messages of one output, stamped
/// ``stamp`, in [`OUTPUT_TOPICS`] order: the published twist with its
/// variances, and the motion model's alone (its covariance left zero:
/// it is for comparison, not for fusion).
pub fn output_messages(stamp: u64, o: &LiveOutput) -> [Vec<u8>; 2] {
    let mut twist_covariance = [0.0; 36];
    for (i, v) in o.variance.iter().enumerate() {
        twist_covariance[i * 7] = *v;
    }
    let gp = odometry_message(
        stamp,
        "odom",
        "base_link",
        &o.pose,
        &o.pose_covariance,
        &o.twist,
        &twist_covariance,
    );
    let wheel = odometry_message(
        stamp,
        "odom",
        "base_link",
        &o.uncorrected_pose,
        &[0.0; 36],
        &o.uncorrected,
        &[0.0; 36],
    );
    [gp, wheel]
}

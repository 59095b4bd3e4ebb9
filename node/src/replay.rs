//! A recording fed to the live pipeline as a robot's topics would feed
//! it: every joint-state message drives one output, the IMU's latest
//! message is held, and the outputs go to an MCAP (`/odom/gp`, the
//! published odometry; `/odom/wheel`, the motion model's alone) and, when
//! asked, the input rows to a CSV in the columns `gpodo predict` reads
//! (after a `time_secs` column). With the frame gate ([`replay_gated`]),
//! the recording's stereo pairs are decided as on the robot, and those
//! forwarded go to a VO in the loop whose poses the learner learns from.

use std::fmt::Write as _;
use std::path::Path;

use gpodo_datasets::bags::OnDamage;
use gpodo_datasets::bags::import::{TimeSource, TopicMap};
use gpodo_datasets::bags::messages::{Odometry, RosMessage};
use gpodo_datasets::bags::topic::{TopicRequest, read_topics};
use gpodo_datasets::bags::write::{OdometryMcap, odometry_message};
use gpodo_kinematics::RoverDescription;

use crate::NodeError;
use crate::diagnostics::percentile;
use crate::feed::LiveFeed;
use crate::gate::GateDecision;
use crate::gate::pairing::{Part, PartHeader, StereoPair};
use crate::gate::session::GateSession;
use crate::gate::topics::GateTopics;
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
    /// With a gate: its decision on every pair, in order.
    pub decisions: Vec<GateDecision>,
}

/// A stereo pair of a recording, as the gate forwards it to a VO in the
/// loop: the four messages, decoded.
pub type RecordedPair<'a> = StereoPair<&'a RosMessage>;

/// The VO behind the gate in a replay: the odometry it publishes for a
/// forwarded pair (given with the gate's decision on it, whose
/// keyframe-threshold scale a VO of gpodo's can apply), or none (it gave
/// nothing: lost, or not yet started).
pub type ReplayVo<'a> = dyn FnMut(&RecordedPair<'_>, &GateDecision) -> Option<Odometry> + 'a;

/// The gate in a replay: its topics, its session (the learner in
/// lock-step), and the VO it forwards pairs to, in the loop: the VO's
/// answer to a pair is taken before the next message.
pub struct GatedReplay<'g, 'a> {
    /// The camera's and the VO's topics.
    pub topics: &'g GateTopics,
    /// The gate, pairing and learner; its pairs name messages by their
    /// topic and index.
    pub session: &'g mut GateSession<(usize, usize)>,
    /// The VO.
    pub vo: &'g mut ReplayVo<'a>,
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
    replay_gated(bag, map, rover, model, out, rows, playback, None)
}

/// [`replay`] with the frame gate in front of a VO in the loop, when
/// `gate` is given: each stereo pair is decided once a joint state
/// stamped at or after it has been run (as on DDS), on the odometry
/// driven up to its stamp; a forwarded pair goes to the VO, whose
/// odometry is learned from before the next message; with a learner, its
/// residual is the one published.
///
/// # Errors
/// As [`replay`]; a bag without the gate's camera topics.
#[allow(clippy::too_many_arguments)]
pub fn replay_gated(
    bag: &Path,
    map: &TopicMap,
    rover: &RoverDescription,
    model: &mut LiveModel,
    out: &Path,
    rows: Option<&Path>,
    playback: Playback<'_>,
    mut gate: Option<GatedReplay<'_, '_>>,
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
    // The camera's four topics follow, in `Part::ALL`'s order.
    let first_camera = requests.len();
    if let Some(g) = &gate {
        for part in Part::ALL {
            requests.push(TopicRequest {
                topic: g.topics.input(part),
                role: "the gate's camera",
                expected: if part.is_image() {
                    &["sensor_msgs/Image"]
                } else {
                    &["sensor_msgs/CameraInfo"]
                },
                optional: false,
            });
        }
    }
    let (messages, _) =
        read_topics(bag, &requests, OnDamage::Stop).map_err(|e| io_error(bag, e))?;
    // Every message by its time (the IMU first at a tie, so a joint state
    // sees the IMU reading of its own instant).
    let stamp = |s: &gpodo_datasets::bags::topic::Stamped, header_ns: i64| match map.time {
        TimeSource::Header => header_ns,
        TimeSource::Receive => s.log_time_ns as i64,
    };
    // Per topic, its rank at a tie: the IMU 0, joint states 1, the
    // camera's 2 (a pair is decided after the joint state of its instant).
    let rank = |topic: usize| match topic {
        0 => 1,
        t if t >= first_camera => 2,
        _ => 0,
    };
    let mut order: Vec<(i64, usize, usize, usize)> = Vec::new();
    for (topic, list) in messages.iter().enumerate() {
        for (k, s) in list.iter().enumerate() {
            let header_ns = match &s.message {
                RosMessage::JointState(m) => m.header.stamp_ns,
                RosMessage::Imu(m) => m.header.stamp_ns,
                RosMessage::Image(m) => m.header.stamp_ns,
                RosMessage::CameraInfo(m) => m.header.stamp_ns,
                _ => continue,
            };
            order.push((stamp(s, header_ns), rank(topic), topic, k));
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
        decisions: Vec::new(),
    };
    let mut latencies = Vec::new();
    let mut feed = LiveFeed::new(map, rover, model)?;
    // Pairs waiting for a joint state stamped at or after them, with when
    // they were completed (the recording's clock, s).
    let mut waiting: std::collections::VecDeque<(StereoPair<(usize, usize)>, f64)> =
        std::collections::VecDeque::new();
    let started = std::time::Instant::now();
    let first_ns = order.first().map_or(0, |o| o.0);
    // The longest sleep between two looks at `stop` at recorded speed.
    const STOP_POLL: std::time::Duration = std::time::Duration::from_millis(20);
    for (ns, _, topic, k) in order {
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
        let stamped = &messages[topic][k];
        let receive_ns = stamped.log_time_ns as i64;
        if topic >= first_camera {
            if let Some(g) = gate.as_mut() {
                let part = Part::ALL[topic - first_camera];
                waiting.extend(gated_part(g, &messages, part, (topic, k), ns));
            }
            continue;
        }
        match &stamped.message {
            RosMessage::Imu(m) if topic != 0 => feed.imu(m, receive_ns),
            RosMessage::JointState(m) if topic == 0 => {
                let taken = std::time::Instant::now();
                let residual = gate.as_ref().and_then(|g| g.session.residual());
                let fed = match feed.joints_with(m, receive_ns, residual) {
                    Ok(f) => f,
                    Err(reason) => {
                        summary.skipped.push(reason);
                        continue;
                    }
                };
                if let Some(g) = gate.as_mut() {
                    if let Err(e) = g.session.output(&fed.output, fed.stamp_ns) {
                        summary.skipped.push(format!("the gate: {e}"));
                    }
                    // The pairs the odometry has now reached.
                    while waiting
                        .front()
                        .is_some_and(|p| p.0.stamp_ns <= fed.stamp_ns)
                    {
                        if let Some((pair, now_secs)) = waiting.pop_front() {
                            summary
                                .decisions
                                .push(decide_pair(g, &messages, pair, now_secs));
                        }
                    }
                }
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
    // Pairs after the last joint state, decided on the odometry there is.
    if let Some(g) = gate.as_mut() {
        for (pair, now_secs) in waiting {
            summary
                .decisions
                .push(decide_pair(g, &messages, pair, now_secs));
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

/// One camera message of a gated replay, at `ns` on the recording's
/// clock: paired; the pair it completes, with the time it was completed.
fn gated_part(
    g: &mut GatedReplay<'_, '_>,
    messages: &[Vec<gpodo_datasets::bags::topic::Stamped>],
    part: Part,
    at: (usize, usize),
    ns: i64,
) -> Option<(StereoPair<(usize, usize)>, f64)> {
    let now_secs = ns as f64 * 1e-9;
    // Pairs are matched by header stamps, as on DDS, whatever the clock.
    let header = match &messages[at.0][at.1].message {
        RosMessage::Image(m) => PartHeader {
            stamp_ns: m.header.stamp_ns,
            width: m.width,
            height: m.height,
        },
        RosMessage::CameraInfo(m) => PartHeader {
            stamp_ns: m.header.stamp_ns,
            width: m.width,
            height: m.height,
        },
        _ => return None,
    };
    g.session.watch(now_secs);
    let pair = g.session.part(part, header, at, now_secs)?;
    Some((pair, now_secs))
}

/// Decides `pair` (completed at `now_secs`); a forwarded pair goes to the
/// VO, whose answer the session takes at once.
fn decide_pair(
    g: &mut GatedReplay<'_, '_>,
    messages: &[Vec<gpodo_datasets::bags::topic::Stamped>],
    pair: StereoPair<(usize, usize)>,
    now_secs: f64,
) -> GateDecision {
    let (decision, forwarded) = g.session.decide(pair, now_secs);
    if let Some(pair) = forwarded {
        let message = |(topic, k): (usize, usize)| &messages[topic][k].message;
        let recorded = StereoPair {
            stamp_ns: pair.stamp_ns,
            left: message(pair.left),
            right: message(pair.right),
            left_info: message(pair.left_info),
            right_info: message(pair.right_info),
        };
        if let Some(odometry) = (g.vo)(&recorded, &decision) {
            g.session.vo_odometry(&odometry);
        }
    }
    decision
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

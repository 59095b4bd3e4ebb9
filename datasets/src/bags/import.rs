//! A recording turned into the rover-log CSV that `dataset: {kind: logs}`
//! reads (`gpodo import`): each role's topic read and checked
//! (in one pass, [`read_topics`]), every stream put on one clock at `rate_hz` by linear
//! interpolation (quaternions normalised after aligning their signs), and
//! never across a gap longer than `max_gap_secs`: rows that would need it
//! are dropped and counted, as are duplicated and out-of-order stamps.

use std::collections::BTreeMap;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use gpodo_traits::{BodyTwist, ImuSample, JointState as Joint, ProprioceptiveSample};

use super::enu::LocalEnu;
use super::messages::RosMessage;
use super::tf::{TfPair, compose};
use super::topic::{Stamped, TopicError, TopicRequest, read_topics};
use crate::log::RoverLog;

fn default_rate() -> f64 {
    10.0
}

fn default_gap() -> f64 {
    0.5
}

/// Which time a message is placed at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeSource {
    /// The message's header stamp (when the sensor measured).
    #[default]
    Header,
    /// When the recorder received it.
    Receive,
}

/// One joint of the bag's `JointState` feeding one joint of the rover.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointRef {
    /// The joint's name in the bag.
    pub joint: String,
    /// Radians per unit of the recorded position (e.g. 2π/ticks per turn
    /// over a gear ratio; default 1).
    #[serde(default = "one")]
    pub position_scale: f64,
    /// Radians per second per unit of the recorded velocity (e.g. 2π/60
    /// for rpm; default 1).
    #[serde(default = "one")]
    pub rate_scale: f64,
}

fn one() -> f64 {
    1.0
}

/// The joints role: a `sensor_msgs/JointState` topic and which of its
/// joints are the rover's wheels, steering joints and bogies (by the
/// rover's names, e.g. `fl`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointMap {
    /// The topic.
    pub topic: String,
    /// Wheels: rover name → bag joint.
    #[serde(default)]
    pub wheels: BTreeMap<String, JointRef>,
    /// Steering joints.
    #[serde(default)]
    pub steering: BTreeMap<String, JointRef>,
    /// Passive bogies.
    #[serde(default)]
    pub bogies: BTreeMap<String, JointRef>,
}

/// Where the ground-truth pose comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum GroundTruthSource {
    /// A pose, odometry or GNSS topic.
    Topic(String),
    /// A transform of the TF tree, composed through intermediate frames.
    Tf {
        /// The frames and the TF topics.
        tf: TfPair,
    },
}

impl std::fmt::Display for GroundTruthSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Topic(t) => f.write_str(t),
            Self::Tf { tf } => write!(
                f,
                "TF {} → {} ({})",
                tf.parent,
                tf.child,
                tf.topics.join(", ")
            ),
        }
    }
}

/// Where the heading of a GNSS ground truth comes from (a fix has a
/// position, not an orientation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GnssHeading {
    /// The course over ground: the direction of the GNSS track over
    /// [`COURSE_WINDOW_SECS`] about each row, where the robot moves faster
    /// than [`COURSE_MIN_SPEED_MPS`], turned by π where the robot drives
    /// backwards (decided against the IMU's yaw); elsewhere the IMU's yaw
    /// with its mean offset to the course removed. Roll and pitch from the
    /// IMU. Lateral velocity is then zero by construction while moving.
    #[default]
    Course,
    /// The IMU's orientation as it is (right only when its yaw is
    /// referenced to east-north-up, as an INS's is; most IMUs' yaw is not).
    Imu,
}

/// Course over ground is taken over this window about each row (s).
pub const COURSE_WINDOW_SECS: f64 = 2.0;
/// Below this ground speed the GNSS course is not used (m/s).
pub const COURSE_MIN_SPEED_MPS: f64 = 0.3;

/// Which topic plays which role, and how streams are put on one clock.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TopicMap {
    /// `sensor_msgs/Imu`: gyro, specific force, and roll and pitch from its
    /// orientation.
    pub imu: String,
    /// How the IMU is mounted: `body_from_imu` as roll, pitch and yaw
    /// (rad, default 0), applied to its rates, forces and orientation
    /// (without a TF tree in the recording, this is the only place to say
    /// it; gravity should then read about +9.8 on the body's z at rest).
    #[serde(default)]
    pub imu_rotation_rpy_rad: [f64; 3],
    /// The ground-truth pose: a topic of `nav_msgs/Odometry`,
    /// `geometry_msgs/PoseStamped`, `geometry_msgs/PoseWithCovarianceStamped`,
    /// or `sensor_msgs/NavSatFix` (position in a local east-north-up frame
    /// about the first fix, orientation from the IMU), or a transform of
    /// the TF tree, `{tf: {parent: world, child: base_link}}`.
    pub ground_truth: GroundTruthSource,
    /// How a GNSS ground truth gets its heading (default: course over
    /// ground).
    #[serde(default)]
    pub gnss_heading: GnssHeading,
    /// Joint encoders (optional).
    #[serde(default)]
    pub joints: Option<JointMap>,
    /// Visual odometry (optional): `nav_msgs/Odometry`,
    /// `geometry_msgs/PoseStamped` or `PoseWithCovarianceStamped`, the
    /// trajectory a SLAM or VO system computed on the camera frames. Its
    /// stamps become the log's camera frames and Table II replays it
    /// (`frontend: {vo: {kind: replay}}` without a `path`).
    #[serde(default)]
    pub vo: Option<String>,
    /// The robot's own odometry (optional): `nav_msgs/Odometry` (its twist,
    /// in the child frame as ROS defines it) or `geometry_msgs/TwistStamped`
    /// (body frame); the `reported_odometry` motion model uses it as `g`.
    #[serde(default)]
    pub odometry: Option<String>,
    /// Rate of the common clock (Hz, default 10).
    #[serde(default = "default_rate")]
    pub rate_hz: f64,
    /// Longest interval between two messages of a stream that is
    /// interpolated across (s, default 0.5).
    #[serde(default = "default_gap")]
    pub max_gap_secs: f64,
    /// Header stamps (default) or receive times.
    #[serde(default)]
    pub time: TimeSource,
}

/// What an import did with each stream.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct StreamReport {
    /// The role (`imu`, `ground_truth`, `odometry`, `joints`).
    pub role: String,
    /// The topic.
    pub topic: String,
    /// Messages read.
    pub messages: usize,
    /// Messages whose stamp repeated the previous one (dropped).
    pub duplicates: usize,
    /// Messages stamped before the previous one (sorted into place).
    pub out_of_order: usize,
    /// Messages that carried nothing usable (e.g. a GNSS fix with no fix).
    pub unusable: usize,
    /// Clock rows dropped because this stream had a longer gap there.
    pub rows_in_gaps: usize,
    /// The longest interval interpolated across (s).
    pub max_gap_bridged_secs: f64,
    /// How much later than the earliest stream this one starts (s): the
    /// log starts with the latest stream.
    pub starts_late_secs: f64,
    /// How much earlier than the latest stream this one stops (s): a topic
    /// that stops part-way ends the log there.
    pub stops_early_secs: f64,
}

/// What an import wrote.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImportReport {
    /// Rows of the log.
    pub rows: usize,
    /// Clock rows dropped (in a gap of some stream).
    pub rows_dropped: usize,
    /// The log's time 0, seconds since the epoch.
    pub start_epoch_secs: f64,
    /// One entry per stream.
    pub streams: Vec<StreamReport>,
    /// How a GNSS ground truth got its heading, when it has one.
    pub gnss_heading: Option<HeadingReport>,
    /// Median horizontal and vertical position standard deviations the
    /// GNSS receiver reported (m), when its fixes carry a covariance.
    pub gnss_sigma_m: Option<[f64; 2]>,
    /// The `vo` role's poses, on the log's clock (s), in time order.
    #[serde(skip)]
    pub vo_poses: Vec<(f64, Isometry3<f64>)>,
}

/// How the heading of a GNSS ground truth was made ([`GnssHeading::Course`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeadingReport {
    /// Rows whose heading is the course over ground.
    pub rows_from_course: usize,
    /// Of those, rows driven backwards (course turned by π).
    pub rows_reversed: usize,
    /// Mean offset course − IMU yaw (deg), removed from the IMU's yaw on
    /// the other rows.
    pub imu_offset_deg: f64,
    /// 10th and 90th percentiles of course − IMU yaw − offset (deg): how far
    /// the IMU's yaw wanders from the track.
    pub imu_spread_deg: [f64; 2],
}

/// Why a recording could not be imported.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// A topic could not be read for its role.
    #[error(transparent)]
    Topic(#[from] TopicError),
    /// The topic map is unusable.
    #[error("topic map: {0}")]
    Map(String),
    /// Nothing was left on the common clock.
    #[error(
        "{file}: no row of the common clock has every stream within max_gap_secs ({gap} s): {detail}"
    )]
    Empty {
        /// The bag.
        file: String,
        /// The gap allowed.
        gap: f64,
        /// Per stream: messages and rows lost in gaps.
        detail: String,
    },
}

impl std::fmt::Display for HeadingReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "GNSS heading: course over ground on {} rows ({} driven backwards), elsewhere \
             the IMU yaw {:+.1}°; course − IMU yaw spans {:+.1}° to {:+.1}° (10–90 %)",
            self.rows_from_course,
            self.rows_reversed,
            self.imu_offset_deg,
            self.imu_spread_deg[0],
            self.imu_spread_deg[1]
        )
    }
}

/// A stream on its own clock: time (s since the epoch) and values.
struct Stream {
    report: StreamReport,
    times: Vec<f64>,
    values: Vec<Vec<f64>>,
    /// Index ranges of values that are quaternions `[x, y, z, w]`.
    quaternions: Vec<usize>,
}

impl Stream {
    fn new(
        role: &str,
        topic: &str,
        mut samples: Vec<(f64, Vec<f64>)>,
        messages: usize,
        unusable: usize,
        quaternions: Vec<usize>,
    ) -> Self {
        let mut report = StreamReport {
            role: role.into(),
            topic: topic.into(),
            messages,
            unusable,
            ..StreamReport::default()
        };
        report.out_of_order = samples.windows(2).filter(|w| w[1].0 < w[0].0).count();
        samples.sort_by(|a, b| a.0.total_cmp(&b.0));
        let before = samples.len();
        samples.dedup_by(|b, a| b.0 == a.0);
        report.duplicates = before - samples.len();
        let (times, values) = samples.into_iter().unzip();
        Self {
            report,
            times,
            values,
            quaternions,
        }
    }

    /// The values at `t`, interpolated between the messages around it, or
    /// `None` when they are more than `max_gap` apart (or `t` is outside).
    fn at(&mut self, t: f64, max_gap: f64) -> Option<Vec<f64>> {
        let k = self.times.partition_point(|&s| s <= t);
        if k == 0 {
            return None;
        }
        let i = k - 1;
        if self.times[i] == t {
            return Some(self.values[i].clone());
        }
        let j = k;
        if j >= self.times.len() {
            return None;
        }
        let gap = self.times[j] - self.times[i];
        if gap > max_gap {
            self.report.rows_in_gaps += 1;
            return None;
        }
        self.report.max_gap_bridged_secs = self.report.max_gap_bridged_secs.max(gap);
        let u = (t - self.times[i]) / gap;
        let (a, b) = (&self.values[i], &self.values[j]);
        let mut v: Vec<f64> = a.iter().zip(b).map(|(a, b)| a + u * (b - a)).collect();
        for &q in &self.quaternions {
            // The shorter way round, then back onto the unit sphere.
            let dot: f64 = (0..4).map(|c| a[q + c] * b[q + c]).sum();
            let sign = if dot < 0.0 { -1.0 } else { 1.0 };
            let mut n = 0.0;
            for c in 0..4 {
                v[q + c] = a[q + c] + u * (sign * b[q + c] - a[q + c]);
                n += v[q + c] * v[q + c];
            }
            let n = n.sqrt();
            for c in 0..4 {
                v[q + c] /= n;
            }
        }
        Some(v)
    }
}

/// Message times as seconds after a whole-second base near the recording's
/// start, subtracted in integer nanoseconds: seconds since the Unix epoch
/// held in an `f64` would keep only a quarter of a microsecond.
struct Clock {
    source: TimeSource,
    base_ns: i64,
}

impl Clock {
    /// The clock whose base is the whole second at or before the first
    /// message's time.
    fn new(source: TimeSource, first: Option<(&Stamped, i64)>) -> Self {
        let mut clock = Self { source, base_ns: 0 };
        if let Some((s, header_ns)) = first {
            let ns = clock.ns(s, header_ns);
            clock.base_ns = ns - ns.rem_euclid(1_000_000_000);
        }
        clock
    }

    fn ns(&self, s: &Stamped, header_ns: i64) -> i64 {
        match self.source {
            TimeSource::Header => header_ns,
            TimeSource::Receive => i64::try_from(s.log_time_ns).unwrap_or(i64::MAX),
        }
    }

    /// Seconds after the base.
    fn at(&self, s: &Stamped, header_ns: i64) -> f64 {
        (self.ns(s, header_ns) - self.base_ns) as f64 * 1e-9
    }
}

/// Roll and pitch (rad) of a `[x, y, z, w]` orientation (ZYX Euler angles).
fn roll_pitch(q: &[f64]) -> (f64, f64) {
    let (x, y, z, w) = (q[0], q[1], q[2], q[3]);
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    (roll, pitch)
}

/// Imports the bag at `path` as the rover log `name`.
///
/// # Errors
/// [`ImportError`] naming the file, topic and what is wrong.
pub fn import_bag(
    path: &Path,
    name: &str,
    map: &TopicMap,
) -> Result<(RoverLog, ImportReport), ImportError> {
    if !(map.rate_hz.is_finite() && map.rate_hz > 0.0) {
        return Err(ImportError::Map(
            "`rate_hz` must be a positive number".into(),
        ));
    }
    if !(map.max_gap_secs.is_finite() && map.max_gap_secs > 0.0) {
        return Err(ImportError::Map(
            "`max_gap_secs` must be a positive number of seconds".into(),
        ));
    }
    // Every role's topic, read in one pass over the bag.
    let mut requests = vec![TopicRequest {
        topic: &map.imu,
        role: "imu",
        expected: &["sensor_msgs/Imu"],
        optional: false,
    }];
    match &map.ground_truth {
        GroundTruthSource::Topic(topic) => requests.push(TopicRequest {
            topic,
            role: "ground_truth",
            expected: &[
                "nav_msgs/Odometry",
                "geometry_msgs/PoseStamped",
                "geometry_msgs/PoseWithCovarianceStamped",
                "sensor_msgs/NavSatFix",
            ],
            optional: false,
        }),
        GroundTruthSource::Tf { tf } => {
            if tf.topics.is_empty() {
                return Err(ImportError::Map(
                    "`ground_truth.tf.topics` must name at least one TF topic".into(),
                ));
            }
            requests.extend(tf.topics.iter().map(|topic| TopicRequest {
                topic,
                role: "ground_truth",
                expected: &["tf2_msgs/TFMessage"],
                optional: false,
            }));
        }
    }
    if let Some(topic) = &map.odometry {
        requests.push(TopicRequest {
            topic,
            role: "odometry",
            expected: &["nav_msgs/Odometry", "geometry_msgs/TwistStamped"],
            optional: false,
        });
    }
    if let Some(topic) = &map.vo {
        requests.push(TopicRequest {
            topic,
            role: "vo",
            expected: &[
                "nav_msgs/Odometry",
                "geometry_msgs/PoseStamped",
                "geometry_msgs/PoseWithCovarianceStamped",
            ],
            optional: true,
        });
    }
    if let Some(j) = &map.joints {
        requests.push(TopicRequest {
            topic: &j.topic,
            role: "joints",
            expected: &["sensor_msgs/JointState"],
            optional: false,
        });
    }
    let mut read = read_topics(path, &requests)?.into_iter();
    let imu_messages = read.next().unwrap_or_default();
    let gt_topics = match &map.ground_truth {
        GroundTruthSource::Topic(_) => 1,
        GroundTruthSource::Tf { tf } => tf.topics.len(),
    };
    let gt_by_topic: Vec<Vec<Stamped>> = read.by_ref().take(gt_topics).collect();
    let odometry_messages = map.odometry.as_ref().and_then(|_| read.next());
    let vo_messages = map.vo.as_ref().and_then(|_| read.next());
    let joint_messages = read.next();
    let clock = Clock::new(
        map.time,
        imu_messages.first().and_then(|s| match &s.message {
            RosMessage::Imu(m) => Some((s, m.header.stamp_ns)),
            _ => None,
        }),
    );
    // IMU: orientation (4), gyro (3), specific force (3).
    let n_imu = imu_messages.len();
    let [r, p, y] = map.imu_rotation_rpy_rad;
    let body_from_imu = UnitQuaternion::from_euler_angles(r, p, y);
    let imu_samples: Vec<(f64, Vec<f64>)> = imu_messages
        .iter()
        .filter_map(|s| match &s.message {
            RosMessage::Imu(m) => {
                let o = m.orientation;
                let world_from_imu =
                    UnitQuaternion::from_quaternion(Quaternion::new(o[3], o[0], o[1], o[2]));
                let q = world_from_imu * body_from_imu.inverse();
                let gyro = body_from_imu * Vector3::from(m.angular_velocity);
                let acc = body_from_imu * Vector3::from(m.linear_acceleration);
                let mut v = vec![q.i, q.j, q.k, q.w];
                v.extend(gyro.iter());
                v.extend(acc.iter());
                Some((clock.at(s, m.header.stamp_ns), v))
            }
            _ => None,
        })
        .collect();
    let mut imu = Stream::new("imu", &map.imu, imu_samples, n_imu, 0, vec![0]);
    // Ground truth: position (3) and, except from GNSS, orientation (4).
    let n_gt = gt_by_topic.iter().map(Vec::len).sum();
    let mut enu: Option<LocalEnu> = None;
    let mut unusable = 0;
    let mut gnss = false;
    let mut sigmas: Vec<[f64; 2]> = Vec::new();
    let mut gt_samples = Vec::new();
    if let GroundTruthSource::Tf { tf } = &map.ground_truth {
        let clock = &clock;
        let inputs = gt_by_topic
            .iter()
            .zip(&tf.topics)
            .flat_map(|(messages, topic)| {
                let is_static = topic.ends_with("tf_static");
                messages.iter().map(move |s| {
                    let received = (map.time == TimeSource::Receive).then(|| clock.at(s, 0));
                    (received, &s.message, is_static)
                })
            });
        let header_time = |ns: i64| (ns - clock.base_ns) as f64 * 1e-9;
        let (poses, missing) = compose(tf, inputs, &header_time, map.max_gap_secs)
            .map_err(|e| ImportError::Map(format!("{}: ground_truth: {e}", path.display())))?;
        unusable = missing;
        gt_samples = poses
            .into_iter()
            .map(|(t, p)| {
                let (v, q) = (p.translation.vector, p.rotation);
                (t, vec![v.x, v.y, v.z, q.i, q.j, q.k, q.w])
            })
            .collect();
    }
    for s in gt_by_topic.iter().flatten() {
        let (header, values) = match &s.message {
            RosMessage::Odometry(m) => (
                &m.header,
                [m.pose.position.to_vec(), m.pose.orientation.to_vec()].concat(),
            ),
            RosMessage::PoseStamped(h, p) | RosMessage::PoseWithCovarianceStamped(h, p, _) => {
                (h, [p.position.to_vec(), p.orientation.to_vec()].concat())
            }
            RosMessage::NavSatFix(f) => {
                gnss = true;
                if f.status < 0 || !(f.latitude.is_finite() && f.longitude.is_finite()) {
                    unusable += 1;
                    continue;
                }
                if f.position_covariance_type > 0 {
                    let c = &f.position_covariance;
                    sigmas.push([(0.5 * (c[0] + c[4])).sqrt(), c[8].sqrt()]);
                }
                let frame =
                    *enu.get_or_insert_with(|| LocalEnu::new(f.latitude, f.longitude, f.altitude));
                let alt = if f.altitude.is_finite() {
                    f.altitude
                } else {
                    0.0
                };
                (
                    &f.header,
                    frame.to_enu(f.latitude, f.longitude, alt).to_vec(),
                )
            }
            _ => continue,
        };
        gt_samples.push((clock.at(s, header.stamp_ns), values));
    }
    let gt_quaternions = if gnss { vec![] } else { vec![3] };
    let mut gt = Stream::new(
        "ground_truth",
        &map.ground_truth.to_string(),
        gt_samples,
        n_gt,
        unusable,
        gt_quaternions,
    );
    // Odometry: the reported body twist (6).
    let mut odometry = match (&map.odometry, odometry_messages) {
        (Some(topic), Some(messages)) => {
            let samples = messages
                .iter()
                .filter_map(|s| match &s.message {
                    RosMessage::Odometry(m) => Some((
                        clock.at(s, m.header.stamp_ns),
                        [m.twist.linear, m.twist.angular].concat(),
                    )),
                    RosMessage::TwistStamped(h, t) => {
                        Some((clock.at(s, h.stamp_ns), [t.linear, t.angular].concat()))
                    }
                    _ => None,
                })
                .collect();
            Some(Stream::new(
                "odometry",
                topic,
                samples,
                messages.len(),
                0,
                vec![],
            ))
        }
        _ => None,
    };
    // Joints: position and rate per mapped joint, in the rover's order.
    let groups: [(&str, Vec<(String, JointRef)>); 3] = match &map.joints {
        Some(j) => [
            ("wheels", j.wheels.clone().into_iter().collect()),
            ("steering", j.steering.clone().into_iter().collect()),
            ("bogies", j.bogies.clone().into_iter().collect()),
        ],
        None => [("wheels", vec![]), ("steering", vec![]), ("bogies", vec![])],
    };
    let mut joints = match (&map.joints, joint_messages) {
        (Some(j), Some(messages)) => {
            let n = messages.len();
            let mut unusable = 0;
            let mut samples = Vec::new();
            for s in &messages {
                let RosMessage::JointState(m) = &s.message else {
                    continue;
                };
                let mut v = Vec::new();
                let mut ok = true;
                for (_, refs) in &groups {
                    for (_, r) in refs {
                        match m.name.iter().position(|n| *n == r.joint) {
                            Some(k) if k < m.position.len() && k < m.velocity.len() => {
                                v.push(m.position[k] * r.position_scale);
                                v.push(m.velocity[k] * r.rate_scale);
                            }
                            _ => ok = false,
                        }
                    }
                }
                if ok {
                    samples.push((clock.at(s, m.header.stamp_ns), v));
                } else {
                    unusable += 1;
                }
            }
            Some(Stream::new(
                "joints",
                &j.topic,
                samples,
                n,
                unusable,
                vec![],
            ))
        }
        _ => None,
    };
    // The common clock, over the span every stream covers.
    let mut streams: Vec<&mut Stream> = vec![&mut imu, &mut gt];
    let odometry_at = odometry.as_ref().map(|_| streams.len());
    if let Some(o) = odometry.as_mut() {
        streams.push(o);
    }
    let joints_at = joints.as_ref().map(|_| streams.len());
    if let Some(j) = joints.as_mut() {
        streams.push(j);
    }
    let (start, end) = common_span(&mut streams);
    let dt = 1.0 / map.rate_hz;
    let steps = if end > start {
        ((end - start) / dt).floor() as usize + 1
    } else {
        0
    };
    let mut samples = Vec::new();
    let mut ground_truth = Vec::new();
    let mut dropped = 0;
    for k in 0..steps {
        let t = start + k as f64 * dt;
        let values: Vec<Option<Vec<f64>>> = streams
            .iter_mut()
            .map(|s| s.at(t, map.max_gap_secs))
            .collect();
        let (Some(Some(i)), Some(Some(g))) = (values.first(), values.get(1)) else {
            dropped += 1;
            continue;
        };
        let ov = odometry_at.and_then(|k| values[k].clone());
        let jv = joints_at.and_then(|k| values[k].clone());
        if (joints_needed(&groups) && jv.is_none()) || (odometry_at.is_some() && ov.is_none()) {
            dropped += 1;
            continue;
        }
        let (roll, pitch) = roll_pitch(&i[0..4]);
        let mut group_joints: [Vec<Joint>; 3] = [vec![], vec![], vec![]];
        let mut at = 0;
        for (g, (_, refs)) in groups.iter().enumerate() {
            for _ in refs {
                let v = jv.as_deref().unwrap_or(&[]);
                group_joints[g].push(Joint {
                    position_rad: v.get(at).copied().unwrap_or(0.0),
                    rate_radps: v.get(at + 1).copied().unwrap_or(0.0),
                });
                at += 2;
            }
        }
        let [wheels, steering, bogies] = group_joints;
        samples.push(ProprioceptiveSample {
            time_secs: t - start,
            wheels,
            steering,
            bogies,
            imu: ImuSample {
                gyro_radps: Vector3::new(i[4], i[5], i[6]),
                accel_mps2: Vector3::new(i[7], i[8], i[9]),
                roll_rad: roll,
                pitch_rad: pitch,
            },
            contact_angles_rad: None,
            odometry: ov.map(|o| BodyTwist {
                linear_mps: Vector3::new(o[0], o[1], o[2]),
                angular_radps: Vector3::new(o[3], o[4], o[5]),
            }),
        });
        let q = if gnss {
            [i[0], i[1], i[2], i[3]]
        } else {
            [g[3], g[4], g[5], g[6]]
        };
        ground_truth.push(Isometry3::from_parts(
            Translation3::new(g[0], g[1], g[2]),
            UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2])),
        ));
    }
    let reports: Vec<StreamReport> = streams.iter().map(|s| s.report.clone()).collect();
    // Visual odometry: its poses on the log's clock, and its stamps within
    // the log as the camera frames.
    let mut vo_poses: Vec<(f64, Isometry3<f64>)> = vo_messages
        .iter()
        .flatten()
        .filter_map(|s| {
            let (h, p) = match &s.message {
                RosMessage::Odometry(m) => (&m.header, &m.pose),
                RosMessage::PoseStamped(h, p) | RosMessage::PoseWithCovarianceStamped(h, p, _) => {
                    (h, p)
                }
                _ => return None,
            };
            let [x, y, z, w] = p.orientation;
            let pose = Isometry3::from_parts(
                Translation3::from(Vector3::from(p.position)),
                UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
            );
            Some((clock.at(s, h.stamp_ns) - start, pose))
        })
        .collect();
    let vo_messages_read = vo_poses.len();
    let vo_out_of_order = vo_poses.windows(2).filter(|w| w[1].0 < w[0].0).count();
    vo_poses.sort_by(|a, b| a.0.total_cmp(&b.0));
    vo_poses.dedup_by(|b, a| a.0 == b.0);
    let mut reports = reports;
    if let Some(topic) = &map.vo {
        reports.push(StreamReport {
            role: "vo".into(),
            topic: topic.clone(),
            messages: vo_messages_read,
            duplicates: vo_messages_read - vo_poses.len(),
            out_of_order: vo_out_of_order,
            ..StreamReport::default()
        });
    }
    let camera_times_secs: Vec<f64> = match (samples.first(), samples.last()) {
        (Some(first), Some(last)) => vo_poses
            .iter()
            .map(|p| p.0)
            .filter(|t| *t >= first.time_secs && *t <= last.time_secs)
            .collect(),
        _ => Vec::new(),
    };
    let gnss_heading = (gnss && map.gnss_heading == GnssHeading::Course)
        .then(|| course_headings(&samples, &mut ground_truth));
    if samples.is_empty() {
        let detail = reports
            .iter()
            .map(|r| {
                format!(
                    "{} `{}`: {} messages, {} rows in gaps",
                    r.role, r.topic, r.messages, r.rows_in_gaps
                )
            })
            .collect::<Vec<_>>()
            .join("; ");
        return Err(ImportError::Empty {
            file: path.display().to_string(),
            gap: map.max_gap_secs,
            detail,
        });
    }
    let names = |g: usize| {
        groups[g]
            .1
            .iter()
            .map(|(n, _)| n.clone())
            .collect::<Vec<_>>()
    };
    let log = RoverLog {
        name: name.into(),
        wheel_names: names(0),
        steer_names: names(1),
        bogie_names: names(2),
        samples,
        ground_truth,
        camera_times_secs,
    };
    let report = ImportReport {
        rows: log.samples.len(),
        rows_dropped: dropped,
        start_epoch_secs: clock.base_ns as f64 * 1e-9 + start,
        streams: reports,
        gnss_heading,
        gnss_sigma_m: median_sigmas(&sigmas),
        vo_poses,
    };
    Ok((log, report))
}

/// The span every stream covers, `(latest first time, earliest last
/// time)`; each stream's report says how late it starts and how early it
/// stops against the others.
fn common_span(streams: &mut [&mut Stream]) -> (f64, f64) {
    let firsts: Vec<f64> = streams
        .iter()
        .filter_map(|s| s.times.first().copied())
        .collect();
    let lasts: Vec<f64> = streams
        .iter()
        .filter_map(|s| s.times.last().copied())
        .collect();
    let start = firsts.iter().copied().fold(f64::MIN, f64::max);
    let end = lasts.iter().copied().fold(f64::MAX, f64::min);
    let earliest = firsts.iter().copied().fold(f64::MAX, f64::min);
    let latest = lasts.iter().copied().fold(f64::MIN, f64::max);
    for s in streams.iter_mut() {
        if let (Some(first), Some(last)) = (s.times.first(), s.times.last()) {
            s.report.starts_late_secs = first - earliest;
            s.report.stops_early_secs = latest - last;
        }
    }
    (start, end)
}

/// Medians of the horizontal and vertical standard deviations.
fn median_sigmas(sigmas: &[[f64; 2]]) -> Option<[f64; 2]> {
    if sigmas.is_empty() {
        return None;
    }
    let median = |k: usize| {
        let mut v: Vec<f64> = sigmas.iter().map(|s| s[k]).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    Some([median(0), median(1)])
}

/// The smallest signed angle equal to `a` modulo 2π.
fn wrap(a: f64) -> f64 {
    (a + PI).rem_euclid(2.0 * PI) - PI
}

/// Replaces the yaw of GNSS ground-truth poses (which hold the IMU's
/// orientation) by the course over ground, as [`GnssHeading::Course`] says.
fn course_headings(
    samples: &[ProprioceptiveSample],
    ground_truth: &mut [Isometry3<f64>],
) -> HeadingReport {
    let times: Vec<f64> = samples.iter().map(|s| s.time_secs).collect();
    let half = 0.5 * COURSE_WINDOW_SECS;
    let imu_yaw: Vec<f64> = ground_truth
        .iter()
        .map(|p| p.rotation.euler_angles().2)
        .collect();
    // Course where the track over the window is long enough to have one.
    let course: Vec<Option<f64>> = (0..times.len())
        .map(|k| {
            let j = times.partition_point(|&t| t < times[k] - half);
            let l = times.partition_point(|&t| t <= times[k] + half) - 1;
            let span = times[l] - times[j];
            if span < half {
                return None;
            }
            let d = ground_truth[l].translation.vector - ground_truth[j].translation.vector;
            (d.xy().norm() / span >= COURSE_MIN_SPEED_MPS).then(|| d.y.atan2(d.x))
        })
        .collect();
    let diffs: Vec<f64> = course
        .iter()
        .zip(&imu_yaw)
        .filter_map(|(c, y)| c.map(|c| wrap(c - y)))
        .collect();
    // The offset modulo π from the doubled angles (forward and backward
    // driving agree there), then the half turn most rows agree with.
    let (s2, c2) = diffs.iter().fold((0.0, 0.0), |(s, c), d| {
        (s + (2.0 * d).sin(), c + (2.0 * d).cos())
    });
    let mut offset = 0.5 * s2.atan2(c2);
    let forward = diffs
        .iter()
        .filter(|d| wrap(*d - offset).abs() < FRAC_PI_2)
        .count();
    if 2 * forward < diffs.len() {
        offset = wrap(offset + PI);
    }
    let mut reversed = 0;
    let mut spread = Vec::with_capacity(diffs.len());
    for (k, pose) in ground_truth.iter_mut().enumerate() {
        let expected = imu_yaw[k] + offset;
        let heading = match course[k] {
            Some(c) => {
                let mut d = wrap(c - expected);
                let mut c = c;
                if d.abs() > FRAC_PI_2 {
                    reversed += 1;
                    c = wrap(c + PI);
                    d = wrap(c - expected);
                }
                spread.push(d);
                c
            }
            None => expected,
        };
        let s = &samples[k].imu;
        pose.rotation = UnitQuaternion::from_euler_angles(s.roll_rad, s.pitch_rad, heading);
    }
    spread.sort_by(f64::total_cmp);
    let quantile = |q: f64| {
        if spread.is_empty() {
            0.0
        } else {
            spread[((spread.len() - 1) as f64 * q).round() as usize].to_degrees()
        }
    };
    HeadingReport {
        rows_from_course: spread.len(),
        rows_reversed: reversed,
        imu_offset_deg: offset.to_degrees(),
        imu_spread_deg: [quantile(0.1), quantile(0.9)],
    }
}

fn joints_needed(groups: &[(&str, Vec<(String, JointRef)>); 3]) -> bool {
    groups.iter().any(|(_, refs)| !refs.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roll_and_pitch_of_known_rotations() {
        let q = UnitQuaternion::from_euler_angles(0.1, -0.2, 0.7);
        let (r, p) = roll_pitch(&[q.i, q.j, q.k, q.w]);
        assert!((r - 0.1).abs() < 1e-12 && (p + 0.2).abs() < 1e-12);
    }

    #[test]
    fn interpolation_stops_at_gaps_and_takes_the_short_way_round() {
        let q0 = [0.0, 0.0, 0.0, 1.0];
        let q1 = [0.0, 0.0, -0.0, -1.0]; // the same rotation, other sign
        let mut s = Stream::new(
            "t",
            "/t",
            vec![
                (0.0, [vec![0.0], q0.to_vec()].concat()),
                (1.0, [vec![2.0], q1.to_vec()].concat()),
                (5.0, [vec![4.0], q0.to_vec()].concat()),
            ],
            3,
            0,
            vec![1],
        );
        let v = s.at(0.25, 1.5).unwrap();
        assert!((v[0] - 0.5).abs() < 1e-12);
        assert!(
            (v[4].abs() - 1.0).abs() < 1e-12,
            "no collapse through zero: {v:?}"
        );
        assert!(s.at(3.0, 1.5).is_none());
        assert_eq!(s.report.rows_in_gaps, 1);
        assert_eq!(s.report.max_gap_bridged_secs, 1.0);
        assert!(s.at(-1.0, 1.5).is_none() && s.at(6.0, 1.5).is_none());
    }

    #[test]
    fn gnss_heading_is_the_course_turned_for_reversing_and_the_imu_offset_is_removed() {
        // 40 s north at 1 m/s facing north, then 20 s south still facing
        // north (reversing), at 10 Hz; the IMU's yaw reads 40° less than
        // the true heading (90°), and its roll and pitch are kept.
        let (roll, pitch) = (0.01, -0.02);
        let mut samples = Vec::new();
        let mut ground_truth = Vec::new();
        for k in 0..=600 {
            let t = k as f64 * 0.1;
            let y = if t <= 40.0 { t } else { 80.0 - t };
            let mut s = ProprioceptiveSample {
                time_secs: t,
                ..Default::default()
            };
            s.imu.roll_rad = roll;
            s.imu.pitch_rad = pitch;
            samples.push(s);
            let imu = UnitQuaternion::from_euler_angles(roll, pitch, 50f64.to_radians());
            ground_truth.push(Isometry3::from_parts(Translation3::new(0.0, y, 0.0), imu));
        }
        let report = course_headings(&samples, &mut ground_truth);
        assert!((report.imu_offset_deg - 40.0).abs() < 1e-9, "{report:?}");
        // Rows within a second of the turn have too short a net track.
        assert!(report.rows_from_course > 570, "{report:?}");
        assert!((190..=200).contains(&report.rows_reversed), "{report:?}");
        for pose in &ground_truth {
            let (r, p, yaw) = pose.rotation.euler_angles();
            assert!((r - roll).abs() < 1e-12 && (p - pitch).abs() < 1e-12);
            assert!((yaw - FRAC_PI_2).abs() < 1e-9, "{}", yaw.to_degrees());
        }
    }

    #[test]
    fn a_stream_that_stops_part_way_ends_the_log_and_says_so() {
        let stream = |role: &str, from: f64, to: f64| {
            let samples = (0..=((to - from) * 10.0).round() as usize)
                .map(|k| (from + k as f64 * 0.1, vec![0.0]))
                .collect();
            Stream::new(role, "/t", samples, 0, 0, vec![])
        };
        let (mut imu, mut gt, mut odom) = (
            stream("imu", 0.0, 100.0),
            stream("ground_truth", 2.0, 100.0),
            stream("odometry", 0.0, 40.0),
        );
        let (start, end) = common_span(&mut [&mut imu, &mut gt, &mut odom]);
        assert_eq!((start, end), (2.0, 40.0));
        assert_eq!(odom.report.stops_early_secs, 60.0);
        assert_eq!(gt.report.starts_late_secs, 2.0);
        assert_eq!(
            (imu.report.starts_late_secs, imu.report.stops_early_secs),
            (0.0, 0.0)
        );
    }

    #[test]
    fn duplicates_and_out_of_order_stamps_are_counted() {
        let s = Stream::new(
            "t",
            "/t",
            vec![
                (1.0, vec![1.0]),
                (0.0, vec![0.0]),
                (1.0, vec![9.0]),
                (2.0, vec![2.0]),
            ],
            4,
            0,
            vec![],
        );
        assert_eq!((s.report.out_of_order, s.report.duplicates), (1, 1));
        assert_eq!(s.times, vec![0.0, 1.0, 2.0]);
    }
}

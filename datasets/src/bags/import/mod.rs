//! A recording turned into the rover-log CSV that `dataset: {kind: logs}`
//! reads (`gpodo import`): each role's topic read and checked
//! (in one pass, [`read_topics`]), every stream put on one clock at `rate_hz` by linear
//! interpolation (quaternions normalised after aligning their signs), and
//! never across a gap longer than `max_gap_secs`: rows that would need it
//! are dropped and counted, as are duplicated and out-of-order stamps.
//!
//! * [`map`]: the topic map;
//! * [`heading`]: the heading of a GNSS ground truth;
//! * `stream`: streams on their own clocks, and the common clock.

pub mod heading;
pub mod live;
pub mod map;
mod roles;
mod stream;

pub use heading::{COURSE_MIN_SPEED_MPS, COURSE_WINDOW_SECS, GnssHeading, HeadingReport};
pub use map::{GroundTruthSource, JointMap, JointRef, TimeSource, TopicMap};

use std::path::Path;

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use serde::Serialize;

use gpodo_traits::{BodyTwist, ImuSample, JointState as Joint, ProprioceptiveSample};

use super::messages::RosMessage;
use super::topic::{Stamped, TopicError, read_topics};
use super::{Damage, OnDamage};
use crate::log::RoverLog;
use heading::course_headings;
use live::{JointGroups, joint_groups};
use roles::{GroundTruth, ground_truth_stream, imu_stream, joint_stream, odometry_stream};
use stream::{Clock, Stream, common_span};

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
    /// The log's time 0, nanoseconds since the epoch (the stamp of the
    /// row at time 0, exactly).
    pub start_epoch_ns: i64,
    /// One entry per stream.
    pub streams: Vec<StreamReport>,
    /// How a GNSS ground truth got its heading, when it has one.
    pub gnss_heading: Option<HeadingReport>,
    /// Median horizontal and vertical position standard deviations the
    /// GNSS receiver reported (m), when its fixes carry a covariance.
    pub gnss_sigma_m: Option<[f64; 2]>,
    /// The damaged chunks skipped (`skip_damaged: true`) and what they
    /// held; empty for an intact recording.
    pub damage: Damage,
    /// The `vo` role's poses, on the log's clock (s), in time order.
    #[serde(skip)]
    pub vo_poses: Vec<(f64, Isometry3<f64>)>,
}

impl std::fmt::Display for StreamReport {
    /// One line: counts, the longest gap bridged, and a late start or an
    /// early stop (over 1 s) against the other streams.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} {}: {} msgs, {} duplicated, {} out of order, {} unusable, {} rows in gaps, longest gap bridged {:.3} s",
            self.role,
            self.topic,
            self.messages,
            self.duplicates,
            self.out_of_order,
            self.unusable,
            self.rows_in_gaps,
            self.max_gap_bridged_secs
        )?;
        if self.starts_late_secs > 1.0 {
            write!(
                f,
                ", starts {:.1} s after the first stream",
                self.starts_late_secs
            )?;
        }
        if self.stops_early_secs > 1.0 {
            write!(
                f,
                ", stops {:.1} s before the last stream (the log ends there)",
                self.stops_early_secs
            )?;
        }
        Ok(())
    }
}

impl ImportReport {
    /// What the import made of a GNSS ground truth (its heading, the
    /// receiver's σ), one line each; empty for other ground truths.
    pub fn gnss_notes(&self) -> Vec<String> {
        let mut notes: Vec<String> = self.gnss_heading.iter().map(|h| h.to_string()).collect();
        notes.extend(self.gnss_sigma_m.map(|[h, v]| {
            format!(
                "GNSS σ reported by the receiver (median): {h:.2} m horizontal, {v:.2} m vertical"
            )
        }));
        notes
    }
}

/// The most rows the common clock may have per message of the densest
/// stream: a clock a hundred times faster than every sensor interpolates
/// nothing new, and a larger span can only come from a damaged stamp.
pub const ROWS_PER_MESSAGE: usize = 100;

/// Why a recording could not be imported.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// A topic could not be read for its role.
    #[error(transparent)]
    Topic(#[from] TopicError),
    /// The topic map is unusable.
    #[error("topic map: {0}")]
    Map(String),
    /// The common clock would have far more rows than the recording has
    /// messages: a stamp far outside the recording, or a `rate_hz` typo.
    #[error(
        "{file}: `rate_hz: {rate_hz}` over the {span_secs:.1} s the streams span would make {rows} rows, more than {limit} ({ROWS_PER_MESSAGE}× the {messages} messages of the densest stream); check `rate_hz`, or the stamps (a stamp far outside the recording stretches the span)"
    )]
    TooManyRows {
        /// The bag.
        file: String,
        /// The clock's rate.
        rate_hz: f64,
        /// The span every stream covers (s).
        span_secs: f64,
        /// The rows it would make.
        rows: f64,
        /// The largest number allowed.
        limit: usize,
        /// Messages of the densest stream.
        messages: usize,
    },
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

/// Roll and pitch (rad) of a `[x, y, z, w]` orientation (ZYX Euler angles).
fn roll_pitch(q: &[f64]) -> (f64, f64) {
    live::roll_pitch(&UnitQuaternion::new_unchecked(Quaternion::new(
        q[3], q[0], q[1], q[2],
    )))
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
    map.check()?;
    let requests = map.topic_requests()?;
    let on_damage = if map.skip_damaged {
        OnDamage::Skip
    } else {
        OnDamage::Stop
    };
    let (read, damage) = read_topics(path, &requests, on_damage)?;
    let mut read = read.into_iter();
    let imu_messages = map.imu.as_ref().map(|_| read.next().unwrap_or_default());
    let gt_topics = match &map.ground_truth {
        GroundTruthSource::Topic(_) => 1,
        GroundTruthSource::Tf { tf } => tf.topics.len(),
    };
    let gt_by_topic: Vec<Vec<Stamped>> = read.by_ref().take(gt_topics).collect();
    let odometry_messages = map.odometry.as_ref().and_then(|_| read.next());
    let vo_messages = map.vo.as_ref().and_then(|_| read.next());
    let joint_messages = read.next();
    // The clock's base: the first IMU message, else the first ground truth.
    let first = match &imu_messages {
        Some(messages) => messages.first(),
        None => gt_by_topic.iter().flatten().next(),
    };
    let clock = Clock::new(
        map.time,
        first.and_then(|s| Some((s, header_ns(&s.message)?))),
    );
    let mut imu = match (&map.imu, &imu_messages) {
        (Some(topic), Some(messages)) => Some(imu_stream(map, topic, messages, &clock)),
        _ => None,
    };
    let GroundTruth {
        stream: mut gt,
        gnss,
        sigmas,
    } = ground_truth_stream(path, map, &gt_by_topic, &clock)?;
    let mut odometry = odometry_stream(map, odometry_messages, &clock);
    let groups = joint_groups(map);
    let mut joints = joint_stream(map, &groups, joint_messages, &clock);
    // The common clock, over the span every stream covers.
    let mut streams: Vec<&mut Stream> = Vec::new();
    let imu_at = imu.as_ref().map(|_| streams.len());
    if let Some(i) = imu.as_mut() {
        streams.push(i);
    }
    let gt_at = streams.len();
    streams.push(&mut gt);
    let odometry_at = odometry.as_ref().map(|_| streams.len());
    if let Some(o) = odometry.as_mut() {
        streams.push(o);
    }
    let joints_at = joints.as_ref().map(|_| streams.len());
    if let Some(j) = joints.as_mut() {
        streams.push(j);
    }
    let (start, end) = common_span(&mut streams);
    // The clock's rows fall on whole nanoseconds: a row at a message's
    // stamp takes that message as it is, at the time a node reading the
    // stamp gives it.
    let (start_ns, end_ns) = ((start * 1e9).round() as i64, (end * 1e9).round() as i64);
    let period_ns = 1e9 / map.rate_hz;
    let steps = row_count(path, map, &streams, start_ns, end_ns)?;
    let mut samples = Vec::new();
    let mut ground_truth = Vec::new();
    let mut dropped = 0;
    for k in 0..steps {
        let offset_ns = (k as f64 * period_ns).round() as i64;
        let t = (start_ns + offset_ns) as f64 * 1e-9;
        let values: Vec<Option<Vec<f64>>> = streams
            .iter_mut()
            .map(|s| s.at(t, map.max_gap_secs))
            .collect();
        let Some(Some(g)) = values.get(gt_at) else {
            dropped += 1;
            continue;
        };
        let i = imu_at.and_then(|k| values[k].as_deref());
        if imu_at.is_some() && i.is_none() {
            dropped += 1;
            continue;
        }
        let ov = odometry_at.and_then(|k| values[k].clone());
        let jv = joints_at.and_then(|k| values[k].clone());
        if (joints_needed(&groups) && jv.is_none()) || (odometry_at.is_some() && ov.is_none()) {
            dropped += 1;
            continue;
        }
        let (sample, pose) = sample_at(offset_ns as f64 * 1e-9, i, g, ov, jv, &groups, gnss);
        samples.push(sample);
        ground_truth.push(pose);
    }
    let mut reports: Vec<StreamReport> = streams.iter().map(|s| s.report.clone()).collect();
    // Visual odometry: its poses on the log's clock, and its stamps within
    // the log as the camera frames.
    let (vo_poses, vo_report) = vo_on_clock(map, vo_messages.as_deref(), &clock, start_ns);
    reports.extend(vo_report);
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
        return Err(nothing_imported(path, map, &reports));
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
        start_epoch_ns: clock.base_ns + start_ns,
        streams: reports,
        gnss_heading,
        gnss_sigma_m: median_sigmas(&sigmas),
        damage,
        vo_poses,
    };
    Ok((log, report))
}

/// One row of the log at `time_secs`: the sample from the streams' values
/// there (IMU `i`, odometry `ov`, joints `jv` in `groups` order) and the
/// ground truth `g` (with the IMU's orientation when the ground truth is
/// GNSS, which gives none).
fn sample_at(
    time_secs: f64,
    i: Option<&[f64]>,
    g: &[f64],
    ov: Option<Vec<f64>>,
    jv: Option<Vec<f64>>,
    groups: &JointGroups,
    gnss: bool,
) -> (ProprioceptiveSample, Isometry3<f64>) {
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
    let sample = ProprioceptiveSample {
        time_secs,
        wheels,
        steering,
        bogies,
        imu: i.map(|i| {
            let (roll, pitch) = roll_pitch(&i[0..4]);
            ImuSample {
                gyro_radps: Vector3::new(i[4], i[5], i[6]),
                accel_mps2: Vector3::new(i[7], i[8], i[9]),
                roll_rad: roll,
                pitch_rad: pitch,
            }
        }),
        attitude_rad: None,
        contact_angles_rad: None,
        odometry: ov.map(|o| BodyTwist {
            linear_mps: Vector3::new(o[0], o[1], o[2]),
            angular_radps: Vector3::new(o[3], o[4], o[5]),
        }),
    };
    // GNSS gives no orientation: the IMU's (its yaw replaced by the
    // heading below), or level without an IMU.
    let q = if gnss {
        i.map_or([0.0, 0.0, 0.0, 1.0], |i| [i[0], i[1], i[2], i[3]])
    } else {
        [g[3], g[4], g[5], g[6]]
    };
    let pose = Isometry3::from_parts(
        Translation3::new(g[0], g[1], g[2]),
        UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2])),
    );
    (sample, pose)
}

/// The recorded VO's poses on the log's clock (s from `start`), in time
/// order without repeated stamps, and what was read of its topic.
fn vo_on_clock(
    map: &TopicMap,
    vo_messages: Option<&[Stamped]>,
    clock: &Clock,
    start_ns: i64,
) -> (Vec<(f64, Isometry3<f64>)>, Option<StreamReport>) {
    let mut poses: Vec<(f64, Isometry3<f64>)> = vo_messages
        .into_iter()
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
            let ns = clock.ns(s, h.stamp_ns) - clock.base_ns - start_ns;
            Some((ns as f64 * 1e-9, pose))
        })
        .collect();
    let read = poses.len();
    let out_of_order = poses.windows(2).filter(|w| w[1].0 < w[0].0).count();
    poses.sort_by(|a, b| a.0.total_cmp(&b.0));
    poses.dedup_by(|b, a| a.0 == b.0);
    let report = map.vo.as_ref().map(|topic| StreamReport {
        role: "vo".into(),
        topic: topic.clone(),
        messages: read,
        duplicates: read - poses.len(),
        out_of_order,
        ..StreamReport::default()
    });
    (poses, report)
}

/// How many rows the common span holds at the map's rate.
///
/// # Errors
/// [`ImportError::TooManyRows`] when they are more than
/// [`ROWS_PER_MESSAGE`] per message of the busiest stream (a rate or a
/// stamp that is wrong, usually).
fn row_count(
    path: &Path,
    map: &TopicMap,
    streams: &[&mut Stream],
    start_ns: i64,
    end_ns: i64,
) -> Result<usize, ImportError> {
    let period_ns = 1e9 / map.rate_hz;
    // A row within half a nanosecond of the end is on it.
    let rows = if end_ns > start_ns {
        ((end_ns - start_ns) as f64 / period_ns + 0.5 / period_ns).floor() + 1.0
    } else {
        0.0
    };
    let messages = streams.iter().map(|s| s.times.len()).max().unwrap_or(0);
    let limit = ROWS_PER_MESSAGE.saturating_mul(messages.max(1));
    if rows > limit as f64 {
        return Err(ImportError::TooManyRows {
            file: path.display().to_string(),
            rate_hz: map.rate_hz,
            span_secs: (end_ns - start_ns) as f64 * 1e-9,
            rows,
            limit,
            messages,
        });
    }
    Ok(rows as usize)
}

/// The error of an import that kept no row, with what each stream gave.
fn nothing_imported(path: &Path, map: &TopicMap, reports: &[StreamReport]) -> ImportError {
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
    ImportError::Empty {
        file: path.display().to_string(),
        gap: map.max_gap_secs,
        detail,
    }
}

/// The header stamp of a message (ns), the first transform's for TF.
fn header_ns(message: &RosMessage) -> Option<i64> {
    use RosMessage as M;
    Some(match message {
        M::Imu(m) => m.header.stamp_ns,
        M::Odometry(m) => m.header.stamp_ns,
        M::NavSatFix(m) => m.header.stamp_ns,
        M::JointState(m) => m.header.stamp_ns,
        M::PoseStamped(h, _) | M::PoseWithCovarianceStamped(h, _, _) | M::TwistStamped(h, _) => {
            h.stamp_ns
        }
        M::Tf(transforms) => transforms.first()?.header.stamp_ns,
        M::Image(m) => m.header.stamp_ns,
        M::CompressedImage(m) => m.header.stamp_ns,
        M::CameraInfo(m) => m.header.stamp_ns,
    })
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

fn joints_needed(groups: &JointGroups) -> bool {
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
}

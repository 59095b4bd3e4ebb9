//! Each role's messages turned into a stream of values on the import
//! clock: the IMU (orientation, rates and forces in the body frame), the
//! ground truth (a pose topic, GNSS in local ENU, or a TF chain), the
//! robot's odometry twist and the mapped joints.

use std::path::Path;

use nalgebra::UnitQuaternion;

use super::live::{JointGroups, imu_in_body, joint_values};
use super::stream::{Clock, Stream};
use super::{GroundTruthSource, ImportError, TimeSource, TopicMap};
use crate::bags::enu::LocalEnu;
use crate::bags::messages::RosMessage;
use crate::bags::tf::compose;
use crate::bags::topic::Stamped;

/// The IMU role: orientation `[x, y, z, w]` (4), gyro (3) and specific
/// force (3), all in the body frame.
pub(super) fn imu_stream(
    map: &TopicMap,
    topic: &str,
    imu_messages: &[Stamped],
    clock: &Clock,
) -> Stream {
    let n_imu = imu_messages.len();
    let [r, p, y] = map.imu_rotation_rpy_rad;
    let body_from_imu = UnitQuaternion::from_euler_angles(r, p, y);
    let imu_samples: Vec<(f64, Vec<f64>)> = imu_messages
        .iter()
        .filter_map(|s| match &s.message {
            RosMessage::Imu(m) => {
                let (q, gyro, acc) = imu_in_body(&body_from_imu, m);
                let mut v = vec![q.i, q.j, q.k, q.w];
                v.extend(gyro.iter());
                v.extend(acc.iter());
                Some((clock.at(s, m.header.stamp_ns), v))
            }
            _ => None,
        })
        .collect();
    Stream::new("imu", topic, imu_samples, n_imu, 0, vec![0])
}

/// The ground-truth role, and what it was made of.
pub(super) struct GroundTruth {
    /// Position (3) and, except from GNSS, orientation `[x, y, z, w]` (4).
    pub(super) stream: Stream,
    /// Whether the positions are GNSS fixes (orientation from the IMU, or
    /// level without one; the heading from the course or the IMU).
    pub(super) gnss: bool,
    /// The receiver's horizontal and vertical σ per fix that has one (m).
    pub(super) sigmas: Vec<[f64; 2]>,
}

/// The ground-truth role from its topics' messages (one topic, or the TF
/// topics in map order).
///
/// # Errors
/// [`ImportError::Map`] when the TF tree does not link the asked frames.
pub(super) fn ground_truth_stream(
    path: &Path,
    map: &TopicMap,
    gt_by_topic: &[Vec<Stamped>],
    clock: &Clock,
) -> Result<GroundTruth, ImportError> {
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
    let stream = Stream::new(
        "ground_truth",
        &map.ground_truth.to_string(),
        gt_samples,
        n_gt,
        unusable,
        gt_quaternions,
    );
    Ok(GroundTruth {
        stream,
        gnss,
        sigmas,
    })
}

/// The odometry role: the reported body twist (6), when the map has one.
pub(super) fn odometry_stream(
    map: &TopicMap,
    odometry_messages: Option<Vec<Stamped>>,
    clock: &Clock,
) -> Option<Stream> {
    match (&map.odometry, odometry_messages) {
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
    }
}

/// The joints role: position and rate per mapped joint, in `groups`
/// order; a message lacking one of them is counted as unusable.
pub(super) fn joint_stream(
    map: &TopicMap,
    groups: &JointGroups,
    joint_messages: Option<Vec<Stamped>>,
    clock: &Clock,
) -> Option<Stream> {
    match (&map.joints, joint_messages) {
        (Some(j), Some(messages)) => {
            let n = messages.len();
            let mut unusable = 0;
            let mut samples = Vec::new();
            for s in &messages {
                let RosMessage::JointState(m) = &s.message else {
                    continue;
                };
                match joint_values(groups, m) {
                    Ok(v) => samples.push((clock.at(s, m.header.stamp_ns), v)),
                    Err(_) => unusable += 1,
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
    }
}

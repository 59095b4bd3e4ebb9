//! A chosen `parent → child` transform out of a recording's TF tree
//! (`tf2_msgs/TFMessage` on `/tf` and, for the transforms that never
//! change, `/tf_static`), composed through intermediate frames when the two
//! are not directly linked: up from the child and from the parent to their
//! common ancestor, `parent_from_child = (ancestor_from_parent)⁻¹ ·
//! ancestor_from_child`.
//!
//! The composed pose is produced at the stamps of the chain's dynamic edge
//! that comes nearest the child (for `map → odom → base_link`, the
//! `odom → base_link` stamps); every other dynamic edge is interpolated
//! there (linear in translation, shortest-arc slerp in rotation), never
//! across a gap longer than `max_gap_secs`, and stamps where one cannot be
//! are counted, not invented.

use std::collections::BTreeMap;

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use super::messages::{RosMessage, TransformStamped};

fn default_tf_topics() -> Vec<String> {
    vec!["/tf".into()]
}

/// Which transform of the TF tree is the ground truth.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TfPair {
    /// The fixed frame (e.g. `world`, `map`).
    pub parent: String,
    /// The robot's body frame (e.g. `base_link`).
    pub child: String,
    /// The TF topics to read (default `[/tf]`); transforms on a topic whose
    /// name ends in `tf_static` are constant.
    #[serde(default = "default_tf_topics")]
    pub topics: Vec<String>,
}

/// Why the transform could not be composed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("no TF chain from `{parent}` to `{child}`: {detail}")]
pub struct TfError {
    /// The parent frame asked for.
    pub parent: String,
    /// The child frame asked for.
    pub child: String,
    /// What is missing, with the frames the recording has.
    pub detail: String,
}

/// One edge of the tree: parent frame, and its transforms over time.
#[derive(Debug, Default)]
struct Edge {
    parent: String,
    is_static: bool,
    /// `(time, parent_from_child)`, sorted by time, one per time.
    samples: Vec<(f64, Isometry3<f64>)>,
}

impl Edge {
    /// The transform at `t`, or `None` outside the samples or across a gap
    /// longer than `max_gap`.
    fn at(&self, t: f64, max_gap: f64) -> Option<Isometry3<f64>> {
        if self.is_static {
            return self.samples.last().map(|s| s.1);
        }
        let k = self.samples.partition_point(|s| s.0 <= t);
        let (t0, a) = *self.samples.get(k.checked_sub(1)?)?;
        if t0 == t {
            return Some(a);
        }
        let (t1, b) = *self.samples.get(k)?;
        if t1 - t0 > max_gap {
            return None;
        }
        let u = (t - t0) / (t1 - t0);
        let translation = a.translation.vector.lerp(&b.translation.vector, u);
        let rotation = a
            .rotation
            .try_slerp(&b.rotation, u, 1e-12)
            .unwrap_or(a.rotation);
        Some(Isometry3::from_parts(translation.into(), rotation))
    }
}

fn isometry(t: &TransformStamped) -> Isometry3<f64> {
    let [x, y, z, w] = t.rotation;
    Isometry3::from_parts(
        Translation3::from(Vector3::from(t.translation)),
        UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
    )
}

/// One TF message for [`compose`]: its receive time on the import clock
/// when transforms are placed at receive times (`None`: at each
/// transform's own header stamp), and whether it came from a static topic.
pub type TfInput<'a> = (Option<f64>, &'a RosMessage, bool);

/// Poses with their times on the import clock (s).
pub type TimedPoses = Vec<(f64, Isometry3<f64>)>;

/// The tree's edges from TF messages.
fn edges<'a>(
    messages: impl Iterator<Item = TfInput<'a>>,
    header_time: &dyn Fn(i64) -> f64,
) -> BTreeMap<String, Edge> {
    let mut edges: BTreeMap<String, Edge> = BTreeMap::new();
    for (received, message, is_static) in messages {
        let RosMessage::Tf(transforms) = message else {
            continue;
        };
        for tf in transforms {
            let edge = edges.entry(tf.child_frame_id.clone()).or_default();
            edge.parent.clone_from(&tf.header.frame_id);
            edge.is_static |= is_static;
            let t = received.unwrap_or_else(|| header_time(tf.header.stamp_ns));
            edge.samples.push((t, isometry(tf)));
        }
    }
    for edge in edges.values_mut() {
        edge.samples.sort_by(|a, b| a.0.total_cmp(&b.0));
        edge.samples.dedup_by(|b, a| a.0 == b.0);
    }
    edges
}

/// `ancestor_from_frame` at `t` for the edges from a frame up to an
/// ancestor (the frame's edge first), or `None` when an edge cannot be
/// interpolated there.
fn chain_at(up: &[&Edge], t: f64, max_gap: f64) -> Option<Isometry3<f64>> {
    up.iter()
        .rev()
        .try_fold(Isometry3::identity(), |acc, edge| {
            Some(acc * edge.at(t, max_gap)?)
        })
}

/// The frames from `frame` up to the root, `frame` first.
fn ancestors(edges: &BTreeMap<String, Edge>, frame: &str) -> Vec<String> {
    let mut chain = vec![frame.to_string()];
    while let Some(edge) = edges.get(chain.last().map_or("", |s| s.as_str())) {
        if chain.contains(&edge.parent) {
            break; // a loop in a malformed tree
        }
        chain.push(edge.parent.clone());
    }
    chain
}

/// The `parent_from_child` poses of `pair` from TF messages, with
/// `header_time` turning a header stamp (ns) into import-clock seconds.
/// Returns the poses and the number of stamps where some edge could not be
/// interpolated.
///
/// # Errors
/// [`TfError`] when the two frames are not connected in the tree.
pub fn compose<'a>(
    pair: &TfPair,
    messages: impl Iterator<Item = TfInput<'a>>,
    header_time: &dyn Fn(i64) -> f64,
    max_gap_secs: f64,
) -> Result<(TimedPoses, usize), TfError> {
    let edges = edges(messages, header_time);
    let error = |detail: String| TfError {
        parent: pair.parent.clone(),
        child: pair.child.clone(),
        detail,
    };
    let frames = || {
        let mut all: Vec<&str> = edges
            .iter()
            .flat_map(|(c, e)| [c.as_str(), e.parent.as_str()])
            .collect();
        all.sort_unstable();
        all.dedup();
        all.join(", ")
    };
    let up_child = ancestors(&edges, &pair.child);
    let up_parent = ancestors(&edges, &pair.parent);
    let Some(common) = up_child.iter().find(|f| up_parent.contains(f)).cloned() else {
        return Err(error(format!(
            "they share no ancestor (the recording's frames: {})",
            frames()
        )));
    };
    // Edges (named by child frame) from the child up to the common
    // ancestor, and from the parent up to it.
    let child_side: Vec<&Edge> = up_child
        .iter()
        .take_while(|f| **f != common)
        .filter_map(|f| edges.get(f))
        .collect();
    let parent_side: Vec<&Edge> = up_parent
        .iter()
        .take_while(|f| **f != common)
        .filter_map(|f| edges.get(f))
        .collect();
    if child_side.is_empty() && parent_side.is_empty() {
        return Err(error("the parent and the child are the same frame".into()));
    }
    // The stamps: those of the dynamic edge nearest the child, else of any
    // dynamic edge; a chain of static edges gives one pose per static
    // sample time.
    let clock = child_side
        .iter()
        .chain(&parent_side)
        .find(|e| !e.is_static)
        .or_else(|| child_side.first())
        .or_else(|| parent_side.first())
        .ok_or_else(|| {
            error(format!(
                "no transform (the recording's frames: {})",
                frames()
            ))
        })?;
    let mut poses = Vec::with_capacity(clock.samples.len());
    let mut missing = 0;
    for &(t, _) in &clock.samples {
        match (
            chain_at(&child_side, t, max_gap_secs),
            chain_at(&parent_side, t, max_gap_secs),
        ) {
            (Some(from_child), Some(from_parent)) => {
                poses.push((t, from_parent.inverse() * from_child));
            }
            _ => missing += 1,
        }
    }
    Ok((poses, missing))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bags::messages::Header;

    fn tf(parent: &str, child: &str, t: f64, x: f64, yaw: f64) -> TransformStamped {
        let stamp_ns = (t * 1e9).round() as i64;
        let q = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
        TransformStamped {
            header: Header {
                stamp_ns,
                frame_id: parent.into(),
            },
            child_frame_id: child.into(),
            translation: [x, 0.0, 0.0],
            rotation: [q.i, q.j, q.k, q.w],
        }
    }

    fn pair(parent: &str, child: &str) -> TfPair {
        TfPair {
            parent: parent.into(),
            child: child.into(),
            topics: default_tf_topics(),
        }
    }

    /// `map → odom` at 1 Hz (drifting), `odom → base_link` at 10 Hz,
    /// `base_link → imu` static, `map → gps` static.
    fn tree() -> Vec<(RosMessage, bool)> {
        let mut m = Vec::new();
        for k in 0..=3 {
            let t = k as f64;
            m.push((
                RosMessage::Tf(vec![tf("map", "odom", t, 0.1 * t, 0.0)]),
                false,
            ));
        }
        for k in 0..=30 {
            let t = k as f64 * 0.1;
            m.push((
                RosMessage::Tf(vec![tf("odom", "base_link", t, t, 0.05 * t)]),
                false,
            ));
        }
        m.push((
            RosMessage::Tf(vec![tf("base_link", "imu", 0.0, 0.2, 1.0)]),
            true,
        ));
        m.push((RosMessage::Tf(vec![tf("map", "gps", 0.0, -1.0, 0.0)]), true));
        m
    }

    fn seconds(ns: i64) -> f64 {
        ns as f64 * 1e-9
    }

    fn run_with_gap(p: &TfPair, gap: f64) -> Result<(TimedPoses, usize), TfError> {
        let messages = tree();
        compose(
            p,
            messages.iter().map(|(m, s)| (None, m, *s)),
            &seconds,
            gap,
        )
    }

    fn run(p: &TfPair) -> Result<(TimedPoses, usize), TfError> {
        run_with_gap(p, 1.5)
    }

    #[test]
    fn a_chain_through_an_intermediate_frame_is_composed_at_the_child_edge_stamps() {
        let (poses, missing) = run(&pair("map", "base_link")).unwrap();
        assert_eq!((poses.len(), missing), (31, 0));
        // At 1.5 s: map→odom interpolated to x = 0.15, odom→base_link at
        // x = 1.5, yaw 0.075.
        let (t, p) = poses[15];
        assert!((t - 1.5).abs() < 1e-12);
        assert!((p.translation.vector.x - 1.65).abs() < 1e-12, "{p}");
        assert!((p.rotation.angle() - 0.075).abs() < 1e-12);
    }

    #[test]
    fn frames_on_two_branches_meet_at_their_common_ancestor() {
        // gps → imu: up to map from both sides.
        let (poses, _) = run(&pair("gps", "imu")).unwrap();
        let (t, p) = poses[10];
        let expected = tf("map", "gps", 0.0, -1.0, 0.0);
        let map_from_gps = isometry(&expected);
        let map_from_imu = Isometry3::from_parts(
            Translation3::new(0.1 * t, 0.0, 0.0),
            UnitQuaternion::identity(),
        ) * Isometry3::from_parts(
            Translation3::new(t, 0.0, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, 0.05 * t),
        ) * isometry(&tf("base_link", "imu", 0.0, 0.2, 1.0));
        let want = map_from_gps.inverse() * map_from_imu;
        assert!((p.translation.vector - want.translation.vector).norm() < 1e-12);
        assert!(p.rotation.angle_to(&want.rotation) < 1e-12);
        // The reverse direction is the inverse.
        let (back, _) = run(&pair("imu", "gps")).unwrap();
        assert!((back[10].1 * p).translation.vector.norm() < 1e-12);
    }

    #[test]
    fn unconnected_or_identical_frames_are_named_in_the_error() {
        let e = run(&pair("map", "camera")).unwrap_err().to_string();
        assert!(
            e.contains("`map` to `camera`") && e.contains("base_link, gps, imu, map, odom"),
            "{e}"
        );
        let e = run(&pair("odom", "odom")).unwrap_err().to_string();
        assert!(e.contains("same frame"), "{e}");
    }

    #[test]
    fn stamps_beyond_a_gap_of_a_slower_edge_are_counted_not_invented() {
        // map → odom every 1 s, but only 0.4 s may be bridged.
        let (poses, missing) = run_with_gap(&pair("map", "base_link"), 0.4).unwrap();
        // Only the stamps that fall on a map → odom sample survive.
        assert_eq!(poses.len(), 4);
        assert_eq!(missing, 27);
    }
}

//! The topic map: which topic plays which role in an import, and how the
//! streams are put on one clock (the `topics:` of a `kind: bags` dataset,
//! the file `gpodo import --topics` reads).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::ImportError;
use super::heading::GnssHeading;
use crate::bags::tf::TfPair;
use crate::bags::topic::TopicRequest;

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
#[serde(
    untagged,
    expecting = "a `ground_truth` of another shape, expected a pose, odometry or GNSS topic (`ground_truth: /mocap/pose`, `ground_truth: /fix`) or a TF chain (`ground_truth: {tf: {parent: map, child: base_link, topics: [/tf, /tf_static]}}`)"
)]
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

/// Which topic plays which role, and how streams are put on one clock.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TopicMap {
    /// `sensor_msgs/Imu`: gyro, specific force, and roll and pitch from its
    /// orientation. Optional: without an IMU the motion model solves the
    /// yaw rate from the wheels, takes the ground as level, and the
    /// regressors get no IMU inputs.
    #[serde(default)]
    pub imu: Option<String>,
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
    /// A rectified stereo camera (optional): the left and right image
    /// topics (`sensor_msgs/Image` mono8, bgr8 or rgb8, or
    /// `CompressedImage` PNG or JPEG) and their `CameraInfo` topics. The
    /// stamps of the pairs (left and right stamped alike) within the log
    /// become its camera frames, and `frontend: {vo: {kind: stereo}}`
    /// tracks on the images; with both camera-info topics the VO's
    /// intrinsics and baseline come from their projection matrices. Not
    /// with `vo:` (each would set the camera frames).
    #[serde(default)]
    pub camera: Option<crate::bags::images::CameraTopics>,
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
    /// Skip damaged MCAP chunks (a CRC that disagrees with the data, an
    /// unreadable record) and import the rest, reporting the messages and
    /// seconds lost (default `false`: damage stops the import).
    #[serde(default)]
    pub skip_damaged: bool,
}

impl TopicMap {
    /// The map's settings that need no bag to check.
    pub(super) fn check(&self) -> Result<(), ImportError> {
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            return Err(ImportError::Map(
                "`rate_hz` must be a positive number".into(),
            ));
        }
        if !(self.max_gap_secs.is_finite() && self.max_gap_secs > 0.0) {
            return Err(ImportError::Map(
                "`max_gap_secs` must be a positive number of seconds".into(),
            ));
        }
        if self.imu.is_none() && self.gnss_heading == GnssHeading::Imu {
            return Err(ImportError::Map(
                "`gnss_heading: imu` needs an `imu` topic; without one, use `gnss_heading: course`"
                    .into(),
            ));
        }
        if self.camera.is_some() && self.vo.is_some() {
            return Err(ImportError::Map(
                "give `vo:` (a recorded VO to replay) or `camera:` (images for the stereo VO), not both: each sets the camera frames".into(),
            ));
        }
        Ok(())
    }

    /// Every role's topic, to be read in one pass over the bag, in the order
    /// [`super::import_bag`] takes them back: IMU, ground truth, odometry, VO,
    /// joints.
    pub(super) fn topic_requests(&self) -> Result<Vec<TopicRequest<'_>>, ImportError> {
        let mut requests = Vec::new();
        if let Some(topic) = &self.imu {
            requests.push(TopicRequest {
                topic,
                role: "imu",
                expected: &["sensor_msgs/Imu"],
                optional: false,
            });
        }
        match &self.ground_truth {
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
        if let Some(topic) = &self.odometry {
            requests.push(TopicRequest {
                topic,
                role: "odometry",
                expected: &["nav_msgs/Odometry", "geometry_msgs/TwistStamped"],
                optional: false,
            });
        }
        if let Some(topic) = &self.vo {
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
        if let Some(j) = &self.joints {
            requests.push(TopicRequest {
                topic: &j.topic,
                role: "joints",
                expected: &["sensor_msgs/JointState"],
                optional: false,
            });
        }
        Ok(requests)
    }
}

//! The gate's topics: the stereo camera's four it pairs, the VO's
//! odometry it learns from, and what it publishes.

use serde::{Deserialize, Serialize};

use super::pairing::Part;

/// The gate's topics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GateTopics {
    /// The left camera's images.
    pub left_image: String,
    /// The right camera's images.
    pub right_image: String,
    /// The left camera's info.
    pub left_info: String,
    /// The right camera's info.
    pub right_info: String,
    /// The VO's `nav_msgs/Odometry`.
    pub vo_odometry: String,
    /// Forwarded pairs go to the same topics under this prefix
    /// (`/stereo/left/image_raw` as `/gated/stereo/left/image_raw`, …),
    /// reliable.
    pub gated_prefix: String,
    /// Every decision, as `diagnostic_msgs/DiagnosticStatus` key-values.
    pub decisions: String,
}

impl Default for GateTopics {
    fn default() -> Self {
        Self {
            left_image: "/left/image_raw".into(),
            right_image: "/right/image_raw".into(),
            left_info: "/left/camera_info".into(),
            right_info: "/right/camera_info".into(),
            vo_odometry: "/vo/odometry".into(),
            gated_prefix: "/gated".into(),
            decisions: "/gpodo/gate/decisions".into(),
        }
    }
}

impl GateTopics {
    /// The topic a part is read from.
    pub fn input(&self, part: Part) -> &str {
        match part {
            Part::LeftImage => &self.left_image,
            Part::RightImage => &self.right_image,
            Part::LeftInfo => &self.left_info,
            Part::RightInfo => &self.right_info,
        }
    }

    /// The topic a forwarded part is republished on: its input topic
    /// under the prefix.
    pub fn gated(&self, part: Part) -> String {
        format!(
            "{}/{}",
            self.gated_prefix.trim_end_matches('/'),
            self.input(part).trim_start_matches('/')
        )
    }
}

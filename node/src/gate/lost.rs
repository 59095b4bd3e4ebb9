//! Whether the visual odometry behind the gate is lost, from what any
//! stereo VO publishes:
//! * its odometry goes silent: no pose for a pair the gate forwarded
//!   within `silent_secs` (the VO publishes only for the pairs it is given,
//!   so silence counts from a forwarded pair, not from the last pose);
//! * its pose covariance at or above `covariance_at_least` (rtabmap
//!   publishes 9999 when lost);
//! * a null pose: an all-zero orientation quaternion (rtabmap's pose when
//!   lost);
//! * a `std_msgs/Bool` topic saying so (isaac_ros_visual_slam keeps
//!   publishing a low covariance when lost: its tracking status must be
//!   wired to this topic).
//!
//! The VO is lost from any of these until a pose arrives that is none of
//! them; what the Bool topic says holds until it says otherwise (a VO
//! that keeps publishing while lost does not clear it).

/// When the VO counts as lost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LostSettings {
    /// No pose this long after a forwarded pair (s; default 1; `None`:
    /// silence is not a loss).
    pub silent_secs: Option<f64>,
    /// A pose whose largest position variance is at least this (m²;
    /// default 9999, rtabmap's; `None`: not read).
    pub covariance_at_least: Option<f64>,
}

impl Default for LostSettings {
    fn default() -> Self {
        Self {
            silent_secs: Some(1.0),
            covariance_at_least: Some(9999.0),
        }
    }
}

/// Why the VO counts as lost.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LostReason {
    /// No pose for a forwarded pair within the silence limit.
    Silent,
    /// Its covariance at or above the limit.
    Covariance,
    /// A null pose.
    NullPose,
    /// The Bool topic says so.
    Reported,
}

impl LostReason {
    /// As the decisions and diagnostics name it.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Silent => "vo silent",
            Self::Covariance => "vo covariance",
            Self::NullPose => "vo null pose",
            Self::Reported => "vo reported lost",
        }
    }
}

/// What one VO pose says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoseVerdict {
    /// A pose to use.
    Tracked,
    /// The VO says it is lost.
    Lost(LostReason),
}

/// Follows the VO's state.
#[derive(Debug, Clone)]
pub struct LostDetector {
    settings: LostSettings,
    /// Since when (s, the node's clock) a forwarded pair waits for a pose.
    waiting_since: Option<f64>,
    /// What the last pose said.
    pose_lost: Option<LostReason>,
    /// What the Bool topic said last.
    reported_lost: bool,
}

impl LostDetector {
    /// Tracking, nothing forwarded yet.
    pub fn new(settings: LostSettings) -> Self {
        Self {
            settings,
            waiting_since: None,
            pose_lost: None,
            reported_lost: false,
        }
    }

    /// A pair was forwarded to the VO at `now_secs` (the node's clock).
    pub fn forwarded(&mut self, now_secs: f64) {
        self.waiting_since.get_or_insert(now_secs);
    }

    /// A pose arrived: its orientation quaternion as received (x, y, z,
    /// w) and its position variances.
    pub fn pose(&mut self, quaternion_xyzw: [f64; 4], position_variances: [f64; 3]) -> PoseVerdict {
        self.waiting_since = None;
        let verdict = if quaternion_xyzw.iter().all(|&q| q == 0.0) {
            PoseVerdict::Lost(LostReason::NullPose)
        } else if self
            .settings
            .covariance_at_least
            .is_some_and(|limit| position_variances.iter().any(|v| v.is_nan() || *v >= limit))
        {
            PoseVerdict::Lost(LostReason::Covariance)
        } else {
            PoseVerdict::Tracked
        };
        self.pose_lost = match verdict {
            PoseVerdict::Lost(reason) => Some(reason),
            PoseVerdict::Tracked => None,
        };
        verdict
    }

    /// The Bool topic said the VO is lost (`true`) or tracking.
    pub fn reported(&mut self, lost: bool) {
        self.reported_lost = lost;
    }

    /// Whether the VO is lost at `now_secs`, and why.
    pub fn lost(&self, now_secs: f64) -> Option<LostReason> {
        if self.reported_lost {
            return Some(LostReason::Reported);
        }
        if let Some(reason) = self.pose_lost {
            return Some(reason);
        }
        match (self.waiting_since, self.settings.silent_secs) {
            (Some(since), Some(limit)) if now_secs - since >= limit => Some(LostReason::Silent),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const IDENTITY: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

    #[test]
    fn silence_counts_from_a_forwarded_pair_not_from_the_last_pose() {
        let mut d = LostDetector::new(LostSettings::default());
        // No pair forwarded for 10 s: not lost.
        assert_eq!(d.lost(10.0), None);
        d.forwarded(10.0);
        d.forwarded(10.4);
        assert_eq!(d.lost(10.9), None);
        assert_eq!(d.lost(11.0), Some(LostReason::Silent));
        assert_eq!(d.pose(IDENTITY, [1e-4; 3]), PoseVerdict::Tracked);
        assert_eq!(d.lost(11.0), None);
    }

    #[test]
    fn a_null_pose_or_a_large_covariance_is_lost_until_a_good_pose() {
        let mut d = LostDetector::new(LostSettings::default());
        assert_eq!(
            d.pose([0.0; 4], [1e-4; 3]),
            PoseVerdict::Lost(LostReason::NullPose)
        );
        assert_eq!(d.lost(0.0), Some(LostReason::NullPose));
        assert_eq!(
            d.pose(IDENTITY, [1e-4, 9999.0, 1e-4]),
            PoseVerdict::Lost(LostReason::Covariance)
        );
        assert_eq!(d.lost(0.0), Some(LostReason::Covariance));
        assert_eq!(d.pose(IDENTITY, [1e-4; 3]), PoseVerdict::Tracked);
        assert_eq!(d.lost(0.0), None);
    }

    #[test]
    fn the_bool_topic_holds_until_it_says_otherwise() {
        let mut d = LostDetector::new(LostSettings {
            silent_secs: None,
            covariance_at_least: None,
        });
        d.reported(true);
        // Isaac keeps publishing low covariances while lost.
        assert_eq!(d.lost(0.0), Some(LostReason::Reported));
        d.reported(false);
        assert_eq!(d.lost(0.0), None);
        d.reported(true);
        d.forwarded(0.0);
        assert_eq!(d.lost(100.0), Some(LostReason::Reported));
        // A pose with a low covariance while the status says lost.
        assert_eq!(d.pose(IDENTITY, [1e-6; 3]), PoseVerdict::Tracked);
        assert_eq!(d.lost(100.0), Some(LostReason::Reported));
        d.reported(false);
        assert_eq!(d.lost(100.0), None);
    }
}

//! The manoeuvres of the simulated rover and the parameters of its driver
//! (the driver itself is [`crate::sim::driver`]).
//!
//! ExoTeR has four steerable corner wheels and two fixed middle wheels, so
//! every feasible motion has its instantaneous centre of rotation on the
//! middle-axle line (the body `y` axis): straight driving, Ackermann arcs
//! (centre at `(0, R)`, `|R| ≥ 0.6 m`), turns on the spot (centre at the
//! origin) and point turns about a middle wheel (centre at `(0, ±0.28 m)`,
//! the ExoTeR-like rover's middle wheels).
//! Rotating at `ω` about a centre `(0, y_c)` moves the body origin at
//! `v_x = ω·y_c`. [`DriveCommand`]'s constructors build exactly these twists.
//!
//! [`Driver`](crate::sim::driver::Driver) is a small state machine called at every sensor step with the
//! rover's true planar pose. It runs in one of two modes:
//! - **training** ([`Driver::training`](crate::sim::driver::Driver::training)): the remote-driving sessions of paper
//!   §V — random manoeuvres (forward, backward, Ackermann, turn on the spot,
//!   point turn) of 5–40 s, with short stops in between so the rover moves
//!   about 70% of the time; within `edge_margin_m` of the area's edge it turns
//!   on the spot towards the centre and drives back in;
//! - **waypoint following** ([`Driver::follow`](crate::sim::driver::Driver::follow)): turns on the spot to face
//!   the next waypoint, then drives forward with Ackermann corrections, e.g.
//!   along [`test_traverse_waypoints`], the ≈ 42 m test run of paper §V-B.
//!
//! Everything is deterministic given the random-number generator.

use std::f64::consts::PI;

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::TestbedError;
use crate::error::require;

/// Curvatures below this (1/m) are driven as [`ManoeuvreKind::Straight`].
pub(crate) const STRAIGHT_CURVATURE_PER_M: f64 = 0.02;
/// Waypoints of the test traverse for a 9 m area (scaled with the area).
const TEST_TRAVERSE_9M: [(f64, f64); 9] = [
    (1.4, 1.4),
    (7.6, 7.6),
    (7.6, 4.5),
    (1.4, 4.5),
    (1.4, 7.6),
    (7.6, 1.4),
    (4.5, 1.4),
    (4.5, 7.6),
    (7.6, 7.6),
];

/// A planar body twist: the body-frame velocity of the body origin and the
/// yaw rate (body `x` forward, `y` left, `z` up).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PlanarTwist {
    /// Forward velocity, m/s.
    pub vx_mps: f64,
    /// Leftward velocity, m/s.
    pub vy_mps: f64,
    /// Yaw rate about body `z`, rad/s (positive turns left).
    pub wz_radps: f64,
}

impl PlanarTwist {
    /// No motion.
    pub const ZERO: Self = Self::new(0.0, 0.0, 0.0);

    /// A twist from its three components.
    pub const fn new(vx_mps: f64, vy_mps: f64, wz_radps: f64) -> Self {
        Self {
            vx_mps,
            vy_mps,
            wz_radps,
        }
    }

    /// Translational speed `sqrt(vx² + vy²)`, m/s.
    pub fn speed_mps(&self) -> f64 {
        self.vx_mps.hypot(self.vy_mps)
    }

    /// Whether all three components are exactly zero.
    pub fn is_zero(&self) -> bool {
        self.vx_mps == 0.0 && self.vy_mps == 0.0 && self.wz_radps == 0.0
    }
}

/// The manoeuvre classes an ExoTeR-like rover can drive.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ManoeuvreKind {
    /// Straight forward or backward.
    Straight,
    /// An arc about a centre on the middle-axle line, `|radius| ≥ 0.6 m`.
    Ackermann,
    /// Rotation about the body origin.
    TurnOnSpot,
    /// Rotation about one middle wheel.
    PointTurn,
    /// Standing still.
    #[default]
    Stop,
}

impl ManoeuvreKind {
    /// Whether the wheels turn in this manoeuvre (everything but `Stop`).
    pub fn is_moving(self) -> bool {
        self != Self::Stop
    }
}

/// A commanded manoeuvre and its slip-free twist.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DriveCommand {
    /// The manoeuvre class.
    pub kind: ManoeuvreKind,
    /// The body twist the wheel speeds produce without slip.
    pub twist: PlanarTwist,
}

impl DriveCommand {
    /// Standing still.
    pub const STOP: Self = Self {
        kind: ManoeuvreKind::Stop,
        twist: PlanarTwist::ZERO,
    };

    /// Straight at `vx_mps` (negative = backward).
    pub fn straight(vx_mps: f64) -> Self {
        Self::new(ManoeuvreKind::Straight, vx_mps, 0.0)
    }

    /// An Ackermann arc at forward speed `vx_mps` about the centre
    /// `(0, radius_m)` (positive radius turns left): `wz = vx / radius`.
    pub fn ackermann(vx_mps: f64, radius_m: f64) -> Self {
        Self::new(ManoeuvreKind::Ackermann, vx_mps, vx_mps / radius_m)
    }

    /// A turn on the spot at `wz_radps` (positive = left).
    pub fn turn_on_spot(wz_radps: f64) -> Self {
        Self::new(ManoeuvreKind::TurnOnSpot, 0.0, wz_radps)
    }

    /// A rotation at `wz_radps` about the middle wheel at `(0, centre_y_m)`:
    /// `vx = wz·centre_y`.
    pub fn point_turn(wz_radps: f64, centre_y_m: f64) -> Self {
        Self::new(ManoeuvreKind::PointTurn, wz_radps * centre_y_m, wz_radps)
    }

    fn new(kind: ManoeuvreKind, vx_mps: f64, wz_radps: f64) -> Self {
        Self {
            kind,
            twist: PlanarTwist::new(vx_mps, 0.0, wz_radps),
        }
    }
}

/// One manoeuvre of the training script: a command held for a duration.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// The manoeuvre class.
    pub kind: ManoeuvreKind,
    /// How long the command is held, seconds.
    pub duration_secs: f64,
    /// The commanded slip-free body twist.
    pub twist: PlanarTwist,
}

/// A planar pose in the world frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PlanarPose {
    /// World `x` of the body origin, metres.
    pub x_m: f64,
    /// World `y` of the body origin, metres.
    pub y_m: f64,
    /// Heading of body `x` from world `x`, rad (counter-clockwise).
    pub yaw_rad: f64,
}

impl From<(f64, f64, f64)> for PlanarPose {
    fn from((x_m, y_m, yaw_rad): (f64, f64, f64)) -> Self {
        Self { x_m, y_m, yaw_rad }
    }
}

impl PlanarPose {
    pub(crate) fn position(&self) -> Vector2<f64> {
        Vector2::new(self.x_m, self.y_m)
    }
}

/// Relative frequencies of the moving manoeuvres the training driver picks
/// (the real training set is mostly forward driving: 97% of its moving
/// seconds).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ManoeuvreWeights {
    /// Straight forward. Default 0.45.
    pub forward: f64,
    /// Straight backward. Default 0.05.
    pub backward: f64,
    /// Ackermann arcs, left or right. Default 0.25.
    pub ackermann: f64,
    /// Turns on the spot, left or right. Default 0.15.
    pub turn_on_spot: f64,
    /// Point turns about either middle wheel. Default 0.10.
    pub point_turn: f64,
}

impl Default for ManoeuvreWeights {
    fn default() -> Self {
        Self {
            forward: 0.45,
            backward: 0.05,
            ackermann: 0.25,
            turn_on_spot: 0.15,
            point_turn: 0.10,
        }
    }
}

impl ManoeuvreWeights {
    pub(crate) fn as_array(&self) -> [f64; 5] {
        [
            self.forward,
            self.backward,
            self.ackermann,
            self.turn_on_spot,
            self.point_turn,
        ]
    }
}

/// How the driver drives; read from configs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DriverParams {
    /// Nominal driving speed, m/s. Default 0.04 (paper: ≈ 4 cm/s).
    pub speed_mps: f64,
    /// Relative spread of speed and turn rate between training segments: each
    /// is drawn uniformly within `±spread` of nominal. Default 0.25.
    pub speed_spread: f64,
    /// Nominal yaw rate of turns on the spot and point turns, rad/s.
    /// Default 0.1.
    pub turn_rate_radps: f64,
    /// Smallest Ackermann radius, metres. Default 0.6.
    pub min_ackermann_radius_m: f64,
    /// Largest Ackermann radius of random training arcs, metres. Default 3.0.
    pub max_ackermann_radius_m: f64,
    /// Lateral offset of the middle wheels (point-turn centres), metres.
    /// Default 0.28 (the ExoTeR-like rover's middle wheels).
    pub point_turn_offset_m: f64,
    /// Shortest moving training segment, seconds. Default 5.
    pub min_segment_secs: f64,
    /// Longest moving training segment, seconds. Default 40.
    pub max_segment_secs: f64,
    /// Shortest stop, seconds. Default 3.
    pub min_stop_secs: f64,
    /// Longest stop, seconds. Default 15.
    pub max_stop_secs: f64,
    /// Share of training time spent in random stops, in [0, 1). The per-segment
    /// stop probability is derived from it and the mean durations. Default 0.35.
    pub stop_time_fraction: f64,
    /// Relative frequencies of the moving manoeuvres.
    pub weights: ManoeuvreWeights,
    /// Distance from the area's edge within which the training driver stops
    /// moving outwards and returns, metres. Default 1.0.
    pub edge_margin_m: f64,
    /// How far beyond the margin the driver drives back in before resuming
    /// random manoeuvres, metres. Default 1.0.
    pub retreat_m: f64,
    /// Distance at which a waypoint counts as reached, metres. Default 0.05.
    pub waypoint_tolerance_m: f64,
    /// Heading error above which the driver stops and turns on the spot, rad.
    /// Default 0.35.
    pub align_start_rad: f64,
    /// Heading error at which a turn on the spot ends, rad. Default 0.05.
    pub align_stop_rad: f64,
    /// Path curvature commanded per radian of heading error, 1/m. Default 2.0.
    pub steering_gain_per_m: f64,
}

impl Default for DriverParams {
    fn default() -> Self {
        Self {
            speed_mps: 0.04,
            speed_spread: 0.25,
            turn_rate_radps: 0.1,
            min_ackermann_radius_m: 0.6,
            max_ackermann_radius_m: 3.0,
            point_turn_offset_m: 0.28,
            min_segment_secs: 5.0,
            max_segment_secs: 40.0,
            min_stop_secs: 3.0,
            max_stop_secs: 15.0,
            stop_time_fraction: 0.35,
            weights: ManoeuvreWeights::default(),
            edge_margin_m: 1.0,
            retreat_m: 1.0,
            waypoint_tolerance_m: 0.05,
            align_start_rad: 0.35,
            align_stop_rad: 0.05,
            steering_gain_per_m: 2.0,
        }
    }
}

impl DriverParams {
    /// Checks every field, naming the first bad one.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`].
    pub fn validate(&self) -> Result<(), TestbedError> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        let w = &self.weights;
        let checks = [
            (
                "speed_mps",
                positive(self.speed_mps) && self.speed_mps <= 1.0,
                "a value in (0, 1]",
            ),
            (
                "speed_spread",
                non_negative(self.speed_spread) && self.speed_spread < 1.0,
                "a value in [0, 1)",
            ),
            (
                "turn_rate_radps",
                positive(self.turn_rate_radps) && self.turn_rate_radps <= 2.0,
                "a value in (0, 2]",
            ),
            (
                "min_ackermann_radius_m",
                positive(self.min_ackermann_radius_m),
                "a finite value > 0",
            ),
            (
                "max_ackermann_radius_m",
                self.max_ackermann_radius_m.is_finite()
                    && self.max_ackermann_radius_m >= self.min_ackermann_radius_m,
                "a finite value >= min_ackermann_radius_m",
            ),
            (
                "point_turn_offset_m",
                positive(self.point_turn_offset_m),
                "a finite value > 0",
            ),
            (
                "min_segment_secs",
                positive(self.min_segment_secs),
                "a finite value > 0",
            ),
            (
                "max_segment_secs",
                self.max_segment_secs.is_finite() && self.max_segment_secs >= self.min_segment_secs,
                "a finite value >= min_segment_secs",
            ),
            (
                "min_stop_secs",
                positive(self.min_stop_secs),
                "a finite value > 0",
            ),
            (
                "max_stop_secs",
                self.max_stop_secs.is_finite() && self.max_stop_secs >= self.min_stop_secs,
                "a finite value >= min_stop_secs",
            ),
            (
                "stop_time_fraction",
                non_negative(self.stop_time_fraction) && self.stop_time_fraction < 1.0,
                "a value in [0, 1)",
            ),
            (
                "weights",
                w.as_array().iter().all(|&v| non_negative(v))
                    && w.as_array().iter().sum::<f64>() > 0.0,
                "finite weights >= 0 with a positive sum",
            ),
            (
                "edge_margin_m",
                non_negative(self.edge_margin_m),
                "a finite value >= 0",
            ),
            (
                "retreat_m",
                non_negative(self.retreat_m),
                "a finite value >= 0",
            ),
            (
                "waypoint_tolerance_m",
                positive(self.waypoint_tolerance_m),
                "a finite value > 0",
            ),
            (
                "align_start_rad",
                positive(self.align_start_rad) && self.align_start_rad < PI,
                "a value in (0, π)",
            ),
            (
                "align_stop_rad",
                positive(self.align_stop_rad) && self.align_stop_rad < self.align_start_rad,
                "a value in (0, align_start_rad)",
            ),
            (
                "steering_gain_per_m",
                positive(self.steering_gain_per_m),
                "a finite value > 0",
            ),
        ];
        for (field, ok, expected) in checks {
            require(ok, field, expected)?;
        }
        Ok(())
    }

    /// Probability that a training segment is a stop, such that stops take
    /// `stop_time_fraction` of the time: `p = f·M / (f·M + (1 − f)·S)` with
    /// `M`, `S` the mean moving and stop durations.
    pub(crate) fn stop_probability(&self) -> f64 {
        let f = self.stop_time_fraction;
        let moving = 0.5 * (self.min_segment_secs + self.max_segment_secs);
        let stop = 0.5 * (self.min_stop_secs + self.max_stop_secs);
        f * moving / (f * moving + (1.0 - f) * stop)
    }
}

/// The waypoints of the fixed test traverse for an area of side
/// `area_size_m`: the two diagonals, the two mid-lines and four half-sides of
/// a square 1.4 m (scaled) inside the edges, crossing the middle of the area
/// (where the hills are) four times. Polyline length 42.34 m at 9 m (paper §V-B:
/// 42.35 m), scaling with the area. Independent of any seed.
pub fn test_traverse_waypoints(area_size_m: f64) -> Vec<(f64, f64)> {
    let scale = area_size_m / 9.0;
    TEST_TRAVERSE_9M
        .iter()
        .map(|&(x, y)| (scale * x, scale * y))
        .collect()
}

/// Where the test traverse starts: on its first waypoint, facing the second.
pub fn test_traverse_start_pose(area_size_m: f64) -> PlanarPose {
    let points = test_traverse_waypoints(area_size_m);
    let ((x0, y0), (x1, y1)) = (points[0], points[1]);
    PlanarPose {
        x_m: x0,
        y_m: y0,
        yaw_rad: (y1 - y0).atan2(x1 - x0),
    }
}

#[cfg(test)]
mod tests;

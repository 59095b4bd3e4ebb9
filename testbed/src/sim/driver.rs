//! The driver of the simulated rover: a small state machine that, every
//! sensor step, commands the manoeuvre of [`crate::sim::manoeuvre`] to
//! perform: random training segments that keep the rover inside the area,
//! or a waypoint route (the test traverse).

use std::f64::consts::{PI, TAU};

use nalgebra::Vector2;
use rand::Rng;

use crate::TestbedError;
use crate::error::require;
use crate::sim::manoeuvre::{
    DriveCommand, DriverParams, ManoeuvreWeights, PlanarPose, PlanarTwist,
    STRAIGHT_CURVATURE_PER_M, Segment,
};

/// Steers towards a target: turn on the spot while the heading error is
/// large (with hysteresis), otherwise drive forward on a corrective arc.
#[derive(Clone, Debug, Default, PartialEq)]
struct Pursuit {
    aligning: bool,
}

impl Pursuit {
    fn steer(
        &mut self,
        params: &DriverParams,
        pose: &PlanarPose,
        target: Vector2<f64>,
    ) -> DriveCommand {
        let to_target = target - pose.position();
        let error = wrap_angle(to_target.y.atan2(to_target.x) - pose.yaw_rad);
        if self.aligning && error.abs() <= params.align_stop_rad {
            self.aligning = false;
        } else if !self.aligning && error.abs() > params.align_start_rad {
            self.aligning = true;
        }
        if self.aligning {
            return DriveCommand::turn_on_spot(params.turn_rate_radps.copysign(error));
        }
        let max_curvature = 1.0 / params.min_ackermann_radius_m;
        let curvature = (params.steering_gain_per_m * error).clamp(-max_curvature, max_curvature);
        if curvature.abs() < STRAIGHT_CURVATURE_PER_M {
            DriveCommand::straight(params.speed_mps)
        } else {
            DriveCommand::ackermann(params.speed_mps, 1.0 / curvature)
        }
    }
}

/// State of the random training driver.
#[derive(Clone, Debug, PartialEq)]
struct Training {
    area_size_m: f64,
    segment: Option<Segment>,
    segment_end_secs: f64,
    retreat: Option<Pursuit>,
}

impl Training {
    fn command<R: Rng + ?Sized>(
        &mut self,
        params: &DriverParams,
        pose: &PlanarPose,
        time_secs: f64,
        rng: &mut R,
    ) -> DriveCommand {
        let centre = Vector2::repeat(self.area_size_m / 2.0);
        if let Some(pursuit) = &mut self.retreat {
            if edge_distance(pose, self.area_size_m) < params.edge_margin_m + params.retreat_m {
                return pursuit.steer(params, pose, centre);
            }
            self.retreat = None;
            self.segment = None;
        }
        let segment = match self.segment {
            Some(segment) if time_secs < self.segment_end_secs => segment,
            _ => {
                let segment = random_segment(params, rng);
                self.segment = Some(segment);
                self.segment_end_secs = time_secs + segment.duration_secs;
                segment
            }
        };
        if heads_out_of_margin(pose, &segment.twist, self.area_size_m, params.edge_margin_m) {
            let mut pursuit = Pursuit::default();
            let command = pursuit.steer(params, pose, centre);
            self.retreat = Some(pursuit);
            return command;
        }
        DriveCommand {
            kind: segment.kind,
            twist: segment.twist,
        }
    }
}

/// State of the waypoint follower.
#[derive(Clone, Debug, PartialEq)]
struct Following {
    waypoints: Vec<Vector2<f64>>,
    next: usize,
    pursuit: Pursuit,
}

impl Following {
    fn command(&mut self, params: &DriverParams, pose: &PlanarPose) -> DriveCommand {
        while let Some(&target) = self.waypoints.get(self.next) {
            if (target - pose.position()).norm() > params.waypoint_tolerance_m {
                return self.pursuit.steer(params, pose, target);
            }
            self.next += 1;
        }
        DriveCommand::STOP
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Mode {
    Training(Training),
    Following(Following),
}

/// The rover's driver: call [`Driver::command`] at every sensor step.
#[derive(Clone, Debug, PartialEq)]
pub struct Driver {
    params: DriverParams,
    mode: Mode,
}

impl Driver {
    /// A random training driver that keeps the rover inside the square
    /// `[0, area_size_m]²`.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] when `params` is invalid or the area
    /// is too small for the margins (`area_size_m` must exceed
    /// `2·(edge_margin_m + retreat_m) + 1`).
    pub fn training(params: DriverParams, area_size_m: f64) -> Result<Self, TestbedError> {
        params.validate()?;
        require(
            area_size_m.is_finite()
                && area_size_m > 2.0 * (params.edge_margin_m + params.retreat_m) + 1.0,
            "area_size_m",
            "a finite value > 2·(edge_margin_m + retreat_m) + 1",
        )?;
        let training = Training {
            area_size_m,
            segment: None,
            segment_end_secs: 0.0,
            retreat: None,
        };
        Ok(Self {
            params,
            mode: Mode::Training(training),
        })
    }

    /// A driver that visits `waypoints` (world `(x, y)`, metres) in order and
    /// then stops for good ([`Driver::done`]).
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] when `params` is invalid or naming
    /// `waypoints` when it is empty or holds a non-finite coordinate.
    pub fn follow(params: DriverParams, waypoints: &[(f64, f64)]) -> Result<Self, TestbedError> {
        params.validate()?;
        require(
            !waypoints.is_empty()
                && waypoints
                    .iter()
                    .all(|(x, y)| x.is_finite() && y.is_finite()),
            "waypoints",
            "a non-empty list of finite (x, y) points",
        )?;
        let following = Following {
            waypoints: waypoints.iter().map(|&(x, y)| Vector2::new(x, y)).collect(),
            next: 0,
            pursuit: Pursuit::default(),
        };
        Ok(Self {
            params,
            mode: Mode::Following(following),
        })
    }

    /// The command for this step, given the rover's true planar pose and the
    /// simulation time. Draws from `rng` only when a training segment starts.
    pub fn command<R: Rng + ?Sized>(
        &mut self,
        pose: impl Into<PlanarPose>,
        time_secs: f64,
        rng: &mut R,
    ) -> DriveCommand {
        let pose = pose.into();
        match &mut self.mode {
            Mode::Training(training) => training.command(&self.params, &pose, time_secs, rng),
            Mode::Following(following) => following.command(&self.params, &pose),
        }
    }

    /// Whether a waypoint follower has reached its last waypoint (always
    /// `false` for a training driver).
    pub fn done(&self) -> bool {
        match &self.mode {
            Mode::Training(_) => false,
            Mode::Following(following) => following.next >= following.waypoints.len(),
        }
    }

    /// The current random training segment, if any (`None` while returning
    /// from the edge and for a waypoint follower).
    pub fn current_segment(&self) -> Option<&Segment> {
        match &self.mode {
            Mode::Training(training) if training.retreat.is_none() => training.segment.as_ref(),
            _ => None,
        }
    }

    /// The driver's parameters.
    pub fn params(&self) -> &DriverParams {
        &self.params
    }
}

/// The moving manoeuvres, in the order of [`ManoeuvreWeights::as_array`].
#[derive(Clone, Copy)]
enum Choice {
    Forward,
    Backward,
    Ackermann,
    TurnOnSpot,
    PointTurn,
}

fn random_segment<R: Rng + ?Sized>(params: &DriverParams, rng: &mut R) -> Segment {
    if rng.random::<f64>() < params.stop_probability() {
        let duration_secs = uniform(rng, params.min_stop_secs, params.max_stop_secs);
        return to_segment(DriveCommand::STOP, duration_secs);
    }
    let duration_secs = uniform(rng, params.min_segment_secs, params.max_segment_secs);
    let jitter = |rng: &mut R| 1.0 + params.speed_spread * uniform(rng, -1.0, 1.0);
    let speed = params.speed_mps * jitter(rng);
    let rate = params.turn_rate_radps * jitter(rng) * random_sign(rng);
    let command = match pick(&params.weights, rng) {
        Choice::Forward => DriveCommand::straight(speed),
        Choice::Backward => DriveCommand::straight(-speed),
        Choice::Ackermann => {
            let radius = uniform(
                rng,
                params.min_ackermann_radius_m,
                params.max_ackermann_radius_m,
            );
            DriveCommand::ackermann(speed, radius * random_sign(rng))
        }
        Choice::TurnOnSpot => DriveCommand::turn_on_spot(rate),
        Choice::PointTurn => {
            DriveCommand::point_turn(rate, params.point_turn_offset_m * random_sign(rng))
        }
    };
    to_segment(command, duration_secs)
}

fn to_segment(command: DriveCommand, duration_secs: f64) -> Segment {
    Segment {
        kind: command.kind,
        duration_secs,
        twist: command.twist,
    }
}

fn pick<R: Rng + ?Sized>(weights: &ManoeuvreWeights, rng: &mut R) -> Choice {
    const CHOICES: [Choice; 5] = [
        Choice::Forward,
        Choice::Backward,
        Choice::Ackermann,
        Choice::TurnOnSpot,
        Choice::PointTurn,
    ];
    let weights = weights.as_array();
    let mut remaining = rng.random::<f64>() * weights.iter().sum::<f64>();
    for (choice, weight) in CHOICES.into_iter().zip(weights) {
        if remaining < weight {
            return choice;
        }
        remaining -= weight;
    }
    Choice::Forward
}

/// Whether the body origin is within `margin` of an edge and the twist moves
/// it further towards that edge.
fn heads_out_of_margin(
    pose: &PlanarPose,
    twist: &PlanarTwist,
    area_size_m: f64,
    margin: f64,
) -> bool {
    let (sin, cos) = pose.yaw_rad.sin_cos();
    let velocity = [
        cos * twist.vx_mps - sin * twist.vy_mps,
        sin * twist.vx_mps + cos * twist.vy_mps,
    ];
    [pose.x_m, pose.y_m]
        .into_iter()
        .zip(velocity)
        .any(|(p, v)| (p < margin && v < 0.0) || (p > area_size_m - margin && v > 0.0))
}

/// Distance from the body origin to the nearest edge of the area (negative
/// outside).
fn edge_distance(pose: &PlanarPose, area_size_m: f64) -> f64 {
    [
        pose.x_m,
        pose.y_m,
        area_size_m - pose.x_m,
        area_size_m - pose.y_m,
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min)
}

fn wrap_angle(angle_rad: f64) -> f64 {
    (angle_rad + PI).rem_euclid(TAU) - PI
}

fn random_sign<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    if rng.random::<bool>() { 1.0 } else { -1.0 }
}

fn uniform<R: Rng + ?Sized>(rng: &mut R, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

//! Wheel slip: how slope, soil, load and manoeuvre turn the commanded body
//! twist into the twist the rover actually makes.
//!
//! This is the physical origin of the odometry residual `f` of paper eq. (12):
//! the parametric model integrates the commanded (wheel-encoder) twist, the
//! ground truth sees the actual one. The model is a pure function of its
//! inputs ([`SlipModel::apply`]); its randomness comes in as a correlated noise
//! sample ([`SlipNoise`], drawn by the caller from [`SlipNoiseProcess`]).
//!
//! With `d` the unit motion direction in the body plane, `l = z × d`, `g` the
//! unit gravity direction in the body frame and `u = |v| + lever·|ω|` the
//! ground speed scale:
//! - **longitudinal slip** `s = base + gain·(e^{k·θ} − 1)` for an uphill angle
//!   `θ = asin(−g·d) ≥ 0` (terramechanics-like, steep on sand); downhill the
//!   base fades and the rover skids ahead of its wheels,
//!   `s = base·e^{k·θ} − downhill_skid_factor·gain·(1 − e^{k·θ})` (`θ < 0`);
//!   plus `cross_slope_factor·gain·(e^{k·|φ|} − 1)` for the cross-slope angle
//!   `φ = asin(−g·l)`, `load_slip_gain·imbalance` and
//!   `slip_noise_std·n_long`, all clamped to `[min_slip, max_slip]`; the
//!   velocity along the command becomes `(1 − s)·v`;
//! - **downhill drift** `lateral_scale·lateral_gain·u·[(g·l)·l + (1 − |v|/u)·(g·d)·d]`:
//!   sideways on a cross slope while driving, straight down the slope while
//!   turning on the spot; plus `lateral_noise_ratio·u·n_lat` along `l` and a
//!   scrub `slip_noise_std·lever·|ω|·n_long` along `d`;
//! - **turn slip** `s_ψ = turn_slip·factor(kind) + load_slip_gain·imbalance +
//!   turn_slip_noise_std·n_yaw`, clamped to `[0, max_turn_slip]`; the yaw rate
//!   becomes `(1 − s_ψ)·ω + yaw_noise_rad_per_m·|v|·n_yaw`.
//!
//! With [`SlipParams::bursts`] set, a burst ([`bursts`]) adds its extra slip
//! to `s` before the clamp while it lasts.
//!
//! Every term is proportional to the commanded speed or yaw rate, so a zero
//! command gives exactly zero motion (no creep). Defaults aim at the real
//! ExoTeR residuals (median `|res_x|`/wheel speed ≈ 8% on moving seconds,
//! mean `|res|` x/y ≈ 4.1/2.3 mm/s).

use nalgebra::{Vector2, Vector3};
use rand::Rng;
use serde::{Deserialize, Serialize};

pub use super::manoeuvre::{ManoeuvreKind, PlanarTwist};
use super::noise::OrnsteinUhlenbeck;
use super::soil::Soil;
use crate::TestbedError;
use crate::error::require;

pub mod bursts;
pub use bursts::{BurstProcess, SlipBursts};

/// Global scale factors of the slip model; the per-soil ones live in [`Soil`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SlipParams {
    /// Exponential rate `k` of slip growth with uphill angle, 1/rad.
    /// Default 6.0 (`e^{k·θ} − 1` = 0.69 at 5°, 1.85 at 10°, 7.1 at 20°).
    pub slope_rate_per_rad: f64,
    /// Multiple of the soil's slope gain that applies downhill, where it makes
    /// the rover skid ahead of its wheels (dimensionless). Default 2.0 (sand
    /// skids by ≈ 20% at 20° downhill, compact soil by ≈ 7%; the real
    /// rover shows large residuals downhill too).
    pub downhill_skid_factor: f64,
    /// Lower clamp of the longitudinal slip ratio (skid). Default −0.3.
    pub min_slip: f64,
    /// Upper clamp of the longitudinal slip ratio. Default 0.9.
    pub max_slip: f64,
    /// Share of the soil's slope gain that applies to the cross-slope angle:
    /// a side slope loads the downhill wheels, which sink and slip more
    /// (dimensionless). Default 1.0.
    pub cross_slope_factor: f64,
    /// Extra slip ratio (longitudinal and turn) per unit load imbalance.
    /// Default 0.1.
    pub load_slip_gain: f64,
    /// Multiplier of every soil's `lateral_slip_gain`. Default 1.0.
    pub lateral_scale: f64,
    /// Share of the soil's `turn_slip` lost in a turn on the spot. Default 1.0.
    pub turn_on_spot_factor: f64,
    /// Share of the soil's `turn_slip` lost in a point turn. Default 0.7.
    pub point_turn_factor: f64,
    /// Share of the soil's `turn_slip` lost on an Ackermann arc. Default 0.3.
    pub ackermann_factor: f64,
    /// Upper clamp of the turn slip ratio. Default 0.8.
    pub max_turn_slip: f64,
    /// Slip ratio per unit of longitudinal noise (its standard deviation).
    /// Default 0.05.
    pub slip_noise_std: f64,
    /// Lateral velocity per unit of lateral noise, as a share of the ground
    /// speed scale `u` (m/s per m/s). Default 0.08.
    pub lateral_noise_ratio: f64,
    /// Turn slip ratio per unit of yaw noise. Default 0.05.
    pub turn_slip_noise_std: f64,
    /// Yaw-rate noise per unit of yaw noise and per m/s of speed, rad/m (the
    /// heading wander of straight driving). Default 0.05.
    pub yaw_noise_rad_per_m: f64,
    /// Lever arm that converts a yaw rate into a wheel ground speed, metres
    /// (≈ distance of the corner wheels from the centre). Default 0.3.
    pub scrub_lever_m: f64,
    /// Correlation time the caller should give the noise processes, seconds.
    /// Default 2.0.
    pub noise_correlation_time_secs: f64,
    /// Slip bursts on loose ground ([`bursts`]); default none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bursts: Option<SlipBursts>,
}

impl Default for SlipParams {
    fn default() -> Self {
        Self {
            slope_rate_per_rad: 6.0,
            downhill_skid_factor: 2.0,
            cross_slope_factor: 1.0,
            min_slip: -0.3,
            max_slip: 0.9,
            load_slip_gain: 0.1,
            lateral_scale: 1.0,
            turn_on_spot_factor: 1.0,
            point_turn_factor: 0.7,
            ackermann_factor: 0.3,
            max_turn_slip: 0.8,
            slip_noise_std: 0.05,
            lateral_noise_ratio: 0.08,
            turn_slip_noise_std: 0.05,
            yaw_noise_rad_per_m: 0.05,
            scrub_lever_m: 0.3,
            noise_correlation_time_secs: 2.0,
            bursts: None,
        }
    }
}

impl SlipParams {
    /// Checks every field, naming the first bad one.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`].
    pub fn validate(&self) -> Result<(), TestbedError> {
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        let checks = [
            (
                "slope_rate_per_rad",
                non_negative(self.slope_rate_per_rad),
                "a finite value >= 0",
            ),
            (
                "downhill_skid_factor",
                non_negative(self.downhill_skid_factor),
                "a finite value >= 0",
            ),
            (
                "min_slip",
                self.min_slip.is_finite() && (-1.0..=0.0).contains(&self.min_slip),
                "a value in [-1, 0]",
            ),
            (
                "max_slip",
                self.max_slip.is_finite() && (0.0..1.0).contains(&self.max_slip),
                "a value in [0, 1)",
            ),
            (
                "cross_slope_factor",
                non_negative(self.cross_slope_factor),
                "a finite value >= 0",
            ),
            (
                "load_slip_gain",
                non_negative(self.load_slip_gain),
                "a finite value >= 0",
            ),
            (
                "lateral_scale",
                non_negative(self.lateral_scale),
                "a finite value >= 0",
            ),
            (
                "turn_on_spot_factor",
                non_negative(self.turn_on_spot_factor),
                "a finite value >= 0",
            ),
            (
                "point_turn_factor",
                non_negative(self.point_turn_factor),
                "a finite value >= 0",
            ),
            (
                "ackermann_factor",
                non_negative(self.ackermann_factor),
                "a finite value >= 0",
            ),
            (
                "max_turn_slip",
                non_negative(self.max_turn_slip) && self.max_turn_slip < 1.0,
                "a value in [0, 1)",
            ),
            (
                "slip_noise_std",
                non_negative(self.slip_noise_std),
                "a finite value >= 0",
            ),
            (
                "lateral_noise_ratio",
                non_negative(self.lateral_noise_ratio),
                "a finite value >= 0",
            ),
            (
                "turn_slip_noise_std",
                non_negative(self.turn_slip_noise_std),
                "a finite value >= 0",
            ),
            (
                "yaw_noise_rad_per_m",
                non_negative(self.yaw_noise_rad_per_m),
                "a finite value >= 0",
            ),
            (
                "scrub_lever_m",
                non_negative(self.scrub_lever_m),
                "a finite value >= 0",
            ),
            (
                "noise_correlation_time_secs",
                self.noise_correlation_time_secs.is_finite()
                    && self.noise_correlation_time_secs > 0.0,
                "a finite value > 0",
            ),
        ];
        for (field, ok, expected) in checks {
            require(ok, field, expected)?;
        }
        if let Some(bursts) = &self.bursts {
            bursts.validate()?;
        }
        Ok(())
    }

    /// Validates the parameters into a usable model.
    ///
    /// # Errors
    /// As [`SlipParams::validate`].
    pub fn check(self) -> Result<SlipModel, TestbedError> {
        self.validate()?;
        Ok(SlipModel { params: self })
    }
}

/// One sample of the slip perturbation, each component unit-variance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SlipNoise {
    /// Perturbs the longitudinal slip ratio and the turning scrub.
    pub longitudinal: f64,
    /// Perturbs the lateral velocity.
    pub lateral: f64,
    /// Perturbs the turn slip and the heading wander.
    pub yaw: f64,
}

/// Everything the slip model looks at during one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlipInput<'a> {
    /// The body twist the wheels would produce without slip.
    pub commanded: PlanarTwist,
    /// Unit gravity direction in the body frame (`(0, 0, −1)` on level
    /// ground); a zero or non-finite vector counts as level.
    pub gravity_body: Vector3<f64>,
    /// The soil under the rover.
    pub soil: &'a Soil,
    /// How unevenly the wheels are loaded, in [0, 1] (0 = evenly); clamped,
    /// NaN counts as 0.
    pub load_imbalance: f64,
    /// The commanded manoeuvre.
    pub kind: ManoeuvreKind,
    /// The correlated noise sample; non-finite components count as 0.
    pub noise: SlipNoise,
    /// Whether a slip burst acts during this step ([`BurstProcess`]); its
    /// extra slip comes from [`SlipParams::bursts`] (none when unset).
    pub in_burst: bool,
}

/// The actual motion and the slip that produced it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SlipOutcome {
    /// The body twist the rover actually makes.
    pub twist: PlanarTwist,
    /// Longitudinal slip ratio applied (0 when not translating).
    pub longitudinal_slip: f64,
    /// Turn slip ratio applied (0 when not turning).
    pub turn_slip: f64,
    /// The ground's inclination along and across the motion direction.
    pub slope: SlopeAngles,
}

/// The ground's inclination relative to the motion direction `d` (body `+x`
/// when not translating).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SlopeAngles {
    /// Uphill angle along `d`, rad: `asin(−g·d)` (negative downhill).
    pub uphill_rad: f64,
    /// Cross-slope angle, rad: `asin(−g·l)` with `l = z × d` (positive when
    /// the left side is up).
    pub cross_rad: f64,
}

impl SlopeAngles {
    fn of(gravity_plane: Vector2<f64>, dir: Vector2<f64>, left: Vector2<f64>) -> Self {
        let angle = |axis: Vector2<f64>| (-gravity_plane.dot(&axis)).clamp(-1.0, 1.0).asin();
        Self {
            uphill_rad: angle(dir),
            cross_rad: angle(left),
        }
    }
}

/// The validated slip model; build it with [`SlipParams::check`]
/// (`SlipModel::default()` uses [`SlipParams::default`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SlipModel {
    params: SlipParams,
}

impl SlipModel {
    /// The parameters.
    pub fn params(&self) -> &SlipParams {
        &self.params
    }

    /// The actual twist for one step (see the module docs for the model).
    pub fn apply(&self, input: &SlipInput<'_>) -> SlipOutcome {
        let cmd = input.commanded;
        let velocity = Vector2::new(cmd.vx_mps, cmd.vy_mps);
        let speed = velocity.norm();
        let rate = cmd.wz_radps.abs();
        if !(speed > 0.0 || rate > 0.0) {
            return SlipOutcome::default();
        }
        let gravity = level_if_invalid(input.gravity_body);
        let gravity_plane = Vector2::new(gravity.x, gravity.y);
        let (dir, left) = motion_axes(velocity, speed);
        let slope = SlopeAngles::of(gravity_plane, dir, left);
        let imbalance = sanitize(input.load_imbalance).clamp(0.0, 1.0);
        let noise = sanitized_noise(input.noise);
        let p = &self.params;

        let slip = if speed > 0.0 {
            let burst = match (&p.bursts, input.in_burst) {
                (Some(b), true) => b.extra_at(slope.uphill_rad),
                _ => 0.0,
            };
            self.slip_ratio(input.soil, slope, imbalance, noise.longitudinal, burst)
        } else {
            0.0
        };
        let ground_speed = speed + p.scrub_lever_m * rate;
        let pure_turn_share = if ground_speed > 0.0 {
            1.0 - speed / ground_speed
        } else {
            0.0
        };
        let drift = p.lateral_scale
            * input.soil.lateral_slip_gain
            * ground_speed
            * (gravity_plane.dot(&left) * left + pure_turn_share * gravity_plane.dot(&dir) * dir);
        let jitter = p.lateral_noise_ratio * ground_speed * noise.lateral * left
            + p.slip_noise_std * p.scrub_lever_m * rate * noise.longitudinal * dir;
        let actual_velocity = (1.0 - slip) * velocity + drift + jitter;

        let turn_slip = if rate > 0.0 {
            self.turn_slip(input.soil, input.kind, imbalance, noise.yaw)
        } else {
            0.0
        };
        let actual_rate =
            (1.0 - turn_slip) * cmd.wz_radps + p.yaw_noise_rad_per_m * speed * noise.yaw;
        SlipOutcome {
            twist: PlanarTwist::new(actual_velocity.x, actual_velocity.y, actual_rate),
            longitudinal_slip: slip,
            turn_slip,
            slope,
        }
    }

    /// Longitudinal slip ratio on `soil` on ground inclined by `slope`, with
    /// the given load imbalance and noise sample, clamped to
    /// `[min_slip, max_slip]`.
    pub fn longitudinal_slip(
        &self,
        soil: &Soil,
        slope: SlopeAngles,
        load_imbalance: f64,
        noise: f64,
    ) -> f64 {
        self.slip_ratio(soil, slope, load_imbalance, noise, 0.0)
    }

    /// [`SlipModel::longitudinal_slip`] with a burst's `extra` slip added
    /// before the clamp.
    fn slip_ratio(
        &self,
        soil: &Soil,
        slope: SlopeAngles,
        load_imbalance: f64,
        noise: f64,
        extra: f64,
    ) -> f64 {
        let p = &self.params;
        let growth = |angle: f64| (p.slope_rate_per_rad * angle).exp() - 1.0;
        let along = if slope.uphill_rad >= 0.0 {
            soil.slip_base + soil.slope_slip_gain * growth(slope.uphill_rad)
        } else {
            let fade = (p.slope_rate_per_rad * slope.uphill_rad).exp();
            soil.slip_base * fade - p.downhill_skid_factor * soil.slope_slip_gain * (1.0 - fade)
        };
        let across = p.cross_slope_factor * soil.slope_slip_gain * growth(slope.cross_rad.abs());
        let slip =
            along + across + p.load_slip_gain * load_imbalance + p.slip_noise_std * noise + extra;
        slip.clamp(p.min_slip, p.max_slip)
    }

    /// Share of the commanded yaw rate lost on `soil` in manoeuvre `kind`,
    /// clamped to `[0, max_turn_slip]`.
    pub fn turn_slip(
        &self,
        soil: &Soil,
        kind: ManoeuvreKind,
        load_imbalance: f64,
        noise: f64,
    ) -> f64 {
        let p = &self.params;
        let factor = match kind {
            ManoeuvreKind::TurnOnSpot => p.turn_on_spot_factor,
            ManoeuvreKind::PointTurn => p.point_turn_factor,
            ManoeuvreKind::Ackermann => p.ackermann_factor,
            ManoeuvreKind::Straight | ManoeuvreKind::Stop => 0.0,
        };
        let slip = soil.turn_slip * factor
            + p.load_slip_gain * load_imbalance
            + p.turn_slip_noise_std * noise;
        slip.clamp(0.0, p.max_turn_slip)
    }
}

/// Three independent unit-variance Ornstein–Uhlenbeck processes that feed
/// [`SlipNoise`] samples to the slip model.
#[derive(Clone, Debug, PartialEq)]
pub struct SlipNoiseProcess {
    longitudinal: OrnsteinUhlenbeck,
    lateral: OrnsteinUhlenbeck,
    yaw: OrnsteinUhlenbeck,
}

impl SlipNoiseProcess {
    /// Processes with correlation time `correlation_time_secs` (use
    /// [`SlipParams::noise_correlation_time_secs`]), started from stationary
    /// draws.
    ///
    /// # Errors
    /// [`TestbedError::InvalidConfig`] naming `correlation_time_secs`.
    pub fn new<R: Rng + ?Sized>(
        correlation_time_secs: f64,
        rng: &mut R,
    ) -> Result<Self, TestbedError> {
        Ok(Self {
            longitudinal: OrnsteinUhlenbeck::new_stationary(1.0, correlation_time_secs, rng)?,
            lateral: OrnsteinUhlenbeck::new_stationary(1.0, correlation_time_secs, rng)?,
            yaw: OrnsteinUhlenbeck::new_stationary(1.0, correlation_time_secs, rng)?,
        })
    }

    /// Advances all three processes by `dt_secs` and returns the new sample.
    pub fn step<R: Rng + ?Sized>(&mut self, dt_secs: f64, rng: &mut R) -> SlipNoise {
        SlipNoise {
            longitudinal: self.longitudinal.step(dt_secs, rng),
            lateral: self.lateral.step(dt_secs, rng),
            yaw: self.yaw.step(dt_secs, rng),
        }
    }
}

/// Unit motion direction `d` and its left normal `l = z × d`; `+x` when not
/// translating.
fn motion_axes(velocity: Vector2<f64>, speed: f64) -> (Vector2<f64>, Vector2<f64>) {
    let dir = if speed > 0.0 {
        velocity / speed
    } else {
        Vector2::x()
    };
    (dir, Vector2::new(-dir.y, dir.x))
}

fn level_if_invalid(gravity: Vector3<f64>) -> Vector3<f64> {
    let norm = gravity.norm();
    if norm.is_finite() && norm > 0.0 {
        gravity / norm
    } else {
        -Vector3::z()
    }
}

fn sanitize(value: f64) -> f64 {
    if value.is_finite() { value } else { 0.0 }
}

fn sanitized_noise(noise: SlipNoise) -> SlipNoise {
    SlipNoise {
        longitudinal: sanitize(noise.longitudinal),
        lateral: sanitize(noise.lateral),
        yaw: sanitize(noise.yaw),
    }
}

#[cfg(test)]
mod tests;

//! Drives the simulated rover through one run and records its sensors.
//!
//! Each step of `dt` (12.5 Hz):
//! 1. the driver commands a planar body twist (its instantaneous centre of
//!    rotation on the middle-axle line, so the fixed middle wheels roll);
//!    the corner wheels steer towards it at a limited rate, the rover
//!    waiting while they do;
//! 2. the slip model turns the command into the twist the rover really makes
//!    on this slope and soil;
//! 3. the planar pose is integrated with that twist and the chassis placed on
//!    the terrain (body height, attitude, bogie and contact angles);
//! 4. the sensors read what happened: the true 3-D twist over the step (gyro,
//!    accelerometers, bogie and steering rates) — but the wheels turn at the
//!    *commanded* motion, computed from each wheel's no-slip rolling
//!    condition at its true contact point: the gap between the two is slip.

use gpodo_kinematics::RoverDescription;
use gpodo_kinematics::chain::{ChainAngles, ContactGeometry};
use gpodo_kinematics::description::WheelChain;
use gpodo_kinematics::loads::static_normal_forces;
use gpodo_traits::{ImuSample, JointState, ProprioceptiveSample};
use nalgebra::{Isometry3, Vector3};
use rand::Rng;

use crate::TestbedError;
use crate::error::require;
use crate::sim::chassis::{ChassisSolver, Placement};
use crate::sim::driver::Driver;
use crate::sim::manoeuvre::{DriveCommand, ManoeuvreKind, PlanarPose, PlanarTwist};
use crate::sim::noise::OrnsteinUhlenbeck;
use crate::sim::sensors::{SensorErrors, SensorNoise, normal};
use crate::sim::slip::{BurstProcess, SlipInput, SlipModel, SlipNoiseProcess};
use crate::sim::soil::SoilMap;
use crate::sim::terrain::Terrain;
use gpodo_datasets::log::RoverLog;

/// Standard gravity (m/s²).
const GRAVITY_MPS2: f64 = 9.81;

/// The world the rover drives in and the physics and sensors it obeys.
#[derive(Debug, Clone)]
pub struct World<'a> {
    /// Rover geometry.
    pub description: &'a RoverDescription,
    /// Ground.
    pub terrain: &'a Terrain,
    /// Soils.
    pub soils: &'a SoilMap,
    /// Slip model.
    pub slip: &'a SlipModel,
    /// Sensor noise levels.
    pub noise: SensorNoise,
    /// Sensor period (s).
    pub dt_secs: f64,
    /// Camera frame rate (Hz).
    pub camera_rate_hz: f64,
    /// Steering joint speed limit (rad/s).
    pub steering_rate_radps: f64,
    /// Wheel sinkage: as the wheels sink into and climb out of the ground,
    /// the body height fluctuates by this much (m, stationary std); the
    /// motion capture and the IMU see it, the joints do not.
    pub sinkage_m: f64,
    /// Distance over which the sinkage decorrelates (m).
    pub sinkage_length_m: f64,
}

/// State carried from step to step.
struct RoverState {
    pose: PlanarPose,
    sinkage: OrnsteinUhlenbeck,
    placement: Placement,
    steer: [f64; 6],
    wheel_angle: [f64; 6],
    burst: BurstProcess,
}

/// Where the body really is (sinkage included) in state `s`.
fn truth_position(s: &RoverState) -> Vector3<f64> {
    sunk(&s.placement.world_from_body, s.sinkage.value())
        .translation
        .vector
}

/// Target steering angle of each wheel for a twist whose centre of rotation
/// is on the body y axis (0 for fixed wheels; flipped to stay within ±90°).
fn steering_for(chains: &[WheelChain], twist: &PlanarTwist, current: &[f64; 6]) -> [f64; 6] {
    let mut out = *current;
    if twist.is_zero() {
        return out;
    }
    for (i, chain) in chains.iter().enumerate() {
        if chain.steer_index.is_none() {
            out[i] = 0.0;
            continue;
        }
        let (x, y) = (chain.center.x, chain.center.y);
        let (vx, vy) = (
            twist.vx_mps - twist.wz_radps * y,
            twist.vy_mps + twist.wz_radps * x,
        );
        let mut angle = vy.atan2(vx);
        if angle.abs() > std::f64::consts::FRAC_PI_2 {
            angle -= std::f64::consts::PI * angle.signum();
        }
        out[i] = angle;
    }
    out
}

/// Rolling rate of a wheel whose contact material point does not slip while
/// the body moves with `(v, w)` and the joints with the given rates:
/// `φ̇ = x_C · (v + ω × p + Σ q̇_j a_j × (p − o_j)) / r`.
fn rolling_rate(
    g: &ContactGeometry,
    radius_m: f64,
    v: &Vector3<f64>,
    w: &Vector3<f64>,
    bogie_rate: f64,
    steer_rate: f64,
) -> f64 {
    let p = g.contact_point().coords;
    let x_c = g.body_from_contact.rotation * Vector3::x();
    let mut vel = v + w.cross(&p) + g.bogie_axis.cross(&(p - g.bogie_pivot.coords)) * bogie_rate;
    if let Some(a) = g.steer_axis {
        vel += a.cross(&(p - g.wheel_center.coords)) * steer_rate;
    }
    x_c.dot(&vel) / radius_m
}

/// The pose lowered by `sinkage_m` along the world vertical.
fn sunk(body: &Isometry3<f64>, sinkage_m: f64) -> Isometry3<f64> {
    let mut body = *body;
    body.translation.vector.z -= sinkage_m;
    body
}

/// Rotation vector of `b` relative to `a`, in `a`'s frame, per second.
fn body_rate(a: &Isometry3<f64>, b: &Isometry3<f64>, dt: f64) -> Vector3<f64> {
    (a.rotation.inverse() * b.rotation).scaled_axis() / dt
}

impl World<'_> {
    fn place(
        &self,
        solver: &ChassisSolver,
        pose: &PlanarPose,
        steer: &[f64; 6],
        guess: &crate::sim::chassis::Suspension,
    ) -> Result<Placement, TestbedError> {
        solver.place(
            self.terrain,
            (pose.x_m, pose.y_m, pose.yaw_rad),
            steer,
            guess,
        )
    }

    fn contacts(
        &self,
        chains: &[WheelChain],
        placement: &Placement,
        steer: &[f64; 6],
    ) -> Vec<ContactGeometry> {
        chains
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let angles = ChainAngles {
                    bogie_rad: c
                        .bogie_index
                        .map_or(0.0, |b| placement.suspension.bogie_rad[b]),
                    steer_rad: steer[i],
                    contact_rad: placement.contact_rad[i],
                };
                ContactGeometry::new(c, self.description.wheel_radius_m, angles)
            })
            .collect()
    }

    /// Load imbalance in [0, 1]: 0 when all wheels carry equal weight.
    fn load_imbalance(&self, contacts: &[ContactGeometry], gravity: &Vector3<f64>) -> f64 {
        match static_normal_forces(self.description, contacts, gravity) {
            Ok(n) => {
                let mean = n.iter().sum::<f64>() / n.len() as f64;
                let spread = n.iter().map(|f| (f - mean).abs()).fold(0.0, f64::max);
                (spread / mean).clamp(0.0, 1.0)
            }
            Err(_) => 0.0,
        }
    }

    /// Simulates one run from `start` until the driver is done or
    /// `max_duration_secs` has passed.
    ///
    /// # Errors
    /// [`TestbedError::Simulation`] if the chassis cannot be placed (terrain
    /// too steep), [`TestbedError::InvalidConfig`] for bad noise levels.
    pub fn run<R: Rng + ?Sized>(
        &self,
        name: &str,
        driver: &mut Driver,
        start: PlanarPose,
        max_duration_secs: f64,
        rng: &mut R,
    ) -> Result<RoverLog, TestbedError> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        require(
            positive(self.dt_secs),
            "dt_secs",
            "a positive sensor period in s",
        )?;
        require(
            positive(self.camera_rate_hz),
            "camera_rate_hz",
            "a positive rate in Hz",
        )?;
        require(
            positive(self.steering_rate_radps),
            "steering_rate_radps",
            "a positive rate in rad/s",
        )?;
        require(
            max_duration_secs.is_finite() && max_duration_secs >= 0.0,
            "max_duration_secs",
            "a finite duration in s",
        )?;
        let d = self.description;
        let chains = d.chains();
        let solver = ChassisSolver::new(d)?;
        let dt = self.dt_secs;
        let mut errors = SensorErrors::new(self.noise, rng)?;
        let mut slip_noise =
            SlipNoiseProcess::new(self.slip.params().noise_correlation_time_secs, rng)?;

        let guess = solver.resting_guess(self.terrain, start.x_m, start.y_m);
        let steer0 = [0.0; 6];
        let placement = self.place(&solver, &start, &steer0, &guess)?;
        let mut state = RoverState {
            pose: start,
            sinkage: OrnsteinUhlenbeck::new_stationary(self.sinkage_m, self.sinkage_length_m, rng)?,
            placement,
            steer: steer0,
            wheel_angle: [0.0; 6],
            burst: BurstProcess::default(),
        };
        // Position of the (sunk) body one step back, for the accelerometer.
        let mut previous_position = truth_position(&state);
        let mut samples = Vec::new();
        let mut ground_truth = Vec::new();
        let steps = (max_duration_secs / dt).floor() as usize;
        for k in 0..steps {
            if driver.done() {
                break;
            }
            let t = k as f64 * dt;
            let command = driver.command(state.pose, t, rng);
            let (sample, truth, next) = self.step(
                &solver,
                &chains,
                &state,
                command,
                &mut errors,
                &mut slip_noise,
                previous_position,
                t,
                rng,
            )?;
            previous_position = truth_position(&state);
            samples.push(sample);
            ground_truth.push(truth);
            state = next;
        }
        let duration = samples.last().map_or(0.0, |s| s.time_secs);
        let camera_period = 1.0 / self.camera_rate_hz;
        let camera_offset = rng.random_range(0.0..camera_period);
        let camera_times_secs = (0..)
            .map(|j| camera_offset + j as f64 * camera_period)
            .take_while(|&t| t <= duration)
            .collect();
        Ok(RoverLog {
            name: name.to_string(),
            wheel_names: d.wheel_names(),
            steer_names: d.steer_names(),
            bogie_names: d.bogie_names(),
            samples,
            ground_truth,
            camera_times_secs,
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn step<R: Rng + ?Sized>(
        &self,
        solver: &ChassisSolver,
        chains: &[WheelChain],
        state: &RoverState,
        command: DriveCommand,
        errors: &mut SensorErrors,
        slip_noise: &mut SlipNoiseProcess,
        previous_position: Vector3<f64>,
        t: f64,
        rng: &mut R,
    ) -> Result<(ProprioceptiveSample, Isometry3<f64>, RoverState), TestbedError> {
        let dt = self.dt_secs;
        let body_k = sunk(&state.placement.world_from_body, state.sinkage.value());

        // 1. Steer first; drive only once the wheels point the right way.
        let target = steering_for(chains, &command.twist, &state.steer);
        let max_step = self.steering_rate_radps * dt;
        let mut steer = state.steer;
        let mut steering = false;
        for i in 0..6 {
            let delta = target[i] - steer[i];
            if delta.abs() > 0.02 {
                steering = true;
            }
            steer[i] += delta.clamp(-max_step, max_step);
        }
        let (kind, commanded) = if steering {
            (ManoeuvreKind::Stop, PlanarTwist::ZERO)
        } else {
            steer = target;
            (command.kind, command.twist)
        };

        // 2. Slip: what the rover really does.
        let gravity = body_k.rotation.inverse() * -Vector3::z();
        let contacts_k = self.contacts(chains, &state.placement, &state.steer);
        let soil = self.soils.soil_at(state.pose.x_m, state.pose.y_m);
        // Bursts draw from `rng` only when set, so runs without them keep
        // their draws.
        let mut burst = state.burst;
        let in_burst = self
            .slip
            .params()
            .bursts
            .as_ref()
            .is_some_and(|b| burst.step(b, soil, commanded.speed_mps() * dt, dt, rng));
        let outcome = self.slip.apply(&SlipInput {
            commanded,
            gravity_body: gravity,
            soil,
            load_imbalance: self.load_imbalance(&contacts_k, &gravity),
            kind,
            noise: slip_noise.step(dt, rng),
            in_burst,
        });
        let actual = outcome.twist;

        // 3. Integrate the planar pose and place the chassis.
        let world_velocity = body_k.rotation * Vector3::new(actual.vx_mps, actual.vy_mps, 0.0);
        let (roll, pitch, _) = body_k.rotation.euler_angles();
        let pose = PlanarPose {
            x_m: state.pose.x_m + world_velocity.x * dt,
            y_m: state.pose.y_m + world_velocity.y * dt,
            yaw_rad: state.pose.yaw_rad + actual.wz_radps * roll.cos() / pitch.cos() * dt,
        };
        let placement = self.place(solver, &pose, &steer, &state.placement.suspension)?;
        // The sinkage process advances with distance travelled, not time:
        // a standing rover does not sink further.
        let mut sinkage = state.sinkage.clone();
        sinkage.step(actual.speed_mps() * dt, rng);
        let body_next = sunk(&placement.world_from_body, sinkage.value());

        // 4. Sensors.
        let w_true = body_rate(&body_k, &body_next, dt);
        // The wheels follow the commanded motion over the ground, which the
        // sinkage is not part of.
        let (chassis_k, chassis_next) =
            (&state.placement.world_from_body, &placement.world_from_body);
        let v_chassis = chassis_k.rotation.inverse()
            * (chassis_next.translation.vector - chassis_k.translation.vector)
            / dt;
        let v_cmd = v_chassis
            + Vector3::new(
                commanded.vx_mps - actual.vx_mps,
                commanded.vy_mps - actual.vy_mps,
                0.0,
            );
        let w_cmd = w_true + Vector3::new(0.0, 0.0, commanded.wz_radps - actual.wz_radps);
        let bogie_rates: Vec<f64> = (0..3)
            .map(|b| {
                (placement.suspension.bogie_rad[b] - state.placement.suspension.bogie_rad[b]) / dt
            })
            .collect();
        let steer_rates: Vec<f64> = (0..6).map(|i| (steer[i] - state.steer[i]) / dt).collect();

        let noise = *errors.levels();
        let mut wheel_angle = state.wheel_angle;
        let mut wheels = Vec::with_capacity(6);
        let mut steering_joints = Vec::new();
        for (i, chain) in chains.iter().enumerate() {
            let rate = rolling_rate(
                &contacts_k[i],
                self.description.wheel_radius_m,
                &v_cmd,
                &w_cmd,
                chain.bogie_index.map_or(0.0, |b| bogie_rates[b]),
                steer_rates[i],
            );
            wheels.push(JointState {
                position_rad: wheel_angle[i],
                rate_radps: rate + normal(rng, noise.wheel_rate_noise_radps),
            });
            wheel_angle[i] += rate * dt;
            if chain.steer_index.is_some() {
                steering_joints.push(JointState {
                    position_rad: state.steer[i] + normal(rng, noise.joint_angle_noise_rad),
                    rate_radps: steer_rates[i] + normal(rng, noise.joint_rate_noise_radps),
                });
            }
        }
        let bogies = (0..3)
            .map(|b| JointState {
                position_rad: state.placement.suspension.bogie_rad[b]
                    + normal(rng, noise.joint_angle_noise_rad),
                rate_radps: bogie_rates[b] + normal(rng, noise.joint_rate_noise_radps),
            })
            .collect();
        let position = body_k.translation.vector;
        let accel_world =
            (body_next.translation.vector - 2.0 * position + previous_position) / (dt * dt);
        let specific_force =
            body_k.rotation.inverse() * (accel_world + Vector3::new(0.0, 0.0, GRAVITY_MPS2));
        let vibration = soil.vibration_mps2 * (commanded.speed_mps() / 0.04).min(2.0);
        let (roll_k, pitch_k, _) = body_k.rotation.euler_angles();
        let (roll_meas, pitch_meas) = errors.attitude(roll_k, pitch_k);
        let sample = ProprioceptiveSample {
            time_secs: t,
            wheels,
            steering: steering_joints,
            bogies,
            imu: Some(ImuSample {
                gyro_radps: errors.gyro(&w_true, rng),
                accel_mps2: errors.accel(&specific_force, vibration, rng),
                roll_rad: roll_meas,
                pitch_rad: pitch_meas,
            }),
            attitude_rad: None,
            contact_angles_rad: Some(state.placement.contact_rad.clone()),
            odometry: None,
        };
        let truth = errors.mocap(&body_k, rng);
        errors.step(dt, rng);
        Ok((
            sample,
            truth,
            RoverState {
                pose,
                sinkage,
                placement,
                steer,
                wheel_angle,
                burst,
            },
        ))
    }
}

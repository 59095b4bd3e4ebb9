//! Fixtures shared by the kinematics tests: samples of an ExoTeR-like rover
//! moving rigidly on a plane without slip, built from rigid-body velocities
//! only (not from the model's Jacobians).

// Each test binary uses a subset of these fixtures.
#![allow(dead_code)]

use gpodo_kinematics::RoverDescription;
use gpodo_traits::{JointState, ProprioceptiveSample};
use nalgebra::Vector3;

/// A planar twist in the body frame (the body's x–y plane is the ground plane).
#[derive(Clone, Copy, Debug)]
pub struct PlanarMotion {
    pub vx: f64,
    pub vy: f64,
    pub wz: f64,
}

/// Roll and pitch of a body lying on a plane of slope `slope_rad` whose
/// downhill direction is at `azimuth_rad` from the body x axis.
pub fn attitude_on_slope(slope_rad: f64, azimuth_rad: f64) -> (f64, f64) {
    // Gravity in the body frame: tilted towards the downhill direction.
    let g = Vector3::new(
        slope_rad.sin() * azimuth_rad.cos(),
        slope_rad.sin() * azimuth_rad.sin(),
        -slope_rad.cos(),
    );
    // g_b = (sin p, −sin r cos p, −cos r cos p).
    let pitch = g.x.asin();
    let roll = (-g.y).atan2(-g.z);
    (roll, pitch)
}

/// The sample an ideal rover reports while moving with `m` on a plane: each
/// steerable wheel points along its centre's velocity, each wheel rolls at
/// that speed, bogies stay at zero, the gyro reads the body rate.
/// `steer_rates` are extra steering rates (they turn a wheel about the
/// vertical through its contact point and so do not move the body).
pub fn planar_sample(
    d: &RoverDescription,
    m: PlanarMotion,
    roll_pitch: (f64, f64),
    steer_rates: &[f64],
) -> ProprioceptiveSample {
    let v = Vector3::new(m.vx, m.vy, 0.0);
    let w = Vector3::new(0.0, 0.0, m.wz);
    let mut wheels = Vec::new();
    let mut steering = Vec::new();
    for wheel in &d.wheels {
        let center = Vector3::from(wheel.center_m);
        let vc = v + w.cross(&center);
        let (steer, speed) = if wheel.steerable {
            if vc.xy().norm() < 1e-15 {
                (0.0, 0.0)
            } else {
                let mut s = vc.y.atan2(vc.x);
                let mut speed = vc.xy().norm();
                // Drive backwards rather than steer beyond ±90°.
                if s.abs() > std::f64::consts::FRAC_PI_2 {
                    s -= std::f64::consts::PI * s.signum();
                    speed = -speed;
                }
                (s, speed)
            }
        } else {
            assert!(vc.y.abs() < 1e-12, "a fixed wheel cannot move sideways");
            (0.0, vc.x)
        };
        if wheel.steerable {
            let k = steering.len();
            steering.push(JointState {
                position_rad: steer,
                rate_radps: steer_rates.get(k).copied().unwrap_or(0.0),
            });
        }
        wheels.push(JointState {
            position_rad: 0.0,
            rate_radps: speed / d.wheel_radius_m,
        });
    }
    let mut s = ProprioceptiveSample {
        time_secs: 0.0,
        wheels,
        steering,
        bogies: vec![JointState::default(); d.bogies.len()],
        ..Default::default()
    };
    s.imu.get_or_insert_default().gyro_radps = w;
    s.imu.get_or_insert_default().roll_rad = roll_pitch.0;
    s.imu.get_or_insert_default().pitch_rad = roll_pitch.1;
    s
}

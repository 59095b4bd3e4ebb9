//! The weighted Jacobian model on chassis beyond ExoTeR: the shipped
//! differential-drive, Husky-like skid-steer and mecanum descriptions,
//! against their closed-form kinematics (straight line, turn on the spot,
//! pure sideways motion and the mecanum inverse kinematics).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use gpodo_kinematics::{
    RoverDescription, SkidSteerModel, WeightedJacobianConfig, WeightedJacobianModel, Weighting,
    YawSource,
};
use gpodo_traits::{JointState, MotionModel, ProprioceptiveSample};
use nalgebra::Vector3;

fn rover(name: &str) -> RoverDescription {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("rovers/{name}.yaml"));
    RoverDescription::from_path(&path).unwrap()
}

fn model(d: &RoverDescription) -> WeightedJacobianModel {
    let config = WeightedJacobianConfig {
        weighting: Weighting::Uniform,
        ..Default::default()
    };
    WeightedJacobianModel::new(d.clone(), config).unwrap()
}

/// A sample with these wheel rates (rad/s, in the description's order) and
/// gyro yaw rate; no bogies, no steering.
fn sample(rates: &[f64], yaw_rate: f64) -> ProprioceptiveSample {
    let mut s = ProprioceptiveSample {
        wheels: rates
            .iter()
            .map(|&r| JointState {
                position_rad: 0.0,
                rate_radps: r,
            })
            .collect(),
        ..Default::default()
    };
    s.imu.get_or_insert_default().gyro_radps = Vector3::new(0.0, 0.0, yaw_rate);
    s.imu.get_or_insert_default().accel_mps2 = Vector3::new(0.0, 0.0, 9.81);
    s
}

fn velocity(m: &WeightedJacobianModel, s: &ProprioceptiveSample) -> Vector3<f64> {
    m.estimate(s, 0.1).unwrap().twist.linear_mps
}

fn assert_close(a: Vector3<f64>, b: Vector3<f64>, what: &str) {
    assert!((a - b).norm() < 1e-12, "{what}: {a} against {b}");
}

#[test]
fn differential_drive_straight_line_and_turn_on_the_spot() {
    let d = rover("diff_drive");
    assert!(d.bogies.is_empty() && d.chains().iter().all(|c| c.bogie_index.is_none()));
    let m = model(&d);
    let (r, track) = (d.wheel_radius_m, 0.16);
    // Straight: v = r ω.
    let v = velocity(&m, &sample(&[4.0, 4.0], 0.0));
    assert_close(v, Vector3::new(r * 4.0, 0.0, 0.0), "straight");
    // On the spot: the gyro reads r (ω_r − ω_l) / track, the body stays.
    let w = r * (3.0 - (-3.0)) / track;
    let v = velocity(&m, &sample(&[-3.0, 3.0], w));
    assert_close(v, Vector3::zeros(), "turn on the spot");
    // An arc: v = r (ω_l + ω_r) / 2 at the axle's centre.
    let w = r * (5.0 - 3.0) / track;
    let v = velocity(&m, &sample(&[3.0, 5.0], w));
    assert_close(v, Vector3::new(r * 4.0, 0.0, 0.0), "arc");
    // The ideal skid-steer model agrees.
    let ideal = SkidSteerModel::from_description(&d, YawSource::Wheels).unwrap();
    let e = ideal.estimate(&sample(&[3.0, 5.0], w), 0.1).unwrap();
    assert_close(e.twist.linear_mps, v, "ideal model");
    assert!((e.twist.angular_radps.z - w).abs() < 1e-12);
}

#[test]
fn husky_like_skid_steer_straight_line_and_turn_on_the_spot() {
    let d = rover("husky");
    let m = model(&d);
    let r = d.wheel_radius_m;
    let v = velocity(&m, &sample(&[2.0; 4], 0.0));
    assert_close(v, Vector3::new(r * 2.0, 0.0, 0.0), "straight");
    // Turning on the spot the wheels skid sideways; by symmetry the body
    // does not translate, whatever yaw rate the gyro measures.
    let s = sample(&[-2.0, 2.0, -2.0, 2.0], 0.9);
    let solution = m.solve(&s, 0.1).unwrap();
    assert_close(solution.linear_mps, Vector3::zeros(), "turn on the spot");
    // The skid shows as lateral slip of opposite sign front and rear.
    let (front, rear) = (solution.slips[0][1], solution.slips[2][1]);
    assert!(
        front * rear < 0.0 && front.abs() > 1e-3,
        "{:?}",
        solution.slips
    );
}

/// Inverse kinematics of the "X" mecanum platform (rollers at 45°): the
/// wheel rates that move the body with `(vx, vy, wz)`.
fn mecanum_rates(d: &RoverDescription, vx: f64, vy: f64, wz: f64) -> [f64; 4] {
    let r = d.wheel_radius_m;
    let k = 0.15 + 0.17; // lx + ly
    [
        (vx - vy - k * wz) / r, // fl
        (vx + vy + k * wz) / r, // fr
        (vx + vy - k * wz) / r, // rl
        (vx - vy + k * wz) / r, // rr
    ]
}

#[test]
fn mecanum_moves_sideways_and_follows_its_inverse_kinematics() {
    let d = rover("mecanum");
    let m = model(&d);
    let r = d.wheel_radius_m;
    // Straight ahead: every wheel forwards.
    let v = velocity(&m, &sample(&[3.0; 4], 0.0));
    assert_close(v, Vector3::new(r * 3.0, 0.0, 0.0), "straight");
    // Pure sideways, to the left: front-left and rear-right backwards.
    let rates = [-3.0, 3.0, 3.0, -3.0];
    let solution = m.solve(&sample(&rates, 0.0), 0.1).unwrap();
    assert_close(
        solution.linear_mps,
        Vector3::new(0.0, r * 3.0, 0.0),
        "sideways",
    );
    // The rollers carry it: every roller turns, no wheel slips.
    assert!(solution.roller_speeds_mps.iter().all(|s| s.abs() > 0.1));
    assert!(
        solution
            .slips
            .iter()
            .all(|s| s[0].abs() < 1e-12 && s[1].abs() < 1e-12)
    );
    // Any planar twist from its own wheel rates.
    for (vx, vy, wz) in [(0.2, -0.1, 0.3), (-0.05, 0.25, -0.4), (0.0, 0.0, 1.0)] {
        let rates = mecanum_rates(&d, vx, vy, wz);
        let v = velocity(&m, &sample(&rates, wz));
        assert_close(v, Vector3::new(vx, vy, 0.0), "inverse kinematics");
    }
    // An ordinary four-wheel chassis of the same size cannot move sideways:
    // the same wheel rates leave it all but still (their least-squares
    // compromise, under 5 % of the mecanum platform's sideways speed).
    let plain = {
        let mut p = d.clone();
        for w in &mut p.wheels {
            w.roller_angle_deg = None;
        }
        model(&p)
    };
    let v = velocity(&plain, &sample(&[-3.0, 3.0, 3.0, -3.0], 0.0));
    assert!(v.norm() < 0.05 * r * 3.0, "{v}");
}

#[test]
fn a_roller_angle_out_of_range_is_named() {
    let mut d = rover("mecanum");
    d.wheels[2].roller_angle_deg = Some(90.0);
    let e = d.validate().unwrap_err().to_string();
    assert!(e.contains("wheels[2].roller_angle_deg"), "{e}");
    // Static loads need three bogies: the error says to use `uniform`.
    let e = WeightedJacobianModel::new(rover("husky"), WeightedJacobianConfig::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("uniform"), "{e}");
}

//! The weighted Jacobian model of a robot without an IMU: the yaw rate is
//! solved from the wheels alone. Checked against closed forms (a
//! differential drive's `ω = (v_r − v_l)/track`, the mecanum inverse
//! kinematics), against the same ExoTeR sample with its gyro on a flat,
//! no-slip run, and for full rank on every shipped description.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use std::path::Path;

use gpodo_kinematics::{
    RoverDescription, WeightedJacobianConfig, WeightedJacobianModel, Weighting,
};
use gpodo_traits::{JointState, MotionModel, ProprioceptiveSample};
use nalgebra::Vector3;
use support::{PlanarMotion, planar_sample};

fn rover(name: &str) -> RoverDescription {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("rovers/{name}.yaml"));
    RoverDescription::from_path(&path).unwrap()
}

fn model(d: &RoverDescription, weighting: Weighting) -> WeightedJacobianModel {
    let config = WeightedJacobianConfig {
        weighting,
        ..Default::default()
    };
    WeightedJacobianModel::new(d.clone(), config).unwrap()
}

/// Wheel rates only: no IMU, no steering, no bogies.
fn wheels_only(rates: &[f64]) -> ProprioceptiveSample {
    ProprioceptiveSample {
        wheels: rates
            .iter()
            .map(|&r| JointState {
                position_rad: 0.0,
                rate_radps: r,
            })
            .collect(),
        ..Default::default()
    }
}

#[test]
fn a_differential_drive_turns_at_the_wheel_speed_difference_over_its_track() {
    let d = rover("diff_drive");
    let m = model(&d, Weighting::Uniform);
    let r = d.wheel_radius_m;
    let track = d.wheels[0].center_m[1] - d.wheels[1].center_m[1];
    for (left, right) in [(4.0, 6.0), (-3.0, 3.0), (5.0, 5.0), (0.0, -2.5)] {
        let s = wheels_only(&[left, right]);
        assert!(s.imu.is_none());
        let twist = m.estimate(&s, 0.1).unwrap().twist;
        let (v_l, v_r) = (left * r, right * r);
        let expected_w = (v_r - v_l) / track;
        assert!(
            (twist.angular_radps - Vector3::new(0.0, 0.0, expected_w)).norm() < 1e-9,
            "{left}, {right}: {} against {expected_w}",
            twist.angular_radps
        );
        assert!(
            (twist.linear_mps - Vector3::new(0.5 * (v_l + v_r), 0.0, 0.0)).norm() < 1e-9,
            "{}",
            twist.linear_mps
        );
    }
}

#[test]
fn a_mecanum_platform_recovers_its_inverse_kinematics_from_wheel_rates_alone() {
    let d = rover("mecanum");
    let m = model(&d, Weighting::Uniform);
    let r = d.wheel_radius_m;
    // lx + ly of the shipped description.
    let lever = d.wheels[0].center_m[0].abs() + d.wheels[0].center_m[1].abs();
    for (vx, vy, wz) in [(0.2, -0.1, 0.3), (-0.05, 0.25, -0.4), (0.0, 0.0, 1.0)] {
        // ω_i = (vx ∓ vy ∓ (lx + ly) ωz) / r for fl, fr, rl, rr.
        let rates = [
            (vx - vy - lever * wz) / r,
            (vx + vy + lever * wz) / r,
            (vx + vy - lever * wz) / r,
            (vx - vy + lever * wz) / r,
        ];
        let twist = m.estimate(&wheels_only(&rates), 0.1).unwrap().twist;
        assert!(
            (twist.linear_mps - Vector3::new(vx, vy, 0.0)).norm() < 1e-9
                && (twist.angular_radps - Vector3::new(0.0, 0.0, wz)).norm() < 1e-9,
            "({vx}, {vy}, {wz}): {} {}",
            twist.linear_mps,
            twist.angular_radps
        );
    }
}

#[test]
fn exoter_on_flat_ground_without_slip_gives_the_same_twist_with_and_without_its_gyro() {
    // Its middle wheels do not steer, so it cannot move sideways.
    let d = RoverDescription::exoter();
    for weighting in [Weighting::NormalForce, Weighting::Uniform] {
        let m = model(&d, weighting);
        for motion in [
            PlanarMotion {
                vx: 0.05,
                vy: 0.0,
                wz: 0.0,
            },
            PlanarMotion {
                vx: 0.04,
                vy: 0.0,
                wz: 0.1,
            },
            PlanarMotion {
                vx: 0.0,
                vy: 0.0,
                wz: -0.2,
            },
            PlanarMotion {
                vx: -0.03,
                vy: 0.0,
                wz: 0.05,
            },
        ] {
            let with_gyro = planar_sample(&d, motion, (0.0, 0.0), &[]);
            let mut without = with_gyro.clone();
            without.imu = None;
            let a = m.estimate(&with_gyro, 0.1).unwrap().twist;
            let b = m.estimate(&without, 0.1).unwrap().twist;
            assert!(
                (a.linear_mps - b.linear_mps).norm() < 1e-9
                    && (a.angular_radps - b.angular_radps).norm() < 1e-9,
                "{motion:?}: {} {} against {} {}",
                a.linear_mps,
                a.angular_radps,
                b.linear_mps,
                b.angular_radps
            );
            assert!((b.angular_radps.z - motion.wz).abs() < 1e-9);
        }
    }
}

/// The normal equations' smallest eigenvalue over their largest, for the
/// sample `s`: the solve's conditioning.
fn conditioning(m: &WeightedJacobianModel, s: &ProprioceptiveSample) -> f64 {
    let h = m.normal_equations(s).unwrap();
    let eig = h.symmetric_eigenvalues();
    eig.min() / eig.max()
}

#[test]
fn every_shipped_description_keeps_full_rank_without_a_gyro() {
    for name in ["diff_drive", "husky", "mecanum", "exoter"] {
        let d = rover(name);
        let weighting = if d.bogies.len() == 3 {
            Weighting::NormalForce
        } else {
            Weighting::Uniform
        };
        let m = model(&d, weighting);
        let mut s = wheels_only(&vec![2.0; d.wheels.len()]);
        s.steering = vec![JointState::default(); d.steer_names().len()];
        s.bogies = vec![JointState::default(); d.bogies.len()];
        let with_gyro = {
            let mut g = s.clone();
            g.imu = Some(Default::default());
            g
        };
        let (without, with) = (conditioning(&m, &s), conditioning(&m, &with_gyro));
        // The yaw rate adds one unknown; the system stays as well posed as
        // the gyro's (the slip prior bounds both away from singular).
        assert!(
            without > 1e-6 && without > 1e-3 * with,
            "{name}: conditioning {without:e} without a gyro, {with:e} with"
        );
        assert_eq!(
            m.normal_equations(&s).unwrap().nrows(),
            m.normal_equations(&with_gyro).unwrap().nrows() + 1
        );
    }
}

//! The skid-steer model and the static normal forces on closed-form cases.

// Tests panic on failure by design.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use gpodo_kinematics::chain::{ChainAngles, ContactGeometry};
use gpodo_kinematics::loads::static_normal_forces;
use gpodo_kinematics::{RoverDescription, SkidSteerModel, YawSource};
use gpodo_traits::MotionModel;
use nalgebra::Vector3;
use support::{PlanarMotion, planar_sample};

#[test]
fn skid_steer_reads_forward_speed_and_yaw_rate_off_the_sides() {
    let d = RoverDescription::exoter();
    let m = SkidSteerModel::from_description(&d, YawSource::Wheels).unwrap();
    assert!((m.track_width_m() - 0.56).abs() < 1e-15);
    // Turning on an arc: with wheels pointing straight (no steering), the
    // sides' speeds are v ∓ ω·track/2.
    let mut s = planar_sample(
        &d,
        PlanarMotion {
            vx: 0.04,
            vy: 0.0,
            wz: 0.0,
        },
        (0.0, 0.0),
        &[],
    );
    let w = 0.05;
    for (i, wheel) in d.wheels.iter().enumerate() {
        let side_speed = 0.04 - w * wheel.center_m[1];
        s.wheels[i].rate_radps = side_speed / d.wheel_radius_m;
    }
    let twist = m.estimate(&s, 0.08).unwrap().twist;
    assert!((twist.linear_mps - Vector3::new(0.04, 0.0, 0.0)).amax() < 1e-15);
    assert!((twist.angular_radps.z - w).abs() < 1e-15);
}

#[test]
fn skid_steer_with_gyro_passes_the_imu_rate_through() {
    let d = RoverDescription::exoter();
    let m = SkidSteerModel::from_description(&d, YawSource::Gyro).unwrap();
    let s = planar_sample(
        &d,
        PlanarMotion {
            vx: 0.0,
            vy: 0.0,
            wz: 0.1,
        },
        (0.0, 0.0),
        &[],
    );
    let twist = m.estimate(&s, 0.08).unwrap().twist;
    assert_eq!(twist.angular_radps, Vector3::new(0.0, 0.0, 0.1));
}

fn contacts(d: &RoverDescription) -> Vec<ContactGeometry> {
    d.chains()
        .iter()
        .map(|c| ContactGeometry::new(c, d.wheel_radius_m, ChainAngles::default()))
        .collect()
}

#[test]
fn loads_are_equal_on_flat_ground_and_sum_to_the_weight() {
    let d = RoverDescription::exoter();
    let n = static_normal_forces(&d, &contacts(&d), &Vector3::new(0.0, 0.0, -1.0)).unwrap();
    for f in &n {
        assert!((f - 1.0 / 6.0).abs() < 1e-15, "{n:?}");
    }
}

#[test]
fn loads_shift_downhill_and_balance_moments() {
    let d = RoverDescription::exoter();
    let c = contacts(&d);
    let tilt = 0.3f64;
    // Nose down and rolled right: gravity has +x and −y components.
    let g = Vector3::new(tilt.sin() * 0.6, -tilt.sin() * 0.8, -tilt.cos());
    let n = static_normal_forces(&d, &c, &g).unwrap();
    let total: f64 = n.iter().sum();
    assert!((total + g.z).abs() < 1e-14);
    // Moment balance about the ground point below the body origin, with the
    // centre of mass at height h above the contacts.
    let h = d.center_of_mass_m[2] - c[0].contact_point().z;
    let mx: f64 = c.iter().zip(&n).map(|(c, f)| c.contact_point().x * f).sum();
    let my: f64 = c.iter().zip(&n).map(|(c, f)| c.contact_point().y * f).sum();
    assert!((mx - h * g.x).abs() < 1e-14 && (my - h * g.y).abs() < 1e-14);
    // The right side carries more than the left; each passive bogie
    // equalises its two wheels (the rear one across, the side ones along).
    assert!(n[1] > n[0] && n[1] > n[4], "{n:?}");
    assert!(
        (n[4] - n[5]).abs() < 1e-15 && (n[0] - n[2]).abs() < 1e-15,
        "{n:?}"
    );
}

//! Every contact Jacobian of eq. (1) checked against finite differences of
//! the forward kinematics: moving the body with `J ṗ` while the joints,
//! wheel and contact angle move with `ṗ` must leave the wheel's material
//! contact point moving only by the slip `(δ_x, δ_y)` in the contact plane,
//! and the contact frame turning only by `δ_ψ` about its normal.

// Tests panic on failure by design.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_kinematics::RoverDescription;
use gpodo_kinematics::chain::{ChainAngles, ContactGeometry};
use gpodo_kinematics::jacobian::{CONTACT_COLUMNS, contact_jacobian};
use nalgebra::{Isometry3, Rotation3, SVector, Translation3, UnitQuaternion, Vector3};
use proptest::prelude::*;

type Rates = SVector<f64, CONTACT_COLUMNS>;

/// World position of the material point and world orientation of the contact
/// frame at time `t`, with the body moving by `twist` and the chain by `rates`.
fn state_at(
    d: &RoverDescription,
    wheel: usize,
    angles: ChainAngles,
    rates: &Rates,
    twist: &SVector<f64, 6>,
    t: f64,
) -> (Vector3<f64>, Rotation3<f64>) {
    let chain = &d.chains()[wheel];
    let moved = ChainAngles {
        bogie_rad: angles.bogie_rad + rates[0] * t,
        steer_rad: angles.steer_rad + rates[1] * t,
        contact_rad: angles.contact_rad + rates[3] * t,
    };
    let g = ContactGeometry::new(chain, d.wheel_radius_m, moved);
    // The material point that touches the ground at t = 0, carried round by
    // the wheel's rotation φ̇ t about its axle.
    let rim0 = Rotation3::from_axis_angle(&Vector3::y_axis(), angles.contact_rad)
        * Vector3::new(0.0, 0.0, -d.wheel_radius_m);
    let rim = Rotation3::from_axis_angle(&Vector3::y_axis(), rates[2] * t) * rim0;
    let material_body = g.wheel_center.coords + g.body_from_wheel * rim;
    let world_from_body = Isometry3::from_parts(
        Translation3::from(twist.fixed_rows::<3>(0) * t),
        UnitQuaternion::from_scaled_axis(twist.fixed_rows::<3>(3) * t),
    );
    let material_world = world_from_body
        .transform_point(&material_body.into())
        .coords;
    let contact_world = world_from_body.rotation.to_rotation_matrix()
        * g.body_from_contact.rotation.to_rotation_matrix();
    (material_world, contact_world)
}

fn check(d: &RoverDescription, wheel: usize, angles: ChainAngles, rates: Rates) {
    let chain = &d.chains()[wheel];
    let mut rates = rates;
    if chain.steer_index.is_none() {
        rates[1] = 0.0;
    }
    let g = ContactGeometry::new(chain, d.wheel_radius_m, angles);
    let twist = contact_jacobian(&g) * rates;
    let h = 1e-6;
    let (p_plus, r_plus) = state_at(d, wheel, angles, &rates, &twist, h);
    let (p_minus, r_minus) = state_at(d, wheel, angles, &rates, &twist, -h);
    let contact_rot = g.body_from_contact.rotation.to_rotation_matrix();

    let material_velocity = contact_rot.inverse() * ((p_plus - p_minus) / (2.0 * h));
    let expected_velocity = Vector3::new(rates[4], rates[5], 0.0);
    // vee of the skew part of R(−h)ᵀR(h) ≈ I + 2h[ω]×: accurate to O(h³),
    // unlike an acos of the trace.
    let rel = (r_minus.inverse() * r_plus).into_inner();
    let skew = (rel - rel.transpose()) * 0.5;
    let angular = Vector3::new(skew[(2, 1)], skew[(0, 2)], skew[(1, 0)]) / (2.0 * h);
    let expected_angular = Vector3::new(0.0, 0.0, rates[6]);

    let scale = 1.0 + rates.amax();
    assert!(
        (material_velocity - expected_velocity).amax() < 1e-7 * scale,
        "wheel {wheel}: material point velocity {material_velocity:?}, expected {expected_velocity:?}"
    );
    assert!(
        (angular - expected_angular).amax() < 1e-7 * scale,
        "wheel {wheel}: contact frame rate {angular:?}, expected {expected_angular:?}"
    );
}

#[test]
fn each_column_of_every_contact_jacobian_matches_finite_differences() {
    let d = RoverDescription::exoter();
    let angles = ChainAngles {
        bogie_rad: 0.17,
        steer_rad: -0.4,
        contact_rad: 0.3,
    };
    for wheel in 0..d.wheels.len() {
        for col in 0..CONTACT_COLUMNS {
            let mut rates = Rates::zeros();
            rates[col] = 0.7;
            check(&d, wheel, angles, rates);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn contact_jacobians_match_finite_differences_at_random_states(
        wheel in 0usize..6,
        bogie in -0.5f64..0.5,
        steer in -1.2f64..1.2,
        contact in -1.0f64..1.0,
        rates in proptest::array::uniform7(-2.0f64..2.0),
    ) {
        let d = RoverDescription::exoter();
        let angles = ChainAngles { bogie_rad: bogie, steer_rad: steer, contact_rad: contact };
        check(&d, wheel, angles, Rates::from_row_slice(&rates));
    }
}

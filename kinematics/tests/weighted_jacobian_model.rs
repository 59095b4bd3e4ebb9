//! The weighted Jacobian model (eq. 2–5) on motions whose answer is known.

// Tests panic on failure by design.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use gpodo_kinematics::{
    RoverDescription, SolveBounds, WeightedJacobianConfig, WeightedJacobianModel, Weighting,
};
use gpodo_traits::{MotionModel, ProprioceptiveSample};
use nalgebra::Vector3;
use support::{PlanarMotion, attitude_on_slope, planar_sample};

fn model(config: WeightedJacobianConfig) -> WeightedJacobianModel {
    WeightedJacobianModel::new(RoverDescription::exoter(), config).unwrap()
}

/// The manoeuvres of the paper: forward, backward, Ackermann, turn on spot,
/// point turn about the right middle wheel (centre at y = vx/ω = −0.28 m).
fn manoeuvres() -> Vec<PlanarMotion> {
    vec![
        PlanarMotion {
            vx: 0.04,
            vy: 0.0,
            wz: 0.0,
        },
        PlanarMotion {
            vx: -0.05,
            vy: 0.0,
            wz: 0.0,
        },
        PlanarMotion {
            vx: 0.04,
            vy: 0.0,
            wz: 0.04 / 1.2,
        },
        PlanarMotion {
            vx: 0.0,
            vy: 0.0,
            wz: -0.1,
        },
        PlanarMotion {
            vx: -0.1 * 0.28,
            vy: 0.0,
            wz: 0.1,
        },
    ]
}

fn assert_recovers(m: &WeightedJacobianModel, s: &ProprioceptiveSample, motion: PlanarMotion) {
    let twist = m.estimate(s, 0.08).unwrap().twist;
    let expected = Vector3::new(motion.vx, motion.vy, 0.0);
    assert!(
        (twist.linear_mps - expected).amax() < 1e-12,
        "{motion:?}: estimated {:?}",
        twist.linear_mps
    );
}

#[test]
fn recovers_true_body_velocity_without_slip_on_flat_ground() {
    let m = model(WeightedJacobianConfig::default());
    for motion in manoeuvres() {
        let s = planar_sample(m.description(), motion, (0.0, 0.0), &[]);
        assert_recovers(&m, &s, motion);
        let solution = m.solve(&s, 0.08).unwrap();
        assert!(
            solution.weighted_residual < 1e-28,
            "{}",
            solution.weighted_residual
        );
        assert!(
            solution
                .slips
                .iter()
                .all(|d| d[0].abs() < 1e-14 && d[1].abs() < 1e-14)
        );
    }
}

#[test]
fn recovers_true_body_velocity_without_slip_on_slopes() {
    let m = model(WeightedJacobianConfig::default());
    for slope_deg in [5.0f64, 12.0, 20.0] {
        for azimuth in [0.0, 0.8, 2.0, -2.7] {
            let attitude = attitude_on_slope(slope_deg.to_radians(), azimuth);
            for motion in manoeuvres() {
                let s = planar_sample(m.description(), motion, attitude, &[0.05, -0.2, 0.1, 0.3]);
                assert_recovers(&m, &s, motion);
            }
        }
    }
}

#[test]
fn weighted_and_uniform_solutions_agree_when_loads_are_equal() {
    // Flat ground: the ExoTeR bogies share the weight equally over the six
    // wheels, so normal-force weights equal I/N even for inconsistent data.
    let weighted = model(WeightedJacobianConfig::default());
    let uniform = model(WeightedJacobianConfig {
        weighting: Weighting::Uniform,
        ..Default::default()
    });
    let motion = PlanarMotion {
        vx: 0.04,
        vy: 0.0,
        wz: 0.03,
    };
    let mut s = planar_sample(weighted.description(), motion, (0.0, 0.0), &[]);
    for (i, w) in s.wheels.iter_mut().enumerate() {
        w.rate_radps *= 1.0 + 0.07 * (i as f64 - 2.5); // wheels disagree: slip
    }
    let a = weighted.solve(&s, 0.08).unwrap();
    let b = uniform.solve(&s, 0.08).unwrap();
    assert!(
        a.weights.iter().all(|w| (w - 1.0 / 6.0).abs() < 1e-15),
        "{:?}",
        a.weights
    );
    assert!((a.linear_mps - b.linear_mps).amax() < 1e-13);
    assert!(
        a.slips.iter().any(|d| d[0].abs() > 1e-4),
        "the data really are inconsistent: {:?}",
        a.slips
    );
}

#[test]
fn normal_force_weighting_trusts_the_loaded_wheels_on_a_slope() {
    // Nose down on a 20° slope: front wheels carry more weight, so a front
    // wheel that disagrees pulls the weighted estimate more than a rear one.
    let weighted = model(WeightedJacobianConfig::default());
    let motion = PlanarMotion {
        vx: 0.04,
        vy: 0.0,
        wz: 0.0,
    };
    let attitude = attitude_on_slope(20f64.to_radians(), 0.0);
    let base = planar_sample(weighted.description(), motion, attitude, &[]);
    let weights = weighted.solve(&base, 0.08).unwrap().weights;
    assert!(
        weights[0] > weights[4] && weights[1] > weights[5],
        "{weights:?}"
    );

    let speed_with_fast_wheel = |wheel: usize| {
        let mut s = base.clone();
        s.wheels[wheel].rate_radps *= 1.5;
        weighted.solve(&s, 0.08).unwrap().linear_mps.x
    };
    assert!(speed_with_fast_wheel(0) > speed_with_fast_wheel(4));
}

#[test]
fn qp_equals_least_squares_when_no_bound_is_active() {
    let free = model(WeightedJacobianConfig::default());
    let bounded = model(WeightedJacobianConfig {
        bounds: SolveBounds {
            contact_angle_max_deg: Some(60.0),
            slip_rate_max_mps: Some(1.0),
        },
        ..Default::default()
    });
    let motion = PlanarMotion {
        vx: 0.04,
        vy: 0.0,
        wz: 0.02,
    };
    let attitude = attitude_on_slope(0.2, 0.5);
    let mut s = planar_sample(free.description(), motion, attitude, &[]);
    s.wheels[2].rate_radps *= 1.3;
    let a = free.solve(&s, 0.08).unwrap();
    let b = bounded.solve(&s, 0.08).unwrap();
    assert!(
        (a.linear_mps - b.linear_mps).amax() < 1e-9,
        "{} vs {}",
        a.linear_mps,
        b.linear_mps
    );
    for (x, y) in a.slips.iter().zip(&b.slips) {
        assert!((x[0] - y[0]).abs() < 1e-9 && (x[1] - y[1]).abs() < 1e-9);
    }
}

#[test]
fn active_slip_bound_is_respected() {
    let bound = 0.002;
    let bounded = model(WeightedJacobianConfig {
        bounds: SolveBounds {
            contact_angle_max_deg: None,
            slip_rate_max_mps: Some(bound),
        },
        ..Default::default()
    });
    let free = model(WeightedJacobianConfig::default());
    let motion = PlanarMotion {
        vx: 0.04,
        vy: 0.0,
        wz: 0.0,
    };
    let mut s = planar_sample(bounded.description(), motion, (0.0, 0.0), &[]);
    s.wheels[0].rate_radps *= 2.0; // one wheel spins: 4 cm/s of slip
    let b = bounded.solve(&s, 0.08).unwrap();
    let a = free.solve(&s, 0.08).unwrap();
    assert!(
        a.slips[0][0].abs() > bound * 2.0,
        "unconstrained slip {:?}",
        a.slips[0]
    );
    for d in &b.slips {
        assert!(
            d[0].abs() <= bound * (1.0 + 1e-6) && d[1].abs() <= bound * (1.0 + 1e-6),
            "{d:?}"
        );
    }
}

#[test]
fn sample_of_another_rover_is_rejected_not_panicked() {
    let m = model(WeightedJacobianConfig::default());
    let mut s = planar_sample(m.description(), manoeuvres()[0], (0.0, 0.0), &[]);
    s.wheels.pop();
    let err = m.estimate(&s, 0.08).unwrap_err();
    assert!(err.to_string().contains("wheels"), "{err}");
}

#[test]
fn invalid_configuration_names_the_field() {
    let err = WeightedJacobianModel::new(
        RoverDescription::exoter(),
        WeightedJacobianConfig {
            slip_prior: -1.0,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(err.to_string().contains("slip_prior"), "{err}");
}

#[test]
fn models_are_shareable_across_threads() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<WeightedJacobianModel>();
    assert_send_sync::<gpodo_kinematics::SkidSteerModel>();
}

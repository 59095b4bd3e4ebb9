//! The pose covariance the node publishes, against Monte Carlo: 20 000
//! tracks integrated as the node integrates them, each step's twist drawn
//! with the variances the node was given, and the spread of their final
//! poses (position in the odom frame, rotation about its axes) compared
//! with the first-order propagation.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_node::covariance::propagate;
use gpodo_traits::BodyTwist;
use nalgebra::{Isometry3, Matrix6, UnitQuaternion, Vector3, Vector6};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

#[test]
fn the_propagated_covariance_is_the_spread_of_noisy_tracks() {
    let dt = 0.08;
    let steps = 100;
    // A rover driving and turning, rolling a little.
    let twist = BodyTwist {
        linear_mps: Vector3::new(0.05, 0.003, -0.001),
        angular_radps: Vector3::new(0.02, -0.01, 0.15),
    };
    let variance = [4e-6, 2e-6, 1e-6, 1e-4, 1e-4, 4e-4];
    let start = Isometry3::from_parts(
        Vector3::new(1.0, 2.0, 0.0).into(),
        UnitQuaternion::from_euler_angles(0.05, -0.02, 0.7),
    );
    let mut pose = start;
    let mut p = Matrix6::zeros();
    for _ in 0..steps {
        p = propagate(
            &p,
            &pose,
            &twist.linear_mps,
            &twist.angular_radps,
            &variance,
            dt,
        );
        pose *= twist.pose_delta(dt);
    }

    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let noise: Vec<Normal<f64>> = variance
        .iter()
        .map(|v| Normal::new(0.0, v.sqrt()).unwrap())
        .collect();
    let tracks = 20_000;
    let mut errors = Vec::with_capacity(tracks);
    for _ in 0..tracks {
        let mut noisy = start;
        for _ in 0..steps {
            let d: Vec<f64> = noise.iter().map(|n| n.sample(&mut rng)).collect();
            let drawn = BodyTwist {
                linear_mps: twist.linear_mps + Vector3::new(d[0], d[1], d[2]),
                angular_radps: twist.angular_radps + Vector3::new(d[3], d[4], d[5]),
            };
            noisy *= drawn.pose_delta(dt);
        }
        let dp = noisy.translation.vector - pose.translation.vector;
        let theta = (noisy.rotation * pose.rotation.inverse()).scaled_axis();
        errors.push(Vector6::new(dp.x, dp.y, dp.z, theta.x, theta.y, theta.z));
    }
    let mut empirical = Matrix6::zeros();
    for e in &errors {
        empirical += e * e.transpose();
    }
    empirical /= tracks as f64;
    // Each element within 5 % of the scale of its row and column (the
    // Monte Carlo error of a variance from 20 000 draws is about 1 %).
    for i in 0..6 {
        for j in 0..6 {
            let scale = (p[(i, i)] * p[(j, j)]).sqrt();
            assert!(
                (p[(i, j)] - empirical[(i, j)]).abs() <= 0.05 * scale,
                "({i}, {j}): propagated {:.4e}, Monte Carlo {:.4e} (scale {scale:.4e})",
                p[(i, j)],
                empirical[(i, j)]
            );
        }
    }
    // The heading's error grows the position's: more than the linear
    // variances alone would give.
    let linear_only: f64 = variance[..3].iter().sum::<f64>() * dt * dt * steps as f64;
    assert!(p[(0, 0)] + p[(1, 1)] + p[(2, 2)] > 2.0 * linear_only);
}

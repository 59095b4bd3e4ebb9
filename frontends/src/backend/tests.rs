//! Tests of [`super`].
use super::*;
use crate::vo::isotropic_covariance;

#[test]
fn conversions_round_trip() {
    let p = Isometry3::from_parts(
        Translation3::new(1.0, -2.0, 0.5),
        UnitQuaternion::from_euler_angles(0.1, -0.2, 2.5),
    );
    let back = from_se3(&to_se3(&p));
    assert!((back.translation.vector - p.translation.vector).norm() < 1e-15);
    assert!(back.rotation.angle_to(&p.rotation) < 1e-12);
}

#[test]
fn noiseless_edges_recover_a_known_trajectory_from_a_bad_start() {
    // A loop in 3-D: consecutive odometry edges plus one loop closure,
    // all exact; the initial guess is perturbed.
    let truth: Vec<Isometry3<f64>> = (0..12)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 12.0;
            Isometry3::from_parts(
                Translation3::new(2.0 * a.cos(), 2.0 * a.sin(), 0.1 * a.sin()),
                UnitQuaternion::from_euler_angles(0.05 * a.cos(), 0.02, a + 1.5),
            )
        })
        .collect();
    let mut graph = PoseGraph::default();
    for (k, p) in truth.iter().enumerate() {
        let start = if k == 0 {
            *p
        } else {
            let e = k as f64 * 0.01;
            Isometry3::from_parts(
                Translation3::new(e, -e, 0.5 * e),
                UnitQuaternion::from_euler_angles(e, -e, 2.0 * e),
            ) * p
        };
        graph.add_node(start);
    }
    let cov = isotropic_covariance(1e-2, 1e-2);
    for k in 1..truth.len() {
        graph.add_edge(PoseGraphEdge {
            from: k - 1,
            to: k,
            measurement: truth[k - 1].inverse() * truth[k],
            covariance: cov,
            kind: EdgeKind::Odometry,
        });
    }
    graph.add_edge(PoseGraphEdge {
        from: 11,
        to: 0,
        measurement: truth[11].inverse() * truth[0],
        covariance: cov,
        kind: EdgeKind::LoopClosure,
    });
    let out = graph.optimize(&BackendParams::default()).unwrap();
    assert!(out.final_error < 1e-16, "{}", out.final_error);
    for (a, b) in out.poses.iter().zip(&truth) {
        assert!((a.translation.vector - b.translation.vector).norm() < 1e-8);
        assert!(a.rotation.angle_to(&b.rotation) < 1e-8);
    }
    assert_eq!(graph.count(EdgeKind::LoopClosure), 1);
}

/// A ring of noisy odometry edges (σ 0.01 rad, 0.01 m) with two exact
/// loop closures and, when `false_closure`, a third measuring the pose
/// 90° and 2 m off, as a place matched to another that looks alike.
fn ring_with_closures(false_closure: bool) -> (PoseGraph, Vec<Isometry3<f64>>) {
    let truth: Vec<Isometry3<f64>> = (0..24)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 24.0;
            Isometry3::from_parts(
                Translation3::new(3.0 * a.cos(), 3.0 * a.sin(), 0.0),
                UnitQuaternion::from_euler_angles(0.0, 0.0, a + 1.5),
            )
        })
        .collect();
    let mut graph = PoseGraph::default();
    let odometry = isotropic_covariance(1e-2, 1e-2);
    let closure = isotropic_covariance(2e-3, 2e-3);
    let mut pose = truth[0];
    graph.add_node(pose);
    for k in 1..truth.len() {
        // A deterministic error of about a σ per axis.
        let e = 0.01 * ((k * 7 % 5) as f64 - 2.0) / 2.0;
        let measured = truth[k - 1].inverse()
            * truth[k]
            * Isometry3::from_parts(
                Translation3::new(e, -e, 0.0),
                UnitQuaternion::from_euler_angles(0.0, 0.0, e),
            );
        pose *= measured;
        graph.add_node(pose);
        graph.add_edge(PoseGraphEdge {
            from: k - 1,
            to: k,
            measurement: measured,
            covariance: odometry,
            kind: EdgeKind::Odometry,
        });
    }
    for (from, to) in [(0, 23), (4, 20)] {
        graph.add_edge(PoseGraphEdge {
            from,
            to,
            measurement: truth[from].inverse() * truth[to],
            covariance: closure,
            kind: EdgeKind::LoopClosure,
        });
    }
    if false_closure {
        graph.add_edge(PoseGraphEdge {
            from: 2,
            to: 14,
            measurement: truth[2].inverse()
                * truth[14]
                * Isometry3::from_parts(
                    Translation3::new(2.0, 0.0, 0.0),
                    UnitQuaternion::from_euler_angles(0.0, 0.0, 1.57),
                ),
            covariance: closure,
            kind: EdgeKind::LoopClosure,
        });
    }
    (graph, truth)
}

#[test]
fn a_false_closure_is_dropped_and_the_rest_optimised_as_without_it() {
    let (clean, truth) = ring_with_closures(false);
    let (with_false, _) = ring_with_closures(true);
    let params = BackendParams::default();
    let reference = clean.optimize(&params).unwrap();
    assert!(reference.rejected.is_empty());
    let out = with_false.optimize(&params).unwrap();
    assert_eq!(out.rejected, vec![with_false.edges.len() - 1]);
    // The same factors from the same start: the same poses.
    assert_eq!(out.poses, reference.poses);
    // Kept, the false closure bends the ring far from the truth.
    let kept = with_false
        .optimize(&BackendParams {
            closure_chi2_max: None,
            ..params
        })
        .unwrap();
    assert!(kept.rejected.is_empty());
    let worst = |poses: &[Isometry3<f64>]| {
        poses
            .iter()
            .zip(&truth)
            .map(|(a, b)| (a.translation.vector - b.translation.vector).norm())
            .fold(0.0, f64::max)
    };
    assert!(worst(&out.poses) < 0.1, "{}", worst(&out.poses));
    assert!(worst(&kept.poses) > 0.5, "{}", worst(&kept.poses));
    // The kept closures' χ² is what their Gaussian errors allow.
    for e in with_false
        .edges
        .iter()
        .filter(|e| e.kind == EdgeKind::LoopClosure)
        .take(2)
    {
        let chi2 = edge_chi2(e, &out.poses).unwrap();
        assert!(chi2 < 30.0, "{chi2}");
    }
}

#[test]
fn edge_chi2_is_the_mahalanobis_norm_of_a_known_perturbation() {
    let from = Isometry3::translation(1.0, 2.0, 0.5);
    let measurement = Isometry3::from_parts(
        Translation3::new(0.3, 0.0, 0.0),
        UnitQuaternion::from_euler_angles(0.0, 0.0, 0.2),
    );
    // `to` off the measurement by 0.01 rad about z and 0.02 m along y,
    // a right perturbation.
    let to = from
        * measurement
        * Isometry3::from_parts(
            Translation3::new(0.0, 0.02, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, 0.01),
        );
    let edge = PoseGraphEdge {
        from: 0,
        to: 1,
        measurement,
        covariance: isotropic_covariance(0.005, 0.01),
        kind: EdgeKind::LoopClosure,
    };
    let chi2 = edge_chi2(&edge, &[from, to]).unwrap();
    assert!(
        (chi2 - (2.0f64.powi(2) + 2.0f64.powi(2))).abs() < 1e-9,
        "{chi2}"
    );
}

#[test]
fn a_non_positive_closure_limit_is_refused_by_name() {
    let err = BackendParams {
        closure_chi2_max: Some(0.0),
        ..BackendParams::default()
    }
    .validate()
    .unwrap_err();
    assert!(
        err.to_string().contains("backend.closure_chi2_max"),
        "{err}"
    );
}

#[test]
fn a_bad_edge_is_an_error_not_a_panic() {
    let mut graph = PoseGraph::default();
    graph.add_node(Isometry3::identity());
    graph.add_edge(PoseGraphEdge {
        from: 0,
        to: 3,
        measurement: Isometry3::identity(),
        covariance: Matrix6::identity(),
        kind: EdgeKind::Odometry,
    });
    assert!(graph.optimize(&BackendParams::default()).is_err());
    let mut graph = PoseGraph::default();
    graph.add_node(Isometry3::identity());
    graph.add_node(Isometry3::identity());
    graph.add_edge(PoseGraphEdge {
        from: 0,
        to: 1,
        measurement: Isometry3::identity(),
        covariance: Matrix6::zeros(),
        kind: EdgeKind::Odometry,
    });
    let err = graph.optimize(&BackendParams::default()).unwrap_err();
    assert!(err.to_string().contains("positive definite"), "{err}");
}

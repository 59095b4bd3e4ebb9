//! The simulated tracker's map error, checked through the back end against
//! its closed form. `N` frames tracked against one keyframe, each with
//! error variance `σ² = σ_m² + σ_f²` of which `σ_m² = ρσ²` is the
//! keyframe's map error, are fused by the pose graph into one estimate of
//! their (common) pose. Its error variance is `σ_m² + σ_f²/N`: it falls to
//! the floor `σ_m²`, not to 0, however many frames are processed. With
//! independent errors it is `σ²/N`.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_frontends::backend::{BackendParams, EdgeKind, PoseGraph, PoseGraphEdge};
use gpodo_frontends::traverse::Traverse;
use gpodo_frontends::vo::{
    ErrorStructure, FrameRef, SimulatedVo, SimulatedVoParams, TrackOutcome, TrackPurpose,
    TrackRequest, TrackerErrorModel, VisualOdometry,
};
use gpodo_traits::BodyTwist;
use nalgebra::Isometry3;

/// Seeds (keyframes) per estimate: 6 axes each, so the variance is known
/// to about ±3 % (one standard error).
const SEEDS: u64 = 400;

/// A rover standing still for `frames` camera frames after the keyframe
/// (frame 0): every frame sees
/// exactly what the keyframe (frame 0) saw, so each measurement has the
/// floor errors σ_t0 and σ_r0.
fn standing(frames: usize) -> Traverse {
    let times: Vec<f64> = (0..=frames + 1).map(|k| 0.1 * k as f64).collect();
    let n = times.len();
    Traverse::new(
        "standing",
        times.clone(),
        vec![Isometry3::identity(); n],
        vec![BodyTwist::default(); n - 1],
        Vec::new(),
        times[..n - 1].to_vec(),
    )
    .unwrap()
}

/// The variance, over seeds and axes, of the pose graph's estimate of the
/// frames' pose from `n` frames tracked against frame 0, in units of each
/// axis' σ².
fn fused_variance(n: usize, error_model: TrackerErrorModel, share: f64) -> f64 {
    let traverse = standing(n);
    let frame = |index: usize| FrameRef {
        index,
        time_secs: traverse.camera_times_secs()[index],
    };
    let mut sum = 0.0;
    let mut count = 0;
    for seed in 0..SEEDS {
        let params = SimulatedVoParams {
            seed,
            error_model,
            map_error_share: share,
            ..SimulatedVoParams::default()
        };
        let (sigma_r, sigma_t) = (params.rotation_sigma_rad, params.translation_sigma_m);
        let mut vo = SimulatedVo::new(params, &traverse).unwrap();
        let mut graph = PoseGraph::default();
        let keyframe = graph.add_node(Isometry3::identity());
        let current = graph.add_node(Isometry3::identity());
        for j in 1..=n {
            let request = TrackRequest {
                reference: frame(0),
                current: frame(j),
                prior: Some(Isometry3::identity()),
                purpose: TrackPurpose::Tracking,
            };
            let TrackOutcome::Tracked(m) = vo.track(&request) else {
                panic!("a frame seeing what the keyframe saw is tracked");
            };
            graph.add_edge(PoseGraphEdge {
                from: keyframe,
                to: current,
                measurement: m.relative,
                covariance: m.covariance,
                kind: EdgeKind::VisualOdometry,
            });
        }
        let estimate = graph.optimize(&BackendParams::default()).unwrap().poses[current];
        let rotation = estimate.rotation.scaled_axis() / sigma_r;
        let translation = estimate.translation.vector / sigma_t;
        for e in rotation.iter().chain(translation.iter()) {
            sum += e * e;
            count += 1;
        }
    }
    sum / f64::from(count)
}

fn assert_close(measured: f64, expected: f64, what: &str) {
    // Six axes of 400 seeds: a relative standard error of 2.9 %; 12 % is
    // four of them.
    assert!(
        (measured / expected - 1.0).abs() < 0.12,
        "{what}: fused variance {measured:.4} σ², expected {expected:.4} σ²"
    );
}

#[test]
fn a_keyframes_frames_fuse_to_the_map_error_floor_not_to_zero() {
    let rho = 0.5;
    for n in [1, 4, 16] {
        let expected = rho + (1.0 - rho) / n as f64;
        let measured = fused_variance(n, TrackerErrorModel::Shared, rho);
        assert_close(measured, expected, &format!("shared, ρ = {rho}, N = {n}"));
    }
    // Fully shared: more frames do not help at all.
    assert_close(
        fused_variance(16, TrackerErrorModel::Shared, 1.0),
        1.0,
        "shared, ρ = 1, N = 16",
    );
}

#[test]
fn independent_errors_average_down_to_zero() {
    for n in [1, 4, 16] {
        let measured = fused_variance(n, TrackerErrorModel::Independent, 0.5);
        assert_close(measured, 1.0 / n as f64, &format!("independent, N = {n}"));
    }
}

#[test]
fn each_measurement_keeps_its_variance_whatever_the_share() {
    for rho in [0.0, 0.3, 1.0] {
        assert_close(
            fused_variance(1, TrackerErrorModel::Shared, rho),
            1.0,
            &format!("one frame, ρ = {rho}"),
        );
    }
}

#[test]
fn a_keyframe_graph_is_what_a_shared_error_tracker_asks_for() {
    let traverse = standing(2);
    let shared = SimulatedVo::new(SimulatedVoParams::default(), &traverse).unwrap();
    let independent = SimulatedVo::new(
        SimulatedVoParams {
            error_model: TrackerErrorModel::Independent,
            ..SimulatedVoParams::default()
        },
        &traverse,
    )
    .unwrap();
    assert_eq!(shared.error_structure(), ErrorStructure::SharedPerKeyframe);
    assert_eq!(independent.error_structure(), ErrorStructure::Independent);
}

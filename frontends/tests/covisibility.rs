//! The statistical tracker's covisible keyframes
//! (`frontends/src/vo/simulated/covisibility.rs`): its refined links are
//! the least-squares placement of the window's keyframes by their links
//! and covisible pairs, checked against the factor-graph back end solving
//! the same graph; their covariances match their errors; and where
//! keyframes see each other the links are more accurate than tracked.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use gpodo_frontends::backend::{BackendParams, EdgeKind, PoseGraph, PoseGraphEdge};
use gpodo_frontends::traverse::Traverse;
use gpodo_frontends::vo::{
    FrameRef, RefinedLink, SimulatedVo, SimulatedVoParams, TrackOutcome, TrackPurpose,
    TrackRequest, TrackerErrorModel, VisualOdometry,
};
use nalgebra::{Isometry3, Matrix6, Vector3, Vector6};

use common::traverse;

/// Keyframes every this many camera frames (12.5 Hz at 5 cm/s: 10 cm).
const SPACING: usize = 25;
/// Keyframes per drive.
const KEYFRAMES: usize = 6;

fn straight() -> Traverse {
    traverse(
        (SPACING * KEYFRAMES) as f64 * common::DT + 1.0,
        |t| (0.05 * t, 0.0, 0.0),
        Vector3::zeros(),
        &[0.0],
    )
}

fn frame(t: &Traverse, index: usize) -> FrameRef {
    FrameRef {
        index,
        time_secs: t.camera_times_secs()[index],
    }
}

/// `truth⁻¹ · estimate` as `[rotation; translation]`.
fn error(estimate: &Isometry3<f64>, truth: &Isometry3<f64>) -> Vector6<f64> {
    let d = truth.inverse() * estimate;
    let (r, t) = (d.rotation.scaled_axis(), d.translation.vector);
    Vector6::new(r.x, r.y, r.z, t.x, t.y, t.z)
}

/// Each keyframe tracked against the one before and inserted, as the front
/// end does: the tracked links `(reference, current, relative,
/// covariance)` and the last adjustment's refined links.
fn drive(vo: &mut SimulatedVo, t: &Traverse) -> (Vec<RefinedLink>, Vec<RefinedLink>) {
    let mut tracked = Vec::new();
    let mut refined = Vec::new();
    for k in 1..KEYFRAMES {
        let (reference, current) = (frame(t, (k - 1) * SPACING), frame(t, k * SPACING));
        let truth =
            t.ground_truth_at(reference.time_secs).inverse() * t.ground_truth_at(current.time_secs);
        let TrackOutcome::Tracked(m) = vo.track(&TrackRequest {
            reference,
            current,
            prior: Some(truth),
            purpose: TrackPurpose::Tracking,
        }) else {
            panic!("keyframes 10 cm apart are tracked");
        };
        tracked.push(RefinedLink {
            reference,
            current,
            relative: m.relative,
            covariance: m.covariance,
        });
        refined = vo.keyframe_inserted(current);
    }
    (tracked, refined)
}

fn tracker(seed: u64, min_overlap: f64) -> SimulatedVoParams {
    SimulatedVoParams {
        seed,
        covisibility_keyframes: 10,
        covisible_min_overlap: min_overlap,
        terrain_features: false,
        min_overlap: 0.01,
        ..SimulatedVoParams::default()
    }
}

#[test]
fn without_covisible_pairs_the_links_stand_as_tracked() {
    let t = straight();
    let mut vo = SimulatedVo::new(tracker(3, 1.0), &t).unwrap();
    let (tracked, refined) = drive(&mut vo, &t);
    assert_eq!(refined.len(), KEYFRAMES - 1);
    for (a, b) in tracked.iter().zip(&refined) {
        assert_eq!((a.reference, a.current), (b.reference, b.current));
        assert!(error(&b.relative, &a.relative).norm() < 1e-12);
        assert!((b.covariance - a.covariance).norm() < 1e-12 * a.covariance.norm());
    }
}

#[test]
fn the_refined_links_are_the_back_ends_solution_of_the_same_graph() {
    let t = straight();
    let params = tracker(5, 0.3);
    let mut vo = SimulatedVo::new(params, &t).unwrap();
    let (tracked, refined) = drive(&mut vo, &t);
    // The same graph in the factor-graph back end: the oldest keyframe
    // anchored at the truth, the tracked links and every covisible pair.
    let nodes: Vec<FrameRef> = (0..KEYFRAMES).map(|k| frame(&t, k * SPACING)).collect();
    let mut graph = PoseGraph::default();
    let mut pose = t.ground_truth_at(nodes[0].time_secs);
    graph.add_node(pose);
    for link in &tracked {
        pose *= link.relative;
        graph.add_node(pose);
    }
    let edge = |from: usize, to: usize, measurement, covariance| PoseGraphEdge {
        from,
        to,
        measurement,
        covariance,
        kind: EdgeKind::VisualOdometry,
    };
    for (k, link) in tracked.iter().enumerate() {
        graph.add_edge(edge(k, k + 1, link.relative, link.covariance));
    }
    let mut pairs = 0;
    for a in 0..KEYFRAMES {
        for b in a + 2..KEYFRAMES {
            if let Some((m, c)) = vo.covisible_measurement(nodes[a], nodes[b]) {
                graph.add_edge(edge(a, b, m, c));
                pairs += 1;
            }
        }
    }
    assert!(pairs >= 4, "{pairs} covisible pairs");
    let solved = graph.optimize(&BackendParams::default()).unwrap().poses;
    for (k, link) in refined.iter().enumerate() {
        let back_end = solved[k].inverse() * solved[k + 1];
        let d = error(&link.relative, &back_end);
        let moved = error(&link.relative, &tracked[k].relative);
        println!(
            "link {k}: moved {:.2e} m by the pairs, {:.2e} m from the back end's",
            moved.fixed_rows::<3>(3).norm(),
            d.fixed_rows::<3>(3).norm()
        );
        // First order against the exact solution: the errors' squares.
        assert!(d.fixed_rows::<3>(3).norm() < 4e-6, "{d}");
        assert!(d.fixed_rows::<3>(0).norm() < 4e-6, "{d}");
        assert!(moved.fixed_rows::<3>(3).norm() > 1e-5, "{moved}");
    }
}

/// Over `seeds` drives with independent errors: the refined links' mean
/// NEES against the truth, and their RMS translation error against the
/// tracked links' (m).
fn monte_carlo(seeds: u64, min_overlap: f64) -> (f64, f64, f64) {
    let t = straight();
    let (mut nees, mut refined_sq, mut tracked_sq, mut count) = (0.0, 0.0, 0.0, 0.0);
    for seed in 0..seeds {
        let params = SimulatedVoParams {
            error_model: TrackerErrorModel::Independent,
            ..tracker(seed, min_overlap)
        };
        let mut vo = SimulatedVo::new(params, &t).unwrap();
        let (tracked, refined) = drive(&mut vo, &t);
        for (a, b) in tracked.iter().zip(&refined) {
            let truth = t.ground_truth_at(a.reference.time_secs).inverse()
                * t.ground_truth_at(a.current.time_secs);
            let e = error(&b.relative, &truth);
            let information: Matrix6<f64> = b.covariance.try_inverse().unwrap();
            nees += (e.transpose() * information * e)[0];
            refined_sq += e.fixed_rows::<3>(3).norm_squared();
            tracked_sq += error(&a.relative, &truth).fixed_rows::<3>(3).norm_squared();
            count += 1.0;
        }
    }
    (
        nees / count,
        (refined_sq / count).sqrt(),
        (tracked_sq / count).sqrt(),
    )
}

#[test]
fn the_refined_links_covariance_matches_their_errors_and_the_pairs_help() {
    // 300 drives of five links: χ²(6) has mean 6 and standard deviation
    // 3.5, so the mean of 1500 (correlated within a drive) is 6 within
    // about ±0.2 at 1 σ.
    let (nees, refined, tracked) = monte_carlo(300, 0.3);
    println!("NEES {nees:.2}; RMS translation {tracked:.2e} m tracked, {refined:.2e} m refined");
    assert!((5.4..6.6).contains(&nees), "mean NEES {nees}");
    assert!(refined < 0.9 * tracked, "{refined} against {tracked}");
    // No pairs: the links stand as tracked, and so do their errors.
    let (nees, refined, tracked) = monte_carlo(100, 1.0);
    assert!((5.2..6.8).contains(&nees), "mean NEES {nees}");
    assert!((refined - tracked).abs() < 1e-12);
}

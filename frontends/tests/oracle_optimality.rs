//! The surrogate planner is optimal by its own cost: on every seed, for
//! both objectives, no fixed-rate schedule on its candidate grid that meets
//! its limits (gap, path, turn and tracking probability) costs less, the
//! schedules' costs integrated here from the odometry, independently of
//! the planner's gap costs.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_frontends::oracle::{OracleObjective, OracleParams, plan_frames};
use gpodo_frontends::params::MotionPrior;
use gpodo_frontends::traverse::Traverse;
use gpodo_frontends::vo::{FrameRef, SimulatedVo, TrackPurpose, TrackRequest, VisualOdometry};
use nalgebra::{Isometry3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

mod common;
use common::{earlier_tracker, traverse};

/// The drift-since-the-last-look cost of processing `frames` (camera
/// indices, the first 0) and whether every gap meets the limits.
fn schedule_cost(
    t: &Traverse,
    vo: &dyn VisualOdometry,
    params: &OracleParams,
    frames: &[usize],
) -> (f64, bool) {
    let camera = t.camera_times_secs();
    let times = t.times_secs();
    let truth = t.ground_truth();
    let first_sample_from = |time: f64| times.partition_point(|&s| s < time - 1e-12);
    let mut cost = 0.0;
    let mut allowed = true;
    for (g, &a) in frames.iter().enumerate() {
        let start = first_sample_from(camera[a]);
        let next = frames.get(g + 1).map(|&b| camera[b]);
        let end_time = next.unwrap_or(times[times.len() - 1]);
        allowed &= end_time - camera[a] <= params.max_gap_secs + 1e-9;
        let mut odometry = Isometry3::identity();
        let mut k = start;
        // Samples from the frame up to (not at) the next frame, or up to
        // the last sample for the tail.
        while k + 1 < times.len() && next.is_none_or(|tb| times[k] < tb) {
            let estimate = truth[start] * odometry;
            let drift2 = (estimate.translation.vector - truth[k].translation.vector).norm_squared();
            cost = match params.objective {
                OracleObjective::SquaredDrift => cost + drift2,
                OracleObjective::MaxDrift => f64::max(cost, drift2.sqrt()),
            };
            let rotation = truth[start].rotation.angle_to(&truth[k].rotation);
            let path = t.distance_at(k) - t.distance_at(start);
            allowed &= params.max_rotation_rad.is_none_or(|r| rotation <= r)
                && params.max_distance_m.is_none_or(|d| path <= d);
            odometry *= t.twists()[k].pose_delta(times[k + 1] - times[k]);
            k += 1;
        }
        if let Some(tb) = next {
            let (reference, current) = (
                FrameRef {
                    index: a,
                    time_secs: camera[a],
                },
                FrameRef {
                    index: frames[g + 1],
                    time_secs: tb,
                },
            );
            for prior in [Some(odometry), None] {
                let p = vo.success_probability(&TrackRequest {
                    reference,
                    current,
                    prior,
                    purpose: TrackPurpose::Tracking,
                });
                allowed &= p >= params.min_track_probability;
            }
        }
    }
    (cost, allowed)
}

#[test]
fn no_fixed_rate_schedule_on_the_grid_beats_the_plan_by_its_own_cost() {
    let mut compared = 0;
    for seed in 1..=4u64 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (turn, wobble) = (rng.random_range(0.2..0.8), rng.random_range(0.02..0.08));
        let error = Vector3::new(
            rng.random_range(-0.006..0.006),
            rng.random_range(-0.003..0.003),
            0.0,
        );
        let t = traverse(
            160.0,
            move |s| {
                let yaw = turn * (wobble * s).sin();
                (0.05 * s, 0.3 * (wobble * s).sin(), yaw)
            },
            error,
            &[0.0],
        );
        let vo = SimulatedVo::new(earlier_tracker(), &t).unwrap();
        let corrections = vec![Vector3::zeros(); t.windows().len()];
        for objective in [OracleObjective::SquaredDrift, OracleObjective::MaxDrift] {
            let params = OracleParams {
                frames: Some(40),
                max_gap_secs: 12.0,
                objective,
                ..OracleParams::default()
            };
            let plan =
                plan_frames(&t, &corrections, &vo, MotionPrior::Odometry, &params, 40).unwrap();
            // The plan's own cost, integrated here, is the one it reports.
            let (own, own_allowed) = schedule_cost(&t, &vo, &params, &plan.frames);
            assert!(own_allowed, "seed {seed}: the plan breaks its limits");
            assert!(
                (own - plan.cost).abs() <= 1e-9 * plan.cost.max(1.0),
                "seed {seed} {objective:?}: {own} vs {}",
                plan.cost
            );
            // Candidates: the camera frames 0.4 s apart (the grid).
            let camera = t.camera_times_secs();
            let mut grid = vec![0usize];
            for (i, &time) in camera.iter().enumerate().skip(1) {
                if time - camera[grid[grid.len() - 1]] >= params.candidate_period_secs - 1e-9 {
                    grid.push(i);
                }
            }
            for stride in 1..=30 {
                let frames: Vec<usize> = grid.iter().step_by(stride).copied().collect();
                if frames.len() > 40 {
                    continue;
                }
                let (cost, allowed) = schedule_cost(&t, &vo, &params, &frames);
                if !allowed {
                    continue;
                }
                compared += 1;
                assert!(
                    plan.cost <= cost * (1.0 + 1e-12),
                    "seed {seed} {objective:?}: the plan costs {} > every {stride}th candidate's {cost}",
                    plan.cost
                );
            }
        }
    }
    // The comparison is not empty: some fixed rates meet the limits.
    assert!(compared >= 8, "{compared} schedules compared");
}

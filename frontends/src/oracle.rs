//! The offline oracle: an exact dynamic programme that sees ground truth
//! and chooses which camera frames to process, for a frame budget, to
//! minimise the trajectory error — the yardstick for how good a causal
//! policy can get.
//!
//! # Model
//! Candidates are the camera frames on a grid of `candidate_period_secs`
//! (the first frame always included). If the frames `a < b` are processed
//! and nothing in between, the trajectory between them is the corrected
//! wheel odometry started from the true pose at `a`, and the gap costs
//! `C(a, b) = Σ_k ‖p̂_k − p_k‖²` over the sensor samples `t_a ≤ t_k < t_b`
//! (the squared position errors the odometry accumulates). A gap the
//! visual odometry would probably not bridge — tracking `b` from `a` with
//! the odometry prior, or matching them without a prior (the tracker's
//! reference keyframe may lie further back than `a`), succeeds with
//! probability below `min_track_probability` — or longer than
//! `max_gap_secs`, or with more
//! true rotation than `max_rotation_rad` or path than `max_distance_m` (the
//! limits of the gated schemes' turn guard), is not allowed.
//! The plan minimises `Σ C` over consecutive chosen frames plus the tail
//! after the last one, with at most `B` frames.
//!
//! # Algorithm
//! `E_m(j) = min_{j−G ≤ i < j} E_{m−1}(i) + C(i, j)`, `E_1(0) = 0`, for
//! `m = 2 … B`, `G` the candidates within `max_gap_secs`; the answer is
//! `min_{m ≤ B, j} E_m(j) + C(j, end)`, traced back through stored
//! predecessors. Exact for the model above, in `O(N G B)` time and
//! `O(N B)` memory for `N` candidates; the gap costs are integrated once,
//! `O(N G)` pose compositions.
//!
//! The plan is then run through the same front end as every causal policy
//! (visual odometry, keyframes, back end) with [`crate::gating::Planned`].
//! The model assumes a processed frame is localised exactly, so the oracle
//! is the best plan for a surrogate of the trajectory error, not a proof
//! that no policy can do better in the full pipeline. With `search:` the
//! plan is refined over the real tracker by [`crate::hindsight`], which is
//! never worse than the scheme it is matched to.

use nalgebra::{Isometry3, Vector3};
use serde::{Deserialize, Serialize};

use crate::FrontendError;
use crate::hindsight::HindsightSearchParams;
use crate::params::MotionPrior;
use crate::traverse::Traverse;
use crate::vo::{FrameRef, TrackPurpose, TrackRequest, VisualOdometry};

/// The oracle's settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OracleParams {
    /// Frame budget. Omitted, `same_as` names the scheme whose frame count
    /// is the budget.
    pub frames: Option<usize>,
    /// The label of the scheme whose processed-frame count is the budget
    /// (read by the experiment runner).
    pub same_as: Option<String>,
    /// Spacing of the candidate frames (s; default 0.4, the fastest the
    /// gated policies process).
    pub candidate_period_secs: f64,
    /// Longest allowed gap between processed frames (s; default 20).
    pub max_gap_secs: f64,
    /// Least probability that visual odometry bridges a gap (default 0.99:
    /// the oracle knows the truth and takes no risk).
    pub min_track_probability: f64,
    /// Largest true rotation between consecutive processed frames (rad;
    /// default 0.15, the turn guard of the gated schemes; null: none).
    pub max_rotation_rad: Option<f64>,
    /// Longest true path between consecutive processed frames (m; default
    /// 0.3, as the turn guard; null: none).
    pub max_distance_m: Option<f64>,
    /// Refine the plan by a hindsight search over the real tracker
    /// ([`crate::hindsight`]), starting from the better of the surrogate
    /// plan and the matched scheme's frames; omitted, the surrogate plan is
    /// run as it is.
    pub search: Option<HindsightSearchParams>,
}

impl Default for OracleParams {
    fn default() -> Self {
        Self {
            frames: None,
            same_as: None,
            candidate_period_secs: 0.4,
            max_gap_secs: 20.0,
            min_track_probability: 0.99,
            max_rotation_rad: Some(0.15),
            max_distance_m: Some(0.3),
            search: None,
        }
    }
}

impl OracleParams {
    /// Checks every field.
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] naming the field.
    pub fn validate(&self) -> Result<(), FrontendError> {
        let bad = |field: &str, expected: &str| {
            Err(FrontendError::InvalidSpec {
                selector: "oracle".into(),
                field: field.into(),
                expected: expected.into(),
            })
        };
        match (&self.frames, &self.same_as) {
            (Some(0), _) => return bad("frames", "a budget of at least 1 frame"),
            (Some(_), Some(_)) | (None, None) => {
                return bad("frames", "either `frames: N` or `same_as: <scheme label>`");
            }
            _ => {}
        }
        if !(self.candidate_period_secs.is_finite() && self.candidate_period_secs > 0.0) {
            return bad("candidate_period_secs", "a positive period in s");
        }
        if !(self.max_gap_secs.is_finite() && self.max_gap_secs >= self.candidate_period_secs) {
            return bad("max_gap_secs", "a duration at least candidate_period_secs");
        }
        if !(0.0..=1.0).contains(&self.min_track_probability) {
            return bad("min_track_probability", "a probability in [0, 1]");
        }
        for (field, v) in [
            ("max_rotation_rad", self.max_rotation_rad),
            ("max_distance_m", self.max_distance_m),
        ] {
            if let Some(v) = v
                && !(v.is_finite() && v > 0.0)
            {
                return bad(field, "a positive limit, or null");
            }
        }
        Ok(())
    }
}

/// The oracle's plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OraclePlan {
    /// Camera frame indices to process, increasing.
    pub frames: Vec<usize>,
    /// Their times (s).
    pub times_secs: Vec<f64>,
    /// The minimised cost `Σ C` (m²·samples).
    pub cost: f64,
    /// Number of candidates considered.
    pub candidates: usize,
}

/// The velocity correction in force at time `t` (that of the last window
/// that ended by then), as the causal front end has it.
fn correction_at(
    traverse: &Traverse,
    corrections: &[Vector3<f64>],
    t: f64,
) -> Option<Vector3<f64>> {
    let done = traverse.windows().partition_point(|w| w.end_secs <= t);
    done.checked_sub(1)
        .and_then(|w| corrections.get(w).copied())
}

/// The dynamic programme itself: candidates `0 … n−1`, candidate 0 always
/// chosen, `gap_cost[i·g_max + (j−i−1)]` the cost of going from `i` to
/// `j ≤ i + g_max` with nothing in between (∞ when not allowed),
/// `tail_cost[i]` the cost from `i` to the end. Returns the least total cost
/// with at most `budget` candidates and the chosen candidates in order, or
/// `None` when every plan costs ∞.
pub fn dp_plan(
    n: usize,
    g_max: usize,
    gap_cost: &[f64],
    tail_cost: &[f64],
    budget: usize,
) -> Option<(f64, Vec<usize>)> {
    if n == 0 || budget == 0 {
        return None;
    }
    let budget = budget.min(n);
    // E_m(j) over layers m = 1 … B; predecessors per layer.
    let mut best = vec![f64::INFINITY; n];
    best[0] = 0.0;
    let mut predecessors: Vec<Vec<u32>> = Vec::with_capacity(budget);
    let mut answer = (tail_cost[0], 1usize, 0usize);
    for m in 2..=budget {
        let mut layer = vec![f64::INFINITY; n];
        let mut from = vec![u32::MAX; n];
        for j in 1..n {
            for i in j.saturating_sub(g_max)..j {
                let c = best[i] + gap_cost[i * g_max + (j - i - 1)];
                if c < layer[j] {
                    layer[j] = c;
                    from[j] = i as u32;
                }
            }
            let total = layer[j] + tail_cost[j];
            if total < answer.0 {
                answer = (total, m, j);
            }
        }
        predecessors.push(from);
        best = layer;
    }
    let (cost, m, mut j) = answer;
    if !cost.is_finite() {
        return None;
    }
    let mut chosen = vec![j];
    for layer in (2..=m).rev() {
        j = predecessors[layer - 2][j] as usize;
        chosen.push(j);
    }
    chosen.reverse();
    Some((cost, chosen))
}

/// The fewest candidates (candidate 0 included) that reach the end with
/// allowed gaps, or `None` when none does: a breadth-first pass, `O(N G)`.
pub fn fewest_frames(n: usize, g_max: usize, gap_cost: &[f64], tail_cost: &[f64]) -> Option<usize> {
    let mut count = vec![usize::MAX; n];
    if n == 0 {
        return None;
    }
    count[0] = 1;
    for j in 1..n {
        for i in j.saturating_sub(g_max)..j {
            if count[i] != usize::MAX && gap_cost[i * g_max + (j - i - 1)].is_finite() {
                count[j] = count[j].min(count[i] + 1);
            }
        }
    }
    (0..n)
        .filter(|&j| count[j] != usize::MAX && tail_cost[j].is_finite())
        .map(|j| count[j])
        .min()
}

/// Plans the frames of a budget; `corrections` is the velocity correction
/// the scheme's odometry applies in each window (zero where it applies
/// none).
///
/// A budget below the fewest frames the limits allow is raised to that
/// number (with a warning).
///
/// # Errors
/// As [`OracleParams::validate`] (except the budget, given here);
/// [`FrontendError::InvalidSpec`] when no plan at all respects the gap and
/// motion limits.
pub fn plan_frames(
    traverse: &Traverse,
    corrections: &[Vector3<f64>],
    vo: &dyn VisualOdometry,
    motion_prior: MotionPrior,
    params: &OracleParams,
    budget: usize,
) -> Result<OraclePlan, FrontendError> {
    let check = OracleParams {
        frames: Some(budget.max(1)),
        same_as: None,
        ..params.clone()
    };
    check.validate()?;
    let camera = traverse.camera_times_secs();
    if camera.is_empty() {
        return Ok(OraclePlan {
            frames: Vec::new(),
            times_secs: Vec::new(),
            cost: 0.0,
            candidates: 0,
        });
    }
    // Candidate frames on the grid.
    let mut candidates = vec![0usize];
    for (i, &t) in camera.iter().enumerate().skip(1) {
        let last = camera[candidates[candidates.len() - 1]];
        if t - last >= params.candidate_period_secs - 1e-9 {
            candidates.push(i);
        }
    }
    let n = candidates.len();
    let times = traverse.times_secs();
    let end_time = times[times.len() - 1];
    let max_gap = params.max_gap_secs;
    // Gap costs C(i, i + g), g = 1 … G, and the tail cost C(i, end).
    let g_max = ((max_gap / params.candidate_period_secs).floor() as usize).max(1);
    let mut gap_cost = vec![f64::INFINITY; n * g_max];
    let mut tail_cost = vec![f64::INFINITY; n];
    for (ci, &fi) in candidates.iter().enumerate() {
        let t_start = camera[fi];
        let mut k = traverse.sample_at_or_before(t_start);
        if times[k] < t_start && k + 1 < times.len() {
            k += 1;
        }
        let start_pose = traverse.ground_truth()[k];
        let mut odometry = Isometry3::identity();
        let mut cost = 0.0;
        let mut next = ci + 1;
        let start_distance = traverse.distance_at(k);
        loop {
            let t = times[k];
            let truth = &traverse.ground_truth()[k];
            let within_limits = params
                .max_rotation_rad
                .is_none_or(|r| start_pose.rotation.angle_to(&truth.rotation) <= r)
                && params
                    .max_distance_m
                    .is_none_or(|d| traverse.distance_at(k) - start_distance <= d);
            // Close every candidate gap that ends at or before this sample.
            while next < n && next - ci <= g_max && camera[candidates[next]] <= t {
                let (a, b) = (
                    FrameRef {
                        index: fi,
                        time_secs: t_start,
                    },
                    FrameRef {
                        index: candidates[next],
                        time_secs: camera[candidates[next]],
                    },
                );
                let prior = match motion_prior {
                    MotionPrior::None => None,
                    _ => Some(odometry),
                };
                let guided = vo.success_probability(&TrackRequest {
                    reference: a,
                    current: b,
                    prior,
                    purpose: TrackPurpose::Tracking,
                });
                // The tracker's reference keyframe may lie further back
                // than the previous frame: the two frames must also match
                // without a prior (they overlap that much).
                let unaided = vo.success_probability(&TrackRequest {
                    reference: a,
                    current: b,
                    prior: None,
                    purpose: TrackPurpose::Tracking,
                });
                let p = guided.min(unaided);
                if p >= params.min_track_probability && within_limits {
                    gap_cost[ci * g_max + (next - ci - 1)] = cost;
                }
                next += 1;
            }
            if t - t_start > max_gap || k + 1 >= times.len() || !within_limits {
                if k + 1 >= times.len() && end_time - t_start <= max_gap && within_limits {
                    tail_cost[ci] = cost;
                }
                break;
            }
            let estimate = start_pose * odometry;
            cost += (estimate.translation.vector - traverse.ground_truth()[k].translation.vector)
                .norm_squared();
            let dt = times[k + 1] - t;
            let mut twist = traverse.twists()[k];
            if let Some(c) = correction_at(traverse, corrections, t) {
                twist.linear_mps += c;
            }
            odometry *= twist.pose_delta(dt);
            k += 1;
        }
    }
    // Fewer frames than the motion limits allow cannot be planned: plan the
    // fewest that can (the report shows the planned count beside the
    // budget).
    let fewest = fewest_frames(n, g_max, &gap_cost, &tail_cost);
    let budget = match fewest {
        Some(f) if f > budget => {
            tracing::warn!(
                budget,
                fewest = f,
                "oracle: the budget cannot respect the gap and motion limits; planning the fewest frames that can"
            );
            f
        }
        _ => budget,
    };
    let Some((cost, chosen)) = dp_plan(n, g_max, &gap_cost, &tail_cost, budget) else {
        return Err(FrontendError::InvalidSpec {
            selector: "oracle".into(),
            field: "frames".into(),
            expected: format!(
                "a budget that can cover the traverse with gaps of at most {max_gap} s that VO can bridge ({budget} frames cannot)"
            ),
        });
    };
    let frames: Vec<usize> = chosen.iter().map(|&c| candidates[c]).collect();
    Ok(OraclePlan {
        times_secs: frames.iter().map(|&f| camera[f]).collect(),
        frames,
        cost,
        candidates: n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Every subset containing candidate 0, by brute force.
    fn brute_force(n: usize, g_max: usize, gap: &[f64], tail: &[f64], budget: usize) -> f64 {
        let mut best = f64::INFINITY;
        for mask in 0u32..(1 << (n - 1)) {
            let chosen: Vec<usize> = std::iter::once(0)
                .chain((1..n).filter(|j| mask & (1 << (j - 1)) != 0))
                .collect();
            if chosen.len() > budget {
                continue;
            }
            let mut cost = 0.0;
            for w in chosen.windows(2) {
                let (i, j) = (w[0], w[1]);
                cost += if j - i <= g_max {
                    gap[i * g_max + (j - i - 1)]
                } else {
                    f64::INFINITY
                };
            }
            cost += tail[chosen[chosen.len() - 1]];
            best = best.min(cost);
        }
        best
    }

    #[test]
    fn the_fewest_frames_are_found() {
        // 0 → 2 → 4 → end, with 0 → 1 → 3 → end just as short.
        let inf = f64::INFINITY;
        let g_max = 2;
        let gap = vec![
            1.0, 1.0, // from 0: to 1, to 2
            inf, 1.0, // from 1: to 3
            inf, 1.0, // from 2: to 4
            inf, inf, // from 3
            inf, inf, // from 4
        ];
        let tail = vec![inf, inf, inf, 1.0, 1.0];
        assert_eq!(fewest_frames(5, g_max, &gap, &tail), Some(3));
        assert_eq!(dp_plan(5, g_max, &gap, &tail, 2), None);
        assert!(dp_plan(5, g_max, &gap, &tail, 3).is_some());
        assert_eq!(fewest_frames(5, g_max, &gap, &[inf; 5]), None);
    }

    #[test]
    fn the_programme_is_exact_against_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for trial in 0..40 {
            let n = rng.random_range(2..11);
            let g_max = rng.random_range(1..5);
            let budget = rng.random_range(1..n + 1);
            let gap: Vec<f64> = (0..n * g_max)
                .map(|_| {
                    if rng.random::<f64>() < 0.15 {
                        f64::INFINITY
                    } else {
                        rng.random_range(0.0..10.0)
                    }
                })
                .collect();
            let tail: Vec<f64> = (0..n)
                .map(|i| {
                    if n - i > g_max + 1 {
                        f64::INFINITY
                    } else {
                        rng.random_range(0.0..10.0)
                    }
                })
                .collect();
            let expected = brute_force(n, g_max, &gap, &tail, budget);
            match dp_plan(n, g_max, &gap, &tail, budget) {
                Some((cost, chosen)) => {
                    assert!(
                        (cost - expected).abs() < 1e-12,
                        "trial {trial}: {cost} vs {expected}"
                    );
                    assert_eq!(chosen[0], 0);
                    assert!(chosen.len() <= budget);
                    let recomputed: f64 = chosen
                        .windows(2)
                        .map(|w| gap[w[0] * g_max + (w[1] - w[0] - 1)])
                        .sum::<f64>()
                        + tail[chosen[chosen.len() - 1]];
                    assert!((recomputed - cost).abs() < 1e-12);
                }
                None => assert!(expected.is_infinite(), "trial {trial}: {expected}"),
            }
        }
    }
}

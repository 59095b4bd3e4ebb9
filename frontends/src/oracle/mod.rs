//! The offline oracle (the surrogate planner): an exact dynamic programme
//! that sees ground truth and chooses which camera frames to process, for
//! a frame budget, to minimise the odometry's drift between processed
//! frames.
//!
//! # What it optimises, and what it is compared on
//! Its objective is the **drift since the last look** of a rover whose
//! every processed frame is localised exactly: the sum of its squares
//! (`objective: squared_drift`, the default: the mean-square drift) or
//! its maximum (`objective: max_drift`). Reports compare it with the fixed
//! rate at equal frames on that measure, the run's
//! `drift_since_look_rms_m` or `drift_since_look_max_m`. It does not
//! optimise the trajectory RMSE: under the shared-error model most of the
//! RMSE is the keyframe chain's drift, which the objective leaves out, so
//! its RMSE says nothing about what a causal policy could reach on RMSE.
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
//!
//! The tracker tracks a frame against its reference keyframe, not against
//! the previous frame. With `keyframe_overlap` (the front end's keyframe
//! threshold) a gap `a → b` must also be bridged, with the odometry prior,
//! from the earliest candidate `r ≤ a` whose predicted overlap with `a`
//! is at least that threshold: the furthest keyframe the tracker may
//! still hold as its reference at `a` (a frame overlapping its reference
//! less becomes a keyframe itself). That keeps the programme exact over
//! pairs `(a, b)` while bounding the request the tracker will make.
//!
//! The plan minimises `Σ C` (or, for `max_drift`, `max C` with `C(a, b)`
//! the largest `‖p̂_k − p_k‖` of the gap) over consecutive chosen frames
//! plus the tail after the last one, with at most `B` frames.
//!
//! # Algorithm
//! [`dp_plan`]: `E_m(j) = min_{j−G ≤ i < j} E_{m−1}(i) ⊕ C(i, j)`,
//! `E_1(0) = 0`, for `m = 2 … B`, `G` the candidates within
//! `max_gap_secs`, `⊕` the sum or the maximum; the answer is
//! `min_{m ≤ B, j} E_m(j) ⊕ C(j, end)`, traced back through stored
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

mod programme;

pub use programme::{OracleObjective, dp_plan, fewest_frames};

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
    /// The keyframe rule's overlap threshold (the front end's
    /// `keyframes.min_overlap`): a gap must also be bridged from the
    /// furthest frame the tracker may hold as its reference keyframe (see
    /// the module documentation); null (default): from the previous frame
    /// only. Needs a visual odometry that predicts overlap (the simulated
    /// one); others plan as with null.
    pub keyframe_overlap: Option<f64>,
    /// Largest true rotation between consecutive processed frames (rad;
    /// default 0.15, the turn guard of the gated schemes; null: none).
    pub max_rotation_rad: Option<f64>,
    /// Longest true path between consecutive processed frames (m; default
    /// 0.3, as the turn guard; null: none).
    pub max_distance_m: Option<f64>,
    /// What the plan minimises (default `squared_drift`).
    pub objective: OracleObjective,
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
            keyframe_overlap: None,
            max_rotation_rad: Some(0.15),
            max_distance_m: Some(0.3),
            objective: OracleObjective::SquaredDrift,
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
        if let Some(o) = self.keyframe_overlap
            && !(o > 0.0 && o <= 1.0)
        {
            return bad("keyframe_overlap", "an overlap in (0, 1], or null");
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
    /// The minimised cost: `Σ C` (m²·samples) or `max C` (m), by the
    /// objective.
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

/// For each candidate `a`, the earliest candidate `r ≤ a` (at most
/// `scan` back) whose predicted overlap with `a`, and that of every
/// candidate between them, is at least `threshold`: the furthest keyframe
/// the tracker may hold as its reference at `a`. `a` itself without a
/// threshold or an odometry that predicts overlap.
fn furthest_references(
    vo: &dyn VisualOdometry,
    threshold: Option<f64>,
    n: usize,
    scan: usize,
    frame: impl Fn(usize) -> FrameRef,
) -> Vec<usize> {
    (0..n)
        .map(|a| {
            let Some(threshold) = threshold else {
                return a;
            };
            let mut r = a;
            while r > 0 && a - (r - 1) <= scan {
                match vo.predicted_overlap(frame(r - 1), frame(a)) {
                    Some(o) if o >= threshold => r -= 1,
                    _ => break,
                }
            }
            r
        })
        .collect()
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
    let frame = |c: usize| FrameRef {
        index: candidates[c],
        time_secs: camera[candidates[c]],
    };
    let references = furthest_references(vo, params.keyframe_overlap, n, 2 * g_max, frame);
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
                // The request from the furthest reference keyframe the
                // tracker may hold at `a`, with `a` placed exactly.
                let from_reference = (references[ci] < ci).then(|| {
                    let r = frame(references[ci]);
                    let r_from_a = traverse.ground_truth_at(r.time_secs).inverse()
                        * traverse.ground_truth_at(t_start);
                    vo.success_probability(&TrackRequest {
                        reference: r,
                        current: b,
                        prior: prior.map(|o| r_from_a * o),
                        purpose: TrackPurpose::Tracking,
                    })
                });
                let p = guided.min(unaided).min(from_reference.unwrap_or(1.0));
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
            cost = params.objective.extend(
                cost,
                (estimate.translation.vector - traverse.ground_truth()[k].translation.vector)
                    .norm_squared(),
            );
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
    let Some((cost, chosen)) = dp_plan(n, g_max, &gap_cost, &tail_cost, budget, params.objective)
    else {
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

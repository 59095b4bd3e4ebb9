//! Hindsight search over the real tracker: a local search for the frames
//! to process, at a fixed frame count, that scores every candidate schedule
//! by running the whole front end (the same visual odometry and its random
//! streams on this seed, keyframes, back end) and keeps the lowest
//! trajectory RMSE.
//!
//! # Scored on fresh draws
//! The search sees one set of tracker draws (which frames the tracker
//! loses, and each measurement's error) and chooses frames that do well
//! on them; part of its gain is that luck. A scheme therefore re-runs the
//! schedule found on an independent set of draws
//! ([`crate::params::VoSpec::with_fresh_draws`]) and reports that run.
//!
//! # What it bounds, and what not
//! The search starts from the better of the given schedules (the frames a
//! causal policy actually processed, replayed, and the surrogate oracle's
//! plan) and accepts only strict improvements, so its RMSE is never above
//! that of any schedule it starts from: matched to a causal policy
//! (`same_as`), it is never worse than that policy at that policy's frame
//! count on that seed's draws (on fresh draws it may be). It is a local
//! search, not an optimum: it bounds the
//! policies it starts from, not every causal policy, and the true hindsight
//! optimum may be lower still.
//!
//! # Moves
//! Each evaluation tries one move, drawn from a seeded generator: shift one
//! processed frame to another camera frame between its neighbours, or move
//! one processed frame into the gap where the current trajectory's position
//! error is largest (hindsight: the search sees the ground truth).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::FrontendError;
use crate::run::FrontendRun;
use crate::traverse::Traverse;

/// Settings of the search.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HindsightSearchParams {
    /// Front-end runs tried after the starting schedules (default 30).
    pub evaluations: usize,
    /// Seed of the move generator (default 0).
    pub seed: u64,
}

impl Default for HindsightSearchParams {
    fn default() -> Self {
        Self {
            evaluations: 30,
            seed: 0,
        }
    }
}

/// What the search did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SearchSummary {
    /// Which starting schedule was the better (`matched scheme` or
    /// `surrogate plan`).
    pub started_from: String,
    /// The RMSE of each starting schedule (m), in the order given.
    pub start_rmse_m: Vec<f64>,
    /// The RMSE found (m), on the tracker draws the search saw.
    pub rmse_m: f64,
    /// The RMSE of the schedule found on an independent set of tracker
    /// draws (m): what a report scores the search by (`None` until the
    /// scheme re-runs it).
    #[serde(default)]
    pub fresh_draws_rmse_m: Option<f64>,
    /// Front-end runs, starts included.
    pub evaluations: usize,
    /// Moves accepted.
    pub accepted: usize,
}

/// The best schedule found, its run and what the search did.
pub struct SearchResult {
    /// Processed frame times (s).
    pub times_secs: Vec<f64>,
    /// The run of that schedule.
    pub run: FrontendRun,
    /// The summary.
    pub summary: SearchSummary,
}

/// Position error at every sensor sample of `run`.
fn errors(traverse: &Traverse, run: &FrontendRun) -> Vec<f64> {
    traverse
        .ground_truth()
        .iter()
        .zip(&run.trajectory)
        .map(|(t, e)| (t.translation.vector - e.translation.vector).norm())
        .collect()
}

/// The camera frame times strictly between `a` and `b`.
fn between(camera: &[f64], a: f64, b: f64) -> &[f64] {
    let lo = camera.partition_point(|&t| t <= a);
    let hi = camera.partition_point(|&t| t < b);
    &camera[lo..hi.max(lo)]
}

/// One move from `times` (sorted, at least two frames); `None` when the
/// drawn move has nowhere to go.
fn propose(
    rng: &mut ChaCha8Rng,
    times: &[f64],
    camera: &[f64],
    traverse: &Traverse,
    run: &FrontendRun,
) -> Option<Vec<f64>> {
    let n = times.len();
    let end = camera.last().copied()? + 1.0;
    // The first processed frame anchors the map: it stays.
    let i = rng.random_range(1..n);
    let mut next = times.to_vec();
    if rng.random_bool(0.5) {
        let after = times.get(i + 1).copied().unwrap_or(end);
        let room = between(camera, times[i - 1], after);
        let to = *room.get(rng.random_range(0..room.len().max(1)))?;
        if to == times[i] {
            return None;
        }
        next[i] = to;
    } else {
        let e = errors(traverse, run);
        let (worst, _) = e.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
        let t_worst = traverse.times_secs()[worst];
        let j = times.partition_point(|&t| t <= t_worst).max(1) - 1;
        let gap_end = times.get(j + 1).copied().unwrap_or(end);
        let room = between(camera, times[j], gap_end);
        let mid = 0.5 * (times[j] + gap_end.min(t_worst.max(times[j])));
        let to = room
            .iter()
            .copied()
            .min_by(|a, b| (a - mid).abs().total_cmp(&(b - mid).abs()))?;
        next.remove(i);
        next.push(to);
        next.sort_by(f64::total_cmp);
        next.dedup();
        if next.len() != n {
            return None;
        }
    }
    Some(next)
}

/// Searches from `starts` (named schedules of processed frame times, each
/// sorted, all of the same length), scoring a schedule with `evaluate`.
///
/// # Errors
/// [`FrontendError::InvalidSpec`] without a starting schedule; what
/// `evaluate` reports.
pub fn search_frames(
    traverse: &Traverse,
    starts: Vec<(String, Vec<f64>)>,
    params: &HindsightSearchParams,
    mut evaluate: impl FnMut(&[f64]) -> Result<FrontendRun, FrontendError>,
) -> Result<SearchResult, FrontendError> {
    let mut best: Option<(String, Vec<f64>, FrontendRun)> = None;
    let mut start_rmse_m = Vec::new();
    let mut evaluations = 0;
    for (name, times) in starts {
        let run = evaluate(&times)?;
        evaluations += 1;
        start_rmse_m.push(run.metrics.rmse_m);
        if best
            .as_ref()
            .is_none_or(|(_, _, b)| run.metrics.rmse_m < b.metrics.rmse_m)
        {
            best = Some((name, times, run));
        }
    }
    let (started_from, mut times, mut run) = best.ok_or_else(|| FrontendError::InvalidSpec {
        selector: "oracle".into(),
        field: "search".into(),
        expected: "a schedule to start from".into(),
    })?;
    let camera = traverse.camera_times_secs();
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut accepted = 0;
    for _ in 0..params.evaluations {
        if times.len() < 2 {
            break;
        }
        let Some(candidate) = propose(&mut rng, &times, camera, traverse, &run) else {
            continue;
        };
        let tried = evaluate(&candidate)?;
        evaluations += 1;
        if tried.metrics.rmse_m < run.metrics.rmse_m {
            times = candidate;
            run = tried;
            accepted += 1;
        }
    }
    Ok(SearchResult {
        summary: SearchSummary {
            started_from,
            start_rmse_m,
            rmse_m: run.metrics.rmse_m,
            fresh_draws_rmse_m: None,
            evaluations,
            accepted,
        },
        times_secs: times,
        run,
    })
}

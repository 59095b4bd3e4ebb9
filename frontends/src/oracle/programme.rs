//! The oracle's dynamic programme over candidate frames, for either of its
//! objectives: the sum of the squared drift since the last look (the mean
//! square, up to the sample count) or its largest value (a minimax path).

use serde::{Deserialize, Serialize};

/// What the oracle minimises, given that a processed frame is localised
/// exactly (the surrogate): the drift since the last look, `‖p̂_k − p_k‖`
/// at each sensor sample `k` of the odometry started from the true pose of
/// the last processed frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OracleObjective {
    /// `Σ_k ‖p̂_k − p_k‖²` (m²·samples): the mean-square drift since the
    /// last look, scored by the run's `drift_since_look_rms_m`.
    #[default]
    SquaredDrift,
    /// `max_k ‖p̂_k − p_k‖` (m): the worst drift since the last look,
    /// scored by the run's `drift_since_look_max_m`.
    MaxDrift,
}

impl OracleObjective {
    /// A gap's cost so far, `cost`, extended by a sample whose squared
    /// drift is `drift_squared_m2`.
    pub fn extend(self, cost: f64, drift_squared_m2: f64) -> f64 {
        match self {
            Self::SquaredDrift => cost + drift_squared_m2,
            Self::MaxDrift => cost.max(drift_squared_m2.sqrt()),
        }
    }

    /// The cost of two consecutive stretches of a plan.
    pub fn combine(self, a: f64, b: f64) -> f64 {
        match self {
            Self::SquaredDrift => a + b,
            Self::MaxDrift => a.max(b),
        }
    }
}

/// The dynamic programme itself: candidates `0 … n−1`, candidate 0 always
/// chosen, `gap_cost[i·g_max + (j−i−1)]` the cost of going from `i` to
/// `j ≤ i + g_max` with nothing in between (∞ when not allowed),
/// `tail_cost[i]` the cost from `i` to the end, stretches combined by
/// `objective`. Returns the least total cost with at most `budget`
/// candidates and the chosen candidates in order, or `None` when every
/// plan costs ∞.
///
/// `E_m(j) = min_{j−G ≤ i < j} combine(E_{m−1}(i), C(i, j))`, `E_1(0) =
/// 0`; the answer is `min_{m ≤ B, j} combine(E_m(j), C(j, end))`. Exact
/// for both objectives (a sum and a maximum are both monotone in each
/// argument), in `O(N G B)` time and `O(N B)` memory.
pub fn dp_plan(
    n: usize,
    g_max: usize,
    gap_cost: &[f64],
    tail_cost: &[f64],
    budget: usize,
    objective: OracleObjective,
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
                let c = objective.combine(best[i], gap_cost[i * g_max + (j - i - 1)]);
                if c < layer[j] {
                    layer[j] = c;
                    from[j] = i as u32;
                }
            }
            let total = objective.combine(layer[j], tail_cost[j]);
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Every subset containing candidate 0, by brute force.
    fn brute_force(
        n: usize,
        g_max: usize,
        gap: &[f64],
        tail: &[f64],
        budget: usize,
        objective: OracleObjective,
    ) -> f64 {
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
                let c = if j - i <= g_max {
                    gap[i * g_max + (j - i - 1)]
                } else {
                    f64::INFINITY
                };
                cost = objective.combine(cost, c);
            }
            cost = objective.combine(cost, tail[chosen[chosen.len() - 1]]);
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
        let sum = OracleObjective::SquaredDrift;
        assert_eq!(fewest_frames(5, g_max, &gap, &tail), Some(3));
        assert_eq!(dp_plan(5, g_max, &gap, &tail, 2, sum), None);
        assert!(dp_plan(5, g_max, &gap, &tail, 3, sum).is_some());
        assert_eq!(fewest_frames(5, g_max, &gap, &[inf; 5]), None);
    }

    #[test]
    fn the_programme_is_exact_against_brute_force_for_both_objectives() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for objective in [OracleObjective::SquaredDrift, OracleObjective::MaxDrift] {
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
                let expected = brute_force(n, g_max, &gap, &tail, budget, objective);
                match dp_plan(n, g_max, &gap, &tail, budget, objective) {
                    Some((cost, chosen)) => {
                        assert!(
                            (cost - expected).abs() < 1e-12,
                            "{objective:?} trial {trial}: {cost} vs {expected}"
                        );
                        assert_eq!(chosen[0], 0);
                        assert!(chosen.len() <= budget);
                        let recomputed = chosen.windows(2).fold(0.0, |acc, w| {
                            objective.combine(acc, gap[w[0] * g_max + (w[1] - w[0] - 1)])
                        });
                        let recomputed =
                            objective.combine(recomputed, tail[chosen[chosen.len() - 1]]);
                        assert!((recomputed - cost).abs() < 1e-12);
                    }
                    None => assert!(expected.is_infinite(), "trial {trial}: {expected}"),
                }
            }
        }
    }
}

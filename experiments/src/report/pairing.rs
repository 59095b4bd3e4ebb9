//! Pairing two curves per seed at a frame budget (tables (b), (c) and
//! (d) of the curves section): each seed's curves interpolated in log
//! frames (never extrapolated), or the policy at the fixed rate's compute,
//! and the 95 % bootstrap interval of the paired difference.

use crate::report::bootstrap::{Interval, bootstrap, mean_at};
use crate::report::controls::{interpolate_log_frames, interpolate_sorted};
use crate::report::curves::{Curve, KnobPoint};
use crate::report::table::Table;

/// One curve at one budget, paired with the fixed-rate curve of its back
/// end (table (b)).
#[derive(Debug, Clone, PartialEq)]
pub struct AtBudget {
    /// Frames.
    pub budget: f64,
    /// Seeds on which both curves reach the budget (no extrapolation).
    pub seeds: Vec<u64>,
    /// The curve's RMSE at the budget per such seed.
    pub rmse: Vec<f64>,
    /// The fixed-rate RMSE at the budget per such seed.
    pub fixed: Vec<f64>,
    /// Mean RMSE and interval.
    pub rmse_mean: Option<Interval>,
    /// Mean paired difference (curve − fixed rate) and interval.
    pub difference: Option<Interval>,
}

/// Table (b) for `curve` against `fixed` (the fixed-rate curve of its back
/// end, or for table (c) its zero-residual twin; `None` for a fixed-rate
/// curve itself, whose difference is zero).
pub fn at_budget(
    curve: &Curve,
    fixed: Option<&Curve>,
    seeds: &[u64],
    budget: f64,
    seed: u64,
) -> AtBudget {
    let at = |c: &Curve, s: usize| {
        let points: Vec<(f64, f64)> = c.points.iter().map(|p| (p.frames[s], p.rmse[s])).collect();
        interpolate_log_frames(&points, budget)
    };
    let mut pairs = Vec::new();
    for (s, &seed_value) in seeds.iter().enumerate() {
        let Some(r) = at(curve, s) else { continue };
        let f = match fixed {
            Some(fc) => match at(fc, s) {
                Some(f) => f,
                None => continue,
            },
            None => r,
        };
        pairs.push((seed_value, r, f));
    }
    paired(budget, pairs, seed, fixed.is_some())
}

/// Δ at equal compute: on each seed, the compute model's cost of the
/// fixed-rate curve `fixed` at `budget` frames (linear in frames, as the
/// model is), the RMSE of `curve` at that cost (interpolated in log
/// compute on the first segment of its knob order that spans the cost,
/// [`interpolate_along_knob`]) and of `fixed` at the budget, paired as [`at_budget`] pairs them.
pub fn at_equal_compute(
    curve: &Curve,
    fixed: &Curve,
    seeds: &[u64],
    budget: f64,
    seed: u64,
) -> AtBudget {
    let mut pairs = Vec::new();
    for (s, &seed_value) in seeds.iter().enumerate() {
        let along = |c: &Curve, y: fn(&KnobPoint, usize) -> f64| -> Vec<(f64, f64)> {
            c.points.iter().map(|p| (p.frames[s], y(p, s))).collect()
        };
        let Some(cost) = interpolate_sorted(&along(fixed, |p, s| p.compute[s]), budget, |x| x)
        else {
            continue;
        };
        let Some(f) = interpolate_log_frames(&along(fixed, |p, s| p.rmse[s]), budget) else {
            continue;
        };
        let by_cost: Vec<(f64, f64)> = curve
            .points
            .iter()
            .map(|p| (p.compute[s], p.rmse[s]))
            .collect();
        let Some(r) = interpolate_along_knob(&by_cost, cost) else {
            continue;
        };
        pairs.push((seed_value, r, f));
    }
    paired(budget, pairs, seed, true)
}

/// The pairs `(seed, curve, against)` at `budget` with the mean of the
/// curve and, when `with_difference`, of the paired difference, each with
/// its bootstrap interval.
fn paired(budget: f64, pairs: Vec<(u64, f64, f64)>, seed: u64, with_difference: bool) -> AtBudget {
    let n = pairs.len();
    let mut out = AtBudget {
        budget,
        seeds: pairs.iter().map(|p| p.0).collect(),
        rmse: pairs.iter().map(|p| p.1).collect(),
        fixed: pairs.iter().map(|p| p.2).collect(),
        rmse_mean: None,
        difference: None,
    };
    if n > 0 {
        out.rmse_mean = bootstrap(n, seed, |ix| Some(mean_at(&out.rmse, ix)));
        if with_difference {
            let diff: Vec<f64> = pairs.iter().map(|p| p.1 - p.2).collect();
            out.difference = bootstrap(n, seed, |ix| Some(mean_at(&diff, ix)));
        }
    }
    out
}

/// `y` at `x` on the first segment, in knob order, of the points `(x, y)`
/// that spans `x`, linear in `ln x`; `None` when none does. A knob's
/// cost need not rise with it: a run that loses track processes frames
/// cheaply (no keyframes) and lands amid the others, so the points are
/// walked in order rather than sorted by cost.
fn interpolate_along_knob(points: &[(f64, f64)], x: f64) -> Option<f64> {
    if let Some(&(_, y)) = points.iter().find(|(a, _)| *a == x) {
        return Some(y);
    }
    points.windows(2).find_map(|w| {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        let spans = x0.min(x1) < x && x < x0.max(x1) && x0 > 0.0 && x1 > 0.0;
        (spans && y0.is_finite() && y1.is_finite()).then(|| {
            let t = (x.ln() - x0.ln()) / (x1.ln() - x0.ln());
            y0 + t * (y1 - y0)
        })
    })
}

/// Each seed's pair of `r` (a curve at budget `b` against the curve named
/// `against`) as a row of `paired`.
pub fn push_pairs(paired: &mut Table, curve: &str, against: &str, b: f64, r: &AtBudget) {
    for ((s, rm), f) in r.seeds.iter().zip(&r.rmse).zip(&r.fixed) {
        paired.push_csv(vec![
            curve.to_string(),
            against.to_string(),
            b.to_string(),
            s.to_string(),
            rm.to_string(),
            f.to_string(),
            (rm - f).to_string(),
        ]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::curves::fixtures::{curve, point};

    #[test]
    fn budgets_pair_each_seed_with_the_fixed_rate_curve_and_skip_out_of_range_seeds() {
        let gated = curve(
            vec![
                point("g1", &[200.0, 200.0, 600.0], &[0.3, 0.3, 0.3]),
                point("g2", &[800.0, 800.0, 900.0], &[0.1, 0.2, 0.1]),
            ],
            false,
            None,
        );
        let fixed = curve(
            vec![
                point("f1", &[100.0, 100.0, 100.0], &[0.4, 0.4, 0.4]),
                point("f2", &[1000.0, 1000.0, 1000.0], &[0.2, 0.2, 0.2]),
            ],
            true,
            None,
        );
        let b = at_budget(&gated, Some(&fixed), &[1, 2, 3], 400.0, 5);
        // Seed 3's gated curve starts at 600 frames: no extrapolation.
        assert_eq!(b.seeds, vec![1, 2]);
        let t = (400f64.ln() - 200f64.ln()) / (800f64.ln() - 200f64.ln());
        let g1 = 0.3 + t * (0.1 - 0.3);
        let t_f = (400f64.ln() - 100f64.ln()) / (1000f64.ln() - 100f64.ln());
        let f = 0.4 + t_f * (0.2 - 0.4);
        assert!((b.rmse[0] - g1).abs() < 1e-12 && (b.fixed[0] - f).abs() < 1e-12);
        let d = b.difference.map_or(f64::NAN, |d| d.estimate);
        let expected = ((b.rmse[0] - f) + (b.rmse[1] - f)) / 2.0;
        assert!((d - expected).abs() < 1e-12, "{d} {expected}");
        // A fixed-rate curve against nothing: no difference.
        assert_eq!(
            at_budget(&fixed, None, &[1, 2, 3], 400.0, 5).difference,
            None
        );
    }

    #[test]
    fn equal_compute_pairs_the_policy_at_the_fixed_rates_cost() {
        // The fixed rate costs 2 s a frame, the policy 1 s: at 400 frames the
        // fixed rate costs 800 s, which the policy spends at 800 frames.
        let mut fixed = curve(
            vec![
                point("f1", &[100.0], &[0.4]),
                point("f2", &[1000.0], &[0.2]),
            ],
            true,
            None,
        );
        for p in &mut fixed.points {
            p.compute = p.frames.iter().map(|f| 2.0 * f).collect();
        }
        let policy = curve(
            vec![
                point("g1", &[200.0], &[0.3]),
                point("g2", &[1600.0], &[0.1]),
            ],
            false,
            None,
        );
        let e = at_equal_compute(&policy, &fixed, &[7], 400.0, 5);
        assert_eq!(e.seeds, vec![7]);
        let t = (800f64.ln() - 200f64.ln()) / (1600f64.ln() - 200f64.ln());
        assert!((e.rmse[0] - (0.3 + t * (0.1 - 0.3))).abs() < 1e-12);
        let t_f = (400f64.ln() - 100f64.ln()) / (1000f64.ln() - 100f64.ln());
        assert!((e.fixed[0] - (0.4 + t_f * (0.2 - 0.4))).abs() < 1e-12);
        // Beyond the policy's compute: no pair.
        assert!(
            at_equal_compute(&policy, &fixed, &[7], 950.0, 5)
                .seeds
                .is_empty()
        );
        // A knob value that lost track (cheap frames, large error) after
        // the curve's dense end is not paired with: the first segment in
        // knob order that spans the cost is.
        let mut lost = policy.clone();
        lost.points.push(point("lost", &[1000.0], &[1.5]));
        let e = at_equal_compute(&lost, &fixed, &[7], 400.0, 5);
        assert!((e.rmse[0] - (0.3 + t * (0.1 - 0.3))).abs() < 1e-12);
    }
}

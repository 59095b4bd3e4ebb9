//! Percentile bootstrap over seeds: the resampling behind every interval
//! of the frames-versus-error curves. Seeded, so the same records give the
//! same intervals.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Resamples drawn per interval.
pub const RESAMPLES: usize = 2000;

/// A statistic with its 95 % percentile-bootstrap interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// The statistic on the data as observed.
    pub estimate: f64,
    /// 2.5 % percentile of the resampled statistic.
    pub low: f64,
    /// 97.5 % percentile.
    pub high: f64,
    /// Share of resamples on which the statistic was defined (1 when it
    /// always is; below 1 the interval is over the defined ones only).
    pub defined: f64,
}

/// The statistic `stat` of `n` units (seeds) and its 95 % interval from
/// [`RESAMPLES`] resamples of the units with replacement; `stat` receives
/// the indices of a resample (with repeats) and may return `None` when it
/// is undefined on it. `None` when it is undefined on the data itself.
pub fn bootstrap(n: usize, seed: u64, stat: impl Fn(&[usize]) -> Option<f64>) -> Option<Interval> {
    let all: Vec<usize> = (0..n).collect();
    let estimate = stat(&all)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut draws = Vec::with_capacity(RESAMPLES);
    let mut sample = vec![0; n];
    for _ in 0..RESAMPLES {
        for s in sample.iter_mut() {
            *s = rng.random_range(0..n);
        }
        if let Some(v) = stat(&sample).filter(|v| v.is_finite()) {
            draws.push(v);
        }
    }
    if draws.is_empty() {
        return Some(Interval {
            estimate,
            low: f64::NAN,
            high: f64::NAN,
            defined: 0.0,
        });
    }
    draws.sort_by(f64::total_cmp);
    let at = |q: f64| draws[((q * draws.len() as f64).floor() as usize).min(draws.len() - 1)];
    Some(Interval {
        estimate,
        low: at(0.025),
        high: at(0.975),
        defined: draws.len() as f64 / RESAMPLES as f64,
    })
}

/// The mean of `values` at `indices`.
pub fn mean_at(values: &[f64], indices: &[usize]) -> f64 {
    indices.iter().map(|&i| values[i]).sum::<f64>() / indices.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_interval_of_a_mean_matches_the_normal_approximation() {
        // 40 values with known mean and std: the bootstrap interval of the
        // mean is close to mean ± 1.96 std / sqrt(n).
        let values: Vec<f64> = (0..40).map(|i| (i as f64 * 0.7).sin()).collect();
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let std = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
        let half = 1.96 * std / n.sqrt();
        let i = bootstrap(values.len(), 1, |ix| Some(mean_at(&values, ix)));
        let i = i.unwrap_or(Interval {
            estimate: f64::NAN,
            low: f64::NAN,
            high: f64::NAN,
            defined: 0.0,
        });
        assert!((i.estimate - mean).abs() < 1e-12);
        assert!((i.low - (mean - half)).abs() < 0.25 * half, "{i:?} {half}");
        assert!((i.high - (mean + half)).abs() < 0.25 * half, "{i:?} {half}");
        assert_eq!(i.defined, 1.0);
        // Same seed, same interval; undefined statistic, no interval.
        assert_eq!(
            bootstrap(values.len(), 1, |ix| Some(mean_at(&values, ix))),
            Some(i)
        );
        assert_eq!(bootstrap(3, 1, |_| None), None);
    }
}

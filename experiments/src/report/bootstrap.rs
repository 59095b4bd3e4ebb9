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
    bootstrap_with_p(n, seed, stat).map(|(interval, _)| interval)
}

/// [`bootstrap`] with the p-value of the statistic being zero: twice the
/// smaller share of resamples on either side of zero (at most 1), the
/// smallest level whose percentile interval excludes zero. With
/// [`RESAMPLES`] draws it resolves down to 1/1000; a share of 0 reads as
/// p < 0.001.
pub fn bootstrap_with_p(
    n: usize,
    seed: u64,
    stat: impl Fn(&[usize]) -> Option<f64>,
) -> Option<(Interval, f64)> {
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
        let interval = Interval {
            estimate,
            low: f64::NAN,
            high: f64::NAN,
            defined: 0.0,
        };
        return Some((interval, f64::NAN));
    }
    draws.sort_by(f64::total_cmp);
    let at = |q: f64| draws[((q * draws.len() as f64).floor() as usize).min(draws.len() - 1)];
    let count = draws.len() as f64;
    let below = draws.iter().filter(|&&v| v <= 0.0).count() as f64 / count;
    let above = draws.iter().filter(|&&v| v >= 0.0).count() as f64 / count;
    let interval = Interval {
        estimate,
        low: at(0.025),
        high: at(0.975),
        defined: draws.len() as f64 / RESAMPLES as f64,
    };
    Some((interval, (2.0 * below.min(above)).min(1.0)))
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

    #[test]
    fn the_p_value_matches_the_normal_approximation() {
        // 30 values shifted so that the mean is 2.2 standard errors above
        // zero: the two-sided normal p-value is 0.0278; the bootstrap's
        // is within sampling error of it, and far from 0 or 1.
        let raw: Vec<f64> = (0..30).map(|i| (f64::from(i) * 1.3).sin()).collect();
        let n = raw.len() as f64;
        let mean = raw.iter().sum::<f64>() / n;
        let std = (raw.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
        let values: Vec<f64> = raw
            .iter()
            .map(|v| v - mean + 2.2 * std / n.sqrt())
            .collect();
        let Some((i, p)) = bootstrap_with_p(values.len(), 7, |ix| Some(mean_at(&values, ix)))
        else {
            panic!("the mean is defined");
        };
        assert!(i.low > 0.0, "{i:?}");
        assert!((0.01..0.06).contains(&p), "{p}");
        // Centred data: p near 1; all resamples above zero: p = 0.
        let centred: Vec<f64> = raw.iter().map(|v| v - mean).collect();
        let p_centred = bootstrap_with_p(30, 7, |ix| Some(mean_at(&centred, ix))).map(|x| x.1);
        assert!(p_centred.is_some_and(|p| p > 0.8), "{p_centred:?}");
        let positive: Vec<f64> = (1..=10).map(f64::from).collect();
        let p_positive = bootstrap_with_p(10, 7, |ix| Some(mean_at(&positive, ix))).map(|x| x.1);
        assert_eq!(p_positive, Some(0.0));
    }
}

//! Exact, distribution-free inference on paired differences, for counts
//! (tracking losses) where a bootstrap of the mean is not the right tool:
//! the sign test and the order-statistic interval of the median, both
//! from the binomial distribution with p = ½.

/// P(X ≤ k) for X ~ Binomial(n, ½), summed in log space.
pub fn binomial_half_cdf(k: usize, n: usize) -> f64 {
    if k >= n {
        return 1.0;
    }
    let ln_half_n = n as f64 * std::f64::consts::LN_2;
    let mut ln_choose = 0.0;
    let mut total = 0.0;
    for i in 0..=k {
        if i > 0 {
            ln_choose += ((n - i + 1) as f64).ln() - (i as f64).ln();
        }
        total += (ln_choose - ln_half_n).exp();
    }
    total.min(1.0)
}

/// The two-sided exact sign test of a zero median: differences equal to
/// zero are dropped; the p-value is twice the smaller binomial tail (at
/// most 1). 1 when every difference is zero.
pub fn sign_test(differences: &[f64]) -> f64 {
    let positive = differences.iter().filter(|&&d| d > 0.0).count();
    let negative = differences.iter().filter(|&&d| d < 0.0).count();
    let n = positive + negative;
    if n == 0 {
        return 1.0;
    }
    (2.0 * binomial_half_cdf(positive.min(negative), n)).min(1.0)
}

/// The median of `values` with its exact distribution-free interval
/// `[x_(k), x_(n+1−k)]`, `k` the largest order whose coverage
/// 1 − 2 P(X ≤ k − 1) is at least `level`: `(median, low, high,
/// coverage)`. `None` for fewer than six values, where no such interval
/// reaches 95 % (coverage 1 − 2⁻ⁿ⁺¹ < 0.95 for n ≤ 5).
pub fn median_interval(values: &[f64], level: f64) -> Option<(f64, f64, f64, f64)> {
    let n = values.len();
    let mut sorted: Vec<f64> = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = if n % 2 == 1 {
        sorted[n / 2]
    } else if n > 0 {
        0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
    } else {
        return None;
    };
    let coverage = |k: usize| 1.0 - 2.0 * binomial_half_cdf(k - 1, n);
    let mut k = 0;
    while k < n / 2 && coverage(k + 1) >= level {
        k += 1;
    }
    (k >= 1).then(|| (median, sorted[k - 1], sorted[n - k], coverage(k)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn choose(n: u64, k: u64) -> f64 {
        (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
    }

    #[test]
    fn the_binomial_tail_matches_its_closed_form() {
        for n in [1u64, 5, 10, 20, 37] {
            let mut cumulative = 0.0;
            for k in 0..=n {
                cumulative += choose(n, k) / 2f64.powi(n as i32);
                let got = binomial_half_cdf(k as usize, n as usize);
                assert!(
                    (got - cumulative).abs() < 1e-12,
                    "n {n} k {k}: {got} {cumulative}"
                );
            }
        }
    }

    #[test]
    fn the_sign_test_matches_hand_computed_values() {
        // 9 of 10 negative: p = 2 (1 + 10) / 1024.
        let mut d = vec![-1.0; 9];
        d.push(2.0);
        assert!((sign_test(&d) - 22.0 / 1024.0).abs() < 1e-15);
        // Zeros are dropped: the same with three ties added.
        d.extend([0.0, 0.0, 0.0]);
        assert!((sign_test(&d) - 22.0 / 1024.0).abs() < 1e-15);
        // Balanced signs and all ties: no evidence.
        assert_eq!(sign_test(&[1.0, -1.0]), 1.0);
        assert_eq!(sign_test(&[0.0, 0.0]), 1.0);
    }

    #[test]
    fn the_median_interval_uses_the_tabulated_orders() {
        // n = 20: k = 6 (x_(6), x_(15)), coverage 1 − 2 P(X ≤ 5) = 0.9586;
        // n = 10: k = 2, coverage 0.9785 (standard tables).
        let values: Vec<f64> = (1..=20).map(f64::from).collect();
        let Some((median, low, high, coverage)) = median_interval(&values, 0.95) else {
            panic!("20 values have an interval");
        };
        assert_eq!((median, low, high), (10.5, 6.0, 15.0));
        assert!((coverage - 0.958_610_5).abs() < 1e-6, "{coverage}");
        let ten: Vec<f64> = (1..=10).rev().map(f64::from).collect();
        let Some((_, low, high, coverage)) = median_interval(&ten, 0.95) else {
            panic!("10 values have an interval");
        };
        assert_eq!((low, high), (2.0, 9.0));
        assert!((coverage - 0.978_515_6).abs() < 1e-6, "{coverage}");
        assert_eq!(median_interval(&[1.0, 2.0, 3.0, 4.0, 5.0], 0.95), None);
    }
}

//! Latency statistics of timed operations, shared by `gpodo bench` and the
//! prequential protocol.

use serde::{Deserialize, Serialize};

/// Latency statistics (µs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Latency {
    /// Timed operations.
    pub count: usize,
    /// Median (µs).
    pub median_us: f64,
    /// 95th percentile (µs).
    pub p95_us: f64,
    /// 99th percentile (µs).
    #[serde(default)]
    pub p99_us: f64,
    /// Mean (µs).
    pub mean_us: f64,
}

impl Latency {
    /// Statistics of `samples_us`.
    pub fn of(mut samples_us: Vec<f64>) -> Self {
        samples_us.sort_by(f64::total_cmp);
        let n = samples_us.len();
        let at = |q: f64| {
            if n == 0 {
                f64::NAN
            } else {
                samples_us[((q * (n - 1) as f64).round() as usize).min(n - 1)]
            }
        };
        Self {
            count: n,
            median_us: at(0.5),
            p95_us: at(0.95),
            p99_us: at(0.99),
            mean_us: samples_us.iter().sum::<f64>() / n.max(1) as f64,
        }
    }
}

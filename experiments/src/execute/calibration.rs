//! Statistics of a residual table that say whether a simulated testbed
//! behaves like the real rover (see `shared/data/README.md`): residual
//! magnitudes per axis, how much of the time the rover moves, slip relative
//! to wheel speed, and how residuals grow with slope. The same function is
//! applied to the simulated and to the real table, so the comparison is like
//! for like (1-s means, absolute values).

use gpodo_datasets::table::{percentile, summarize_abs};
use gpodo_traits::ResidualDataset;
use serde::{Deserialize, Serialize};

/// Rows whose mean wheel speed is below this count as standing (m/s).
pub const MOVING_THRESHOLD_MPS: f64 = 0.005;

/// Residual statistics of one table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResidualStatistics {
    /// Rows.
    pub n_rows: usize,
    /// Mean |residual| per target (target units).
    pub mean_abs: Vec<f64>,
    /// 95th percentile of |residual| per target.
    pub p95_abs: Vec<f64>,
    /// Fraction of rows in which the rover moves.
    pub moving_fraction: Option<f64>,
    /// Mean wheel translational speed over moving rows (m/s).
    pub mean_wheel_speed_moving_mps: Option<f64>,
    /// Median over moving rows of |residual_x| / wheel speed.
    pub median_slip_ratio_x: Option<f64>,
    /// Pearson correlation of |residual_x| with |pitch|.
    pub corr_abs_x_abs_pitch: Option<f64>,
    /// Pearson correlation of |residual_x| with |roll|.
    pub corr_abs_x_abs_roll: Option<f64>,
    /// Root mean square of each target.
    #[serde(default)]
    pub rms: Vec<f64>,
    /// Each target's noise standard deviation estimated from successive
    /// rows, `sqrt(mean((y[k+1] − y[k])²) / 2)`: right for noise that is
    /// independent from row to row on top of a residual that changes slowly.
    /// Close to [`Self::rms`], the residual is mostly noise at the rows'
    /// rate, and no regressor can predict it from any input.
    #[serde(default)]
    pub noise_sd: Vec<f64>,
}

/// The successive-difference noise estimate of a series (0 for fewer than
/// two values).
pub fn successive_difference_sd(y: &[f64]) -> f64 {
    if y.len() < 2 {
        return 0.0;
    }
    let sum: f64 = y.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum();
    (0.5 * sum / (y.len() - 1) as f64).sqrt()
}

fn pearson(a: &[f64], b: &[f64]) -> Option<f64> {
    let n = a.len() as f64;
    if a.len() < 2 {
        return None;
    }
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    (va > 0.0 && vb > 0.0).then(|| cov / (va * vb).sqrt())
}

/// Computes the statistics; the slope and speed figures need columns named
/// `pitch`, `roll` and `*_transl` (wheel speeds), as in the authors' table
/// and gpodo's residual datasets.
pub fn residual_statistics(data: &ResidualDataset) -> ResidualStatistics {
    let o = data.targets.ncols();
    let abs_col =
        |j: usize| -> Vec<f64> { data.targets.column(j).iter().map(|v| v.abs()).collect() };
    let summary = summarize_abs(data);
    let mean_abs = summary.iter().map(|c| c.mean_abs).collect();
    let p95_abs = summary.iter().map(|c| c.p95_abs).collect();

    let index = |name: &str| data.input_names.iter().position(|n| n == name);
    // The wheels' translational speeds or, for a robot logged without
    // joints, its own odometry's forward speed.
    let mut wheel_cols: Vec<usize> = data
        .input_names
        .iter()
        .enumerate()
        .filter(|(_, n)| n.ends_with("_transl"))
        .map(|(i, _)| i)
        .collect();
    if wheel_cols.is_empty() {
        wheel_cols.extend(index("odom_vx"));
    }
    let speed: Option<Vec<f64>> = (!wheel_cols.is_empty()).then(|| {
        data.inputs
            .rows()
            .map(|r| wheel_cols.iter().map(|&c| r[c].abs()).sum::<f64>() / wheel_cols.len() as f64)
            .collect()
    });
    let res_x = if o > 0 { abs_col(0) } else { Vec::new() };
    let moving: Option<Vec<usize>> = speed.as_ref().map(|s| {
        (0..s.len())
            .filter(|&i| s[i] > MOVING_THRESHOLD_MPS)
            .collect()
    });
    let abs_input = |name: &str| {
        index(name).map(|c| {
            data.inputs
                .column(c)
                .iter()
                .map(|v| v.abs())
                .collect::<Vec<f64>>()
        })
    };
    ResidualStatistics {
        n_rows: data.len(),
        mean_abs,
        p95_abs,
        moving_fraction: moving
            .as_ref()
            .map(|m| m.len() as f64 / data.len().max(1) as f64),
        mean_wheel_speed_moving_mps: speed
            .as_ref()
            .zip(moving.as_ref())
            .map(|(s, m)| m.iter().map(|&i| s[i]).sum::<f64>() / m.len().max(1) as f64),
        median_slip_ratio_x: speed.as_ref().zip(moving.as_ref()).and_then(|(s, m)| {
            let ratios: Vec<f64> = m.iter().map(|&i| res_x[i] / s[i]).collect();
            (!ratios.is_empty()).then(|| percentile(&ratios, 50.0))
        }),
        corr_abs_x_abs_pitch: abs_input("pitch").and_then(|p| pearson(&res_x, &p)),
        corr_abs_x_abs_roll: abs_input("roll").and_then(|r| pearson(&res_x, &r)),
        rms: (0..o)
            .map(|j| {
                let c = data.targets.column(j);
                (c.iter().map(|v| v * v).sum::<f64>() / c.len().max(1) as f64).sqrt()
            })
            .collect(),
        noise_sd: (0..o)
            .map(|j| successive_difference_sd(&data.targets.column(j)))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn successive_differences_see_white_noise_and_not_a_slow_trend() {
        // Alternating ±1: independent-looking noise of standard deviation 1.
        let noise: Vec<f64> = (0..1000)
            .map(|k| if k % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        // sqrt(4 / 2) = √2 for a perfectly alternating series.
        assert!((successive_difference_sd(&noise) - 2f64.sqrt()).abs() < 1e-12);
        // A slow ramp from 0 to 1: almost no noise.
        let ramp: Vec<f64> = (0..1000).map(|k| k as f64 / 999.0).collect();
        assert!(successive_difference_sd(&ramp) < 1e-3);
        assert_eq!(successive_difference_sd(&[3.0]), 0.0);
    }

    #[test]
    fn pearson_of_proportional_series_is_one() {
        assert!((pearson(&[1.0, 2.0, 3.0], &[2.0, 4.0, 6.0]).unwrap() - 1.0).abs() < 1e-15);
        assert!(pearson(&[1.0, 1.0], &[2.0, 3.0]).is_none());
    }
}

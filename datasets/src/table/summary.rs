//! Per-axis residual magnitudes (mean and 95th percentile of `|y|`), the
//! figures used to compare a simulated testbed with the real rover.

use gpodo_traits::ResidualDataset;
use serde::{Deserialize, Serialize};

/// Magnitude statistics of one target column.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColumnSummary {
    /// The target column's name.
    pub name: String,
    /// Mean of `|y|` (target units).
    pub mean_abs: f64,
    /// 95th percentile of `|y|` (target units), linear interpolation between
    /// order statistics as numpy's default `percentile`.
    pub p95_abs: f64,
}

/// Mean and 95th percentile of `|y|` for each target column of `data`, in
/// target order. Both are NaN for a dataset without rows.
pub fn summarize_abs(data: &ResidualDataset) -> Vec<ColumnSummary> {
    data.target_names
        .iter()
        .enumerate()
        .map(|(j, name)| {
            let mut abs: Vec<f64> = data.targets.column(j).iter().map(|y| y.abs()).collect();
            abs.sort_by(f64::total_cmp);
            ColumnSummary {
                name: name.clone(),
                mean_abs: abs.iter().sum::<f64>() / abs.len() as f64,
                p95_abs: percentile_sorted(&abs, 95.0),
            }
        })
        .collect()
}

/// The `q`-th percentile (0–100) of unsorted `values`, as
/// [`percentile_sorted`] (numpy's default); NaN when `values` is empty.
pub fn percentile(values: &[f64], q: f64) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    percentile_sorted(&sorted, q)
}

/// The `q`-th percentile (0–100) of ascending `sorted` values, interpolating
/// linearly between the order statistics at ranks `⌊h⌋` and `⌈h⌉`,
/// `h = (n − 1)·q/100` (numpy's default). NaN when `sorted` is empty.
pub fn percentile_sorted(sorted: &[f64], q: f64) -> f64 {
    let Some(last) = sorted.len().checked_sub(1) else {
        return f64::NAN;
    };
    let h = last as f64 * q / 100.0;
    let lo = h.floor() as usize;
    let hi = h.ceil() as usize;
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

#[cfg(test)]
mod tests {
    use approx::assert_relative_eq;
    use gpodo_traits::SampleMatrix;

    use super::*;

    #[test]
    fn percentile_matches_numpy_linear_interpolation() {
        // numpy.percentile([1, 2, 3, 4], 95) == 3.85; of [7], 7.
        assert_relative_eq!(percentile_sorted(&[1.0, 2.0, 3.0, 4.0], 95.0), 3.85);
        assert_eq!(percentile_sorted(&[7.0], 95.0), 7.0);
        assert_eq!(percentile_sorted(&[1.0, 2.0, 3.0], 100.0), 3.0);
        assert!(percentile_sorted(&[], 95.0).is_nan());
    }

    #[test]
    fn summarizes_absolute_values_of_each_target() {
        let x = SampleMatrix::zeros(4, 1);
        let y = SampleMatrix::from_rows(2, &[[-1.0, 0.0], [2.0, 0.0], [-3.0, 1.0], [4.0, -1.0]])
            .unwrap();
        let data =
            ResidualDataset::new(x, y, vec!["x".into()], vec!["a".into(), "b".into()]).unwrap();
        let summary = summarize_abs(&data);
        assert_eq!(summary.len(), 2);
        assert_eq!(summary[0].name, "a");
        assert_relative_eq!(summary[0].mean_abs, 2.5);
        assert_relative_eq!(summary[0].p95_abs, 3.85);
        assert_relative_eq!(summary[1].mean_abs, 0.5);
        assert_relative_eq!(summary[1].p95_abs, 1.0);
    }
}

//! The time-ordered train/test split of gpodo's configurations: the first
//! part of a run trains, the rest tests (no shuffling, so no sample of the
//! test period leaks into training).

use gpodo_traits::ResidualDataset;

use crate::DatasetError;

/// Splits `data` in time order: the first `⌊f·n⌋` rows train, the rest test
/// (`f = train_fraction`, computed as `(f * n as f64).floor()`).
///
/// # Errors
/// [`DatasetError::InvalidConfig`] for `train_fraction` when it is not in
/// the open interval (0, 1) or when either part would be empty.
pub fn split_fraction(
    data: &ResidualDataset,
    train_fraction: f64,
) -> Result<(ResidualDataset, ResidualDataset), DatasetError> {
    if !(train_fraction > 0.0 && train_fraction < 1.0) {
        return Err(invalid_fraction(format!(
            "a fraction in (0, 1), found {train_fraction}"
        )));
    }
    let n = data.len();
    let n_train = (train_fraction * n as f64).floor() as usize;
    if n_train == 0 || n_train >= n {
        return Err(invalid_fraction(format!(
            "a fraction that leaves both parts of {n} rows non-empty, found {train_fraction} ({n_train} train rows)"
        )));
    }
    let train: Vec<usize> = (0..n_train).collect();
    let test: Vec<usize> = (n_train..n).collect();
    Ok((data.select(&train), data.select(&test)))
}

/// An [`DatasetError::InvalidConfig`] for `train_fraction`.
fn invalid_fraction(expected: String) -> DatasetError {
    DatasetError::InvalidConfig {
        field: "train_fraction".to_string(),
        expected,
    }
}

#[cfg(test)]
mod tests {
    use gpodo_traits::SampleMatrix;

    use super::*;

    fn ramp(n: usize) -> ResidualDataset {
        let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let y: Vec<f64> = x.iter().map(|v| 10.0 * v).collect();
        ResidualDataset::new(
            SampleMatrix::from_row_major(n, 1, x).unwrap(),
            SampleMatrix::from_row_major(n, 1, y).unwrap(),
            vec!["x".into()],
            vec!["y".into()],
        )
        .unwrap()
    }

    #[test]
    fn keeps_time_order_with_floor_of_fraction_for_training() {
        let (train, test) = split_fraction(&ramp(10), 0.75).unwrap();
        assert_eq!(train.inputs.column(0), [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(test.inputs.column(0), [7.0, 8.0, 9.0]);
        assert_eq!(test.targets.column(0), [70.0, 80.0, 90.0]);
        assert_eq!(train.input_names, ["x"]);
    }

    #[test]
    fn rejects_fraction_outside_open_unit_interval() {
        for f in [0.0, 1.0, -0.5, 1.5, f64::NAN] {
            let err = split_fraction(&ramp(10), f).unwrap_err();
            assert!(
                matches!(&err, DatasetError::InvalidConfig { field, .. } if field == "train_fraction"),
                "{f}: {err}"
            );
        }
    }

    #[test]
    fn rejects_split_leaving_a_part_empty() {
        assert!(split_fraction(&ramp(3), 0.2).is_err());
        assert!(split_fraction(&ramp(1), 0.99).is_err());
        assert!(split_fraction(&ramp(0), 0.5).is_err());
    }
}

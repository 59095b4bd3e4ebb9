//! Rows of a stream an online learner keeps before it can learn them (the
//! sparse-spectrum GP's warm-up, the streaming sparse GP's first batch):
//! what it predicts meanwhile, and the rows as a dataset once there are
//! enough.

use gpodo_traits::{Error, Predictions, ResidualDataset, SampleMatrix};

/// Input and target rows, in arrival order.
pub(crate) type Rows = [(Vec<f64>, Vec<f64>)];

/// `rows` as a dataset with placeholder column names (`x0…`, `y0…`).
pub(crate) fn rows_dataset(rows: &Rows) -> Result<ResidualDataset, Error> {
    let (d, p) = rows.first().map_or((0, 0), |(x, y)| (x.len(), y.len()));
    let inputs: Vec<&[f64]> = rows.iter().map(|r| r.0.as_slice()).collect();
    let targets: Vec<&[f64]> = rows.iter().map(|r| r.1.as_slice()).collect();
    ResidualDataset::new(
        SampleMatrix::from_rows(d, &inputs)?,
        SampleMatrix::from_rows(p, &targets)?,
        (0..d).map(|j| format!("x{j}")).collect(),
        (0..p).map(|j| format!("y{j}")).collect(),
    )
}

/// The kept rows' target mean and variance per output, for each row of
/// `inputs` (with one row, its square as the variance);
/// [`Error::NotFitted`] naming `model` before any row.
pub(crate) fn running_moments(
    model: &str,
    rows: &Rows,
    inputs: &SampleMatrix,
) -> Result<Predictions, Error> {
    let Some((_, y0)) = rows.first() else {
        return Err(Error::NotFitted {
            model: model.into(),
        });
    };
    let (n, p) = (rows.len() as f64, y0.len());
    let mean: Vec<f64> = (0..p)
        .map(|j| rows.iter().map(|r| r.1[j]).sum::<f64>() / n)
        .collect();
    let variance: Vec<f64> = (0..p)
        .map(|j| {
            let spread: f64 = rows.iter().map(|r| (r.1[j] - mean[j]).powi(2)).sum();
            if n > 1.0 {
                spread / (n - 1.0)
            } else {
                mean[j] * mean[j]
            }
        })
        .collect();
    let q = inputs.nrows();
    Ok(Predictions {
        mean: SampleMatrix::from_row_major(q, p, mean.repeat(q))?,
        variance: SampleMatrix::from_row_major(q, p, variance.repeat(q))?,
    })
}

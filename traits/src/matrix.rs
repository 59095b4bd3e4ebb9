//! A small row-major matrix of samples: one row per sample, one column per
//! feature. It keeps this crate free of a linear-algebra dependency for data
//! that is only stored and passed on; regressors convert at their boundary.

use serde::{Deserialize, Serialize};

use crate::Error;

/// `nrows × ncols` values stored row by row (one sample per row).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SampleMatrix {
    nrows: usize,
    ncols: usize,
    data: Vec<f64>,
}

impl SampleMatrix {
    /// Builds a matrix from row-major data.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] when `data.len() != nrows * ncols`.
    pub fn from_row_major(nrows: usize, ncols: usize, data: Vec<f64>) -> Result<Self, Error> {
        let expected = nrows.checked_mul(ncols).ok_or_else(|| {
            Error::InvalidInput(format!("matrix shape {nrows}×{ncols} overflows"))
        })?;
        if data.len() != expected {
            return Err(Error::DimensionMismatch {
                what: format!("row-major data of a {nrows}×{ncols} matrix"),
                expected,
                found: data.len(),
            });
        }
        Ok(Self { nrows, ncols, data })
    }

    /// A matrix of zeros.
    pub fn zeros(nrows: usize, ncols: usize) -> Self {
        Self {
            nrows,
            ncols,
            data: vec![0.0; nrows * ncols],
        }
    }

    /// Builds a matrix from rows that must all have `ncols` entries.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] naming the first row of the wrong length.
    pub fn from_rows<R: AsRef<[f64]>>(ncols: usize, rows: &[R]) -> Result<Self, Error> {
        let mut data = Vec::with_capacity(rows.len() * ncols);
        for (i, row) in rows.iter().enumerate() {
            let row = row.as_ref();
            if row.len() != ncols {
                return Err(Error::DimensionMismatch {
                    what: format!("row {i}"),
                    expected: ncols,
                    found: row.len(),
                });
            }
            data.extend_from_slice(row);
        }
        Ok(Self {
            nrows: rows.len(),
            ncols,
            data,
        })
    }

    /// Number of rows (samples).
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Number of columns (features or outputs).
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Row `i`; panics if `i >= nrows` like slice indexing.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.data[i * self.ncols..(i + 1) * self.ncols]
    }

    /// Mutable row `i`; panics if `i >= nrows` like slice indexing.
    pub fn row_mut(&mut self, i: usize) -> &mut [f64] {
        &mut self.data[i * self.ncols..(i + 1) * self.ncols]
    }

    /// Iterates over the rows.
    pub fn rows(&self) -> impl ExactSizeIterator<Item = &[f64]> + '_ {
        // `chunks_exact(0)` panics, so a matrix without columns yields empty rows.
        let ncols = self.ncols;
        (0..self.nrows).map(move |i| &self.data[i * ncols..(i + 1) * ncols])
    }

    /// Element `(i, j)`.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.data[i * self.ncols + j]
    }

    /// Column `j` copied into a vector.
    pub fn column(&self, j: usize) -> Vec<f64> {
        self.rows().map(|r| r[j]).collect()
    }

    /// The row-major storage.
    pub fn as_slice(&self) -> &[f64] {
        &self.data
    }

    /// The rows with the given indices, in that order.
    pub fn select_rows(&self, indices: &[usize]) -> Self {
        let mut data = Vec::with_capacity(indices.len() * self.ncols);
        for &i in indices {
            data.extend_from_slice(self.row(i));
        }
        Self {
            nrows: indices.len(),
            ncols: self.ncols,
            data,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_data_of_the_wrong_length() {
        let err = SampleMatrix::from_row_major(2, 3, vec![0.0; 5]).unwrap_err();
        assert!(matches!(
            err,
            Error::DimensionMismatch {
                expected: 6,
                found: 5,
                ..
            }
        ));
    }

    #[test]
    fn rows_and_columns_index_row_major_storage() {
        let m = SampleMatrix::from_rows(2, &[[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]]).unwrap();
        assert_eq!(m.row(1), &[3.0, 4.0]);
        assert_eq!(m.column(1), vec![2.0, 4.0, 6.0]);
        assert_eq!(m.get(2, 0), 5.0);
        assert_eq!(m.select_rows(&[2, 0]).as_slice(), &[5.0, 6.0, 1.0, 2.0]);
        assert_eq!(m.rows().count(), 3);
    }

    #[test]
    fn from_rows_names_the_bad_row() {
        let err = SampleMatrix::from_rows(2, &[vec![1.0, 2.0], vec![3.0]]).unwrap_err();
        assert!(err.to_string().contains("row 1"), "{err}");
    }
}

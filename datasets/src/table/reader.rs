//! Reads numeric CSV files: a header row naming the columns, then rows of
//! numbers. Shared by the residual-table and rover-log loaders, so both
//! report bad input the same way (file, 1-based line, column name).

use std::path::{Path, PathBuf};

use crate::DatasetError;

/// The header of a numeric CSV file and the parsed values of the columns a
/// caller selected.
#[derive(Debug, Clone)]
pub(crate) struct NumericRows {
    /// The file read.
    pub path: PathBuf,
    /// Number of selected columns (the width of each row of `values`).
    pub width: usize,
    /// Selected cells, row-major, in the order the caller selected them.
    pub values: Vec<f64>,
    /// 1-based line of each row (the header is line 1).
    pub lines: Vec<u64>,
}

impl NumericRows {
    /// Number of data rows.
    pub fn len(&self) -> usize {
        self.lines.len()
    }

    /// The selected cells of row `i`.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.values[i * self.width..(i + 1) * self.width]
    }

    /// Fails with [`DatasetError::Empty`] when there are no data rows.
    pub fn require_rows(self) -> Result<Self, DatasetError> {
        if self.lines.is_empty() {
            return Err(DatasetError::Empty { path: self.path });
        }
        Ok(self)
    }
}

/// Reads `path`, lets `select` choose column indices from the header (and
/// return whatever else it learned from the header, `T`), and parses those
/// cells as finite numbers. Unselected cells are not parsed.
///
/// Fields are trimmed; blank lines are skipped. The header must be present,
/// with non-empty, distinct names, and every row must have as many fields as
/// the header. A file with a header and no rows yields no rows (callers that
/// need rows use [`NumericRows::require_rows`]).
pub(crate) fn read_numeric_csv<T, F>(
    path: &Path,
    select: F,
) -> Result<(NumericRows, T), DatasetError>
where
    F: FnOnce(&[String]) -> Result<(Vec<usize>, T), DatasetError>,
{
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| csv_error(path, e))?;
    let header = read_header(path, &mut reader)?;
    let (selected, learned) = select(&header)?;
    let mut rows = NumericRows {
        path: path.to_path_buf(),
        width: selected.len(),
        values: Vec::new(),
        lines: Vec::new(),
    };
    let mut record = csv::StringRecord::new();
    while reader
        .read_record(&mut record)
        .map_err(|e| csv_error(path, e))?
    {
        let line = record.position().map_or(0, csv::Position::line);
        if record.len() != header.len() {
            return Err(DatasetError::Shape {
                path: path.to_path_buf(),
                line,
                expected: header.len(),
                found: record.len(),
            });
        }
        for &j in &selected {
            rows.values
                .push(parse_cell(path, line, &header[j], &record[j])?);
        }
        rows.lines.push(line);
    }
    Ok((rows, learned))
}

/// Index of the column called `name`, or [`DatasetError::MissingColumn`].
pub(crate) fn column_index(
    path: &Path,
    header: &[String],
    name: &str,
) -> Result<usize, DatasetError> {
    header
        .iter()
        .position(|h| h == name)
        .ok_or_else(|| DatasetError::MissingColumn {
            path: path.to_path_buf(),
            column: name.to_string(),
        })
}

/// The header row: present, names non-empty and distinct.
fn read_header(
    path: &Path,
    reader: &mut csv::Reader<std::fs::File>,
) -> Result<Vec<String>, DatasetError> {
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| csv_error(path, e))?
        .iter()
        .map(str::to_string)
        .collect();
    if header.iter().all(String::is_empty) {
        return Err(DatasetError::Empty {
            path: path.to_path_buf(),
        });
    }
    for (j, name) in header.iter().enumerate() {
        if name.is_empty() {
            return Err(DatasetError::Csv {
                path: path.to_path_buf(),
                line: 1,
                detail: format!("header field {} has an empty name", j + 1),
            });
        }
        if header[..j].contains(name) {
            return Err(DatasetError::DuplicateColumn {
                path: path.to_path_buf(),
                column: name.clone(),
            });
        }
    }
    Ok(header)
}

/// Parses one cell as a finite number.
fn parse_cell(path: &Path, line: u64, column: &str, text: &str) -> Result<f64, DatasetError> {
    let value: f64 = text.parse().map_err(|_| DatasetError::NotANumber {
        path: path.to_path_buf(),
        line,
        column: column.to_string(),
        value: text.to_string(),
    })?;
    if !value.is_finite() {
        return Err(DatasetError::NonFinite {
            path: path.to_path_buf(),
            line,
            column: column.to_string(),
        });
    }
    Ok(value)
}

/// Maps a `csv` error to [`DatasetError::Io`] or [`DatasetError::Csv`].
fn csv_error(path: &Path, error: csv::Error) -> DatasetError {
    let line = error.position().map_or(0, csv::Position::line);
    let detail = error.to_string();
    match error.into_kind() {
        csv::ErrorKind::Io(source) => DatasetError::Io {
            path: path.to_path_buf(),
            source,
        },
        _ => DatasetError::Csv {
            path: path.to_path_buf(),
            line,
            detail,
        },
    }
}

//! Residual tables: CSV files that already hold regressor inputs and residual
//! targets (`x_k`, `y_k` of the paper's eq. 12, §IV-C), for experiments that
//! study the regressor alone, such as the authors' ExoTeR training table.
//!
//! A table is one header row naming the columns, then one row of numbers per
//! sample, in time order. A [`TableSpec`] names the target columns and,
//! optionally, the input columns; [`read_residual_table`] returns them in
//! that order as a [`ResidualDataset`]. Columns the spec does not name are
//! ignored and not parsed. [`split_fraction`] makes the time-ordered
//! train/test split and [`summarize_abs`] the per-axis residual magnitudes
//! used to compare datasets.

mod reader;
mod split;
mod summary;

use std::path::Path;

use gpodo_traits::{ResidualDataset, SampleMatrix};
use serde::{Deserialize, Serialize};

use crate::DatasetError;

pub(crate) use reader::{NumericRows, column_index, read_numeric_csv};
pub use split::split_fraction;
pub use summary::{ColumnSummary, percentile, percentile_sorted, summarize_abs};

/// Which columns of a residual table are inputs and which are targets.
///
/// Read from an experiment configuration; unknown fields are rejected so a
/// typo fails when the configuration is read.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableSpec {
    /// Input columns, in the order the regressor sees them. `None` (the
    /// default) means every column that is not a target, in file order.
    #[serde(default)]
    pub inputs: Option<Vec<String>>,
    /// Target (residual) columns, in output order. At least one.
    pub targets: Vec<String>,
}

impl TableSpec {
    /// Checks the spec on its own: at least one target, no empty input list,
    /// no name listed twice, no column both input and target.
    ///
    /// # Errors
    /// [`DatasetError::InvalidConfig`] naming the field at fault.
    pub fn validate(&self) -> Result<(), DatasetError> {
        if self.targets.is_empty() {
            return Err(invalid("targets", "at least one target column"));
        }
        check_distinct("targets", &self.targets)?;
        if let Some(inputs) = &self.inputs {
            if inputs.is_empty() {
                return Err(invalid(
                    "inputs",
                    "at least one input column (or omit `inputs` to use every non-target column)",
                ));
            }
            check_distinct("inputs", inputs)?;
            if let Some(both) = inputs.iter().find(|c| self.targets.contains(c)) {
                return Err(invalid(
                    "inputs",
                    &format!("columns that are not targets, but `{both}` is also a target"),
                ));
            }
        }
        Ok(())
    }
}

/// Reads the residual table at `path`, taking the columns `spec` names.
///
/// # Errors
/// [`DatasetError::InvalidConfig`] for a bad spec; for a bad file, an error
/// naming the file and, where it applies, the line and column:
/// [`DatasetError::MissingColumn`], [`DatasetError::NotANumber`],
/// [`DatasetError::NonFinite`], [`DatasetError::Shape`] (ragged row),
/// [`DatasetError::Empty`], [`DatasetError::DuplicateColumn`],
/// [`DatasetError::Csv`], [`DatasetError::Io`].
pub fn read_residual_table(path: &Path, spec: &TableSpec) -> Result<ResidualDataset, DatasetError> {
    spec.validate()?;
    let (rows, input_names) = read_numeric_csv(path, |header| {
        let inputs = input_names(spec, header);
        let indices = inputs
            .iter()
            .chain(&spec.targets)
            .map(|name| column_index(path, header, name))
            .collect::<Result<_, _>>()?;
        Ok((indices, inputs))
    })?;
    let rows = rows.require_rows()?;
    let target_names = spec.targets.clone();
    let (inputs, targets) = split_columns(&rows, input_names.len())?;
    Ok(ResidualDataset::new(
        inputs,
        targets,
        input_names,
        target_names,
    )?)
}

/// The input names: the spec's, or every non-target header column.
fn input_names(spec: &TableSpec, header: &[String]) -> Vec<String> {
    match &spec.inputs {
        Some(inputs) => inputs.clone(),
        None => header
            .iter()
            .filter(|h| !spec.targets.contains(h))
            .cloned()
            .collect(),
    }
}

/// Splits rows whose first `n_inputs` cells are inputs into two matrices.
fn split_columns(
    rows: &NumericRows,
    n_inputs: usize,
) -> Result<(SampleMatrix, SampleMatrix), DatasetError> {
    let n_targets = rows.width - n_inputs;
    let mut inputs = Vec::with_capacity(rows.len() * n_inputs);
    let mut targets = Vec::with_capacity(rows.len() * n_targets);
    for i in 0..rows.len() {
        let (x, y) = rows.row(i).split_at(n_inputs);
        inputs.extend_from_slice(x);
        targets.extend_from_slice(y);
    }
    Ok((
        SampleMatrix::from_row_major(rows.len(), n_inputs, inputs)?,
        SampleMatrix::from_row_major(rows.len(), n_targets, targets)?,
    ))
}

/// Fails when `names` lists a column twice.
fn check_distinct(field: &str, names: &[String]) -> Result<(), DatasetError> {
    for (i, name) in names.iter().enumerate() {
        if names[..i].contains(name) {
            return Err(invalid(
                field,
                &format!("distinct column names, but `{name}` is listed twice"),
            ));
        }
    }
    Ok(())
}

/// An [`DatasetError::InvalidConfig`] for `field`.
fn invalid(field: &str, expected: &str) -> DatasetError {
    DatasetError::InvalidConfig {
        field: field.to_string(),
        expected: expected.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use serde::de::value::{Error as ValueError, MapDeserializer};

    use super::*;

    fn write_table(contents: &str) -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("table.csv");
        std::fs::write(&path, contents).unwrap();
        (dir, path)
    }

    fn spec(inputs: Option<&[&str]>, targets: &[&str]) -> TableSpec {
        let owned = |names: &[&str]| names.iter().map(|s| s.to_string()).collect();
        TableSpec {
            inputs: inputs.map(owned),
            targets: owned(targets),
        }
    }

    #[test]
    fn reads_named_columns_in_spec_order() {
        let (_dir, path) = write_table("a,b,c,y\n1,2,3,4\n5,6,7,8\n");
        let data = read_residual_table(&path, &spec(Some(&["c", "a"]), &["y"])).unwrap();
        assert_eq!(data.input_names, ["c", "a"]);
        assert_eq!(data.target_names, ["y"]);
        assert_eq!(data.inputs.as_slice(), &[3.0, 1.0, 7.0, 5.0]);
        assert_eq!(data.targets.as_slice(), &[4.0, 8.0]);
    }

    #[test]
    fn missing_inputs_mean_every_non_target_column_in_file_order() {
        let (_dir, path) = write_table("y2,a,y1,b\n1,2,3,4\n");
        let data = read_residual_table(&path, &spec(None, &["y1", "y2"])).unwrap();
        assert_eq!(data.input_names, ["a", "b"]);
        assert_eq!(data.inputs.as_slice(), &[2.0, 4.0]);
        assert_eq!(data.targets.as_slice(), &[3.0, 1.0]);
    }

    #[test]
    fn ignores_unselected_non_numeric_columns() {
        let (_dir, path) = write_table("run,a,y\nfirst,1,2\n");
        let data = read_residual_table(&path, &spec(Some(&["a"]), &["y"])).unwrap();
        assert_eq!(data.len(), 1);
    }

    #[test]
    fn rejects_missing_column_naming_column_and_file() {
        let (_dir, path) = write_table("a,y\n1,2\n");
        let err = read_residual_table(&path, &spec(Some(&["a", "b"]), &["y"])).unwrap_err();
        assert!(matches!(&err, DatasetError::MissingColumn { column, .. } if column == "b"));
        let msg = err.to_string();
        assert!(msg.contains("table.csv") && msg.contains("`b`"), "{msg}");
    }

    #[test]
    fn rejects_non_numeric_cell_with_line_and_column() {
        let (_dir, path) = write_table("a,y\n1,2\n3,oops\n");
        let err = read_residual_table(&path, &spec(None, &["y"])).unwrap_err();
        assert!(
            matches!(&err, DatasetError::NotANumber { line: 3, column, value, .. }
                if column == "y" && value == "oops"),
            "{err}"
        );
        assert!(err.to_string().contains("line 3"), "{err}");
    }

    #[test]
    fn rejects_nan_with_line_and_column() {
        let (_dir, path) = write_table("a,y\n1,2\nNaN,3\n");
        let err = read_residual_table(&path, &spec(None, &["y"])).unwrap_err();
        assert!(
            matches!(&err, DatasetError::NonFinite { line: 3, column, .. } if column == "a"),
            "{err}"
        );
    }

    #[test]
    fn rejects_infinity_with_line_and_column() {
        let (_dir, path) = write_table("a,y\n-inf,2\n");
        let err = read_residual_table(&path, &spec(None, &["y"])).unwrap_err();
        assert!(
            matches!(&err, DatasetError::NonFinite { line: 2, .. }),
            "{err}"
        );
    }

    #[test]
    fn rejects_empty_file() {
        let (_dir, path) = write_table("");
        let err = read_residual_table(&path, &spec(None, &["y"])).unwrap_err();
        assert!(matches!(err, DatasetError::Empty { .. }), "{err}");
    }

    #[test]
    fn rejects_header_without_rows() {
        let (_dir, path) = write_table("a,y\n");
        let err = read_residual_table(&path, &spec(None, &["y"])).unwrap_err();
        assert!(matches!(err, DatasetError::Empty { .. }), "{err}");
    }

    #[test]
    fn rejects_ragged_row_with_line() {
        let (_dir, path) = write_table("a,y\n1,2\n3,4,5\n");
        let err = read_residual_table(&path, &spec(None, &["y"])).unwrap_err();
        assert!(
            matches!(
                err,
                DatasetError::Shape {
                    line: 3,
                    expected: 2,
                    found: 3,
                    ..
                }
            ),
            "{err}"
        );
    }

    #[test]
    fn rejects_duplicate_header_columns() {
        let (_dir, path) = write_table("a,a,y\n1,2,3\n");
        let err = read_residual_table(&path, &spec(None, &["y"])).unwrap_err();
        assert!(matches!(&err, DatasetError::DuplicateColumn { column, .. } if column == "a"));
    }

    #[test]
    fn rejects_missing_file_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("absent.csv");
        let err = read_residual_table(&path, &spec(None, &["y"])).unwrap_err();
        assert!(matches!(err, DatasetError::Io { .. }), "{err}");
        assert!(err.to_string().contains("absent.csv"), "{err}");
    }

    #[test]
    fn rejects_spec_with_column_both_input_and_target() {
        let err = spec(Some(&["a", "y"]), &["y"]).validate().unwrap_err();
        assert!(matches!(&err, DatasetError::InvalidConfig { field, .. } if field == "inputs"));
    }

    #[test]
    fn rejects_spec_without_targets() {
        let err = spec(None, &[]).validate().unwrap_err();
        assert!(matches!(&err, DatasetError::InvalidConfig { field, .. } if field == "targets"));
    }

    #[test]
    fn spec_rejects_unknown_fields() {
        let fields = vec![
            ("targets", vec!["y".to_string()]),
            ("input", vec!["a".to_string()]),
        ];
        let de = MapDeserializer::<_, ValueError>::new(fields.into_iter());
        let err = TableSpec::deserialize(de).unwrap_err();
        assert!(err.to_string().contains("input"), "{err}");
    }

    #[test]
    fn spec_inputs_default_to_none() {
        let fields = vec![("targets", vec!["y".to_string()])];
        let de = MapDeserializer::<_, ValueError>::new(fields.into_iter());
        assert_eq!(TableSpec::deserialize(de).unwrap(), spec(None, &["y"]));
    }
}

//! A residual table for the exact GP's examples: a CSV with a header row
//! whose last three columns are the targets.

use anyhow::{Context, bail};
use gpodo_traits::{ResidualDataset, SampleMatrix};

/// The table's column names and its first `rows` rows (fewer when it is
/// shorter), every column z-scored on the first `fit` of them.
pub struct Table {
    /// Column names; the last three are the targets.
    pub header: Vec<String>,
    /// Rows, z-scored.
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    /// Reads `path`.
    ///
    /// # Errors
    /// When the file cannot be read, is empty, or holds a value that is not
    /// a number (named by its line).
    pub fn read(path: &str, rows: usize, fit: usize) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {path}"))?;
        let mut lines = text.lines();
        let header: Vec<String> = lines
            .next()
            .context("empty file")?
            .split(',')
            .map(String::from)
            .collect();
        if header.len() < 4 {
            bail!("{path}: at least one input and three target columns expected");
        }
        let raw: Vec<Vec<f64>> = lines
            .take(rows)
            .enumerate()
            .map(|(i, l)| {
                l.split(',')
                    .map(|v| v.trim().parse::<f64>())
                    .collect::<Result<Vec<_>, _>>()
                    .with_context(|| format!("{path}:{}: a row of numbers expected", i + 2))
            })
            .collect::<anyhow::Result<_>>()?;
        let fit = fit.clamp(1, raw.len().max(1));
        let mut z = raw.clone();
        for c in 0..header.len() {
            let mean = raw[..fit].iter().map(|r| r[c]).sum::<f64>() / fit as f64;
            let sd = (raw[..fit]
                .iter()
                .map(|r| (r[c] - mean).powi(2))
                .sum::<f64>()
                / fit as f64)
                .sqrt();
            let sd = if sd < 1e-12 { 1.0 } else { sd };
            for r in &mut z {
                r[c] = (r[c] - mean) / sd;
            }
        }
        Ok(Self { header, rows: z })
    }

    /// Input columns.
    pub fn inputs(&self) -> usize {
        self.header.len() - 3
    }

    /// Its first `rows` rows as a residual dataset.
    ///
    /// # Errors
    /// When the rows are ragged.
    pub fn dataset(&self, rows: usize) -> anyhow::Result<ResidualDataset> {
        let (head, d) = (&self.rows[..rows.min(self.rows.len())], self.inputs());
        let columns = |range: std::ops::Range<usize>| {
            SampleMatrix::from_row_major(
                head.len(),
                range.len(),
                head.iter()
                    .flat_map(|r| r[range.clone()].to_vec())
                    .collect(),
            )
        };
        Ok(ResidualDataset::new(
            columns(0..d)?,
            columns(d..d + 3)?,
            self.header[..d].to_vec(),
            self.header[d..].to_vec(),
        )?)
    }
}

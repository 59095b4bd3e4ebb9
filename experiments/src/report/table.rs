//! The one table renderer of every report: a header, its column alignment,
//! rows of formatted cells for Markdown, and optionally a CSV twin with the
//! unrounded numbers. Table I and Table II of a single run (`report.md`),
//! of a sweep (`summary.md`, `tables/*.csv`) and the tables of `gpodo bench`
//! are all built as a [`Table`].

use std::fmt::Write as _;

/// How a column's cells are aligned in Markdown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Align {
    /// Text (`---`).
    Left,
    /// Numbers (`---:`).
    Right,
}

/// A table: header, alignment, rows of Markdown cells, and a CSV twin.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    header: Vec<String>,
    align: Vec<Align>,
    rows: Vec<Vec<String>>,
    csv: Vec<Vec<String>>,
}

impl Table {
    /// A table with these column names: the first column is text, the
    /// others numbers (see [`Table::align`]).
    pub fn new<S: AsRef<str>>(header: &[S]) -> Self {
        let header: Vec<String> = header.iter().map(|h| h.as_ref().to_string()).collect();
        let align = (0..header.len())
            .map(|i| if i == 0 { Align::Left } else { Align::Right })
            .collect();
        Self {
            header,
            align,
            ..Self::default()
        }
    }

    /// Aligns the given columns (by index) this way.
    #[must_use]
    pub fn align(mut self, columns: &[usize], align: Align) -> Self {
        for &c in columns {
            if let Some(a) = self.align.get_mut(c) {
                *a = align;
            }
        }
        self
    }

    /// Gives the table a CSV twin with these column names.
    #[must_use]
    pub fn with_csv<S: AsRef<str>>(mut self, header: &[S]) -> Self {
        self.csv = vec![header.iter().map(|h| h.as_ref().to_string()).collect()];
        self
    }

    /// Appends a row of Markdown cells.
    pub fn push(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }

    /// Appends a row to the CSV twin.
    pub fn push_csv(&mut self, cells: Vec<String>) {
        self.csv.push(cells);
    }

    /// The CSV twin's rows, without its header.
    pub fn csv_rows(&self) -> &[Vec<String>] {
        self.csv.get(1..).unwrap_or_default()
    }

    /// Whether the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The Markdown table, one line per row, ending with a newline; a `|`
    /// inside a cell is escaped.
    pub fn markdown(&self) -> String {
        let cells = |row: &[String]| {
            row.iter()
                .map(|c| c.replace('|', "\\|"))
                .collect::<Vec<_>>()
                .join(" | ")
        };
        let mut s = format!("| {} |\n|", cells(&self.header));
        for a in &self.align {
            s.push_str(match a {
                Align::Left => "---|",
                Align::Right => "---:|",
            });
        }
        s.push('\n');
        for row in &self.rows {
            let _ = writeln!(s, "| {} |", cells(row));
        }
        s
    }

    /// The CSV twin (RFC 4180 quoting), empty when there is none.
    pub fn csv_text(&self) -> String {
        let escape = |c: &String| {
            if c.contains([',', '"', '\n']) {
                format!("\"{}\"", c.replace('"', "\"\""))
            } else {
                c.clone()
            }
        };
        let mut s = String::new();
        for row in &self.csv {
            let _ = writeln!(
                s,
                "{}",
                row.iter().map(escape).collect::<Vec<_>>().join(",")
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_aligns_and_csv_quotes() {
        let mut t = Table::new(&["name", "value", "note"])
            .align(&[2], Align::Left)
            .with_csv(&["name", "value"]);
        t.push(vec!["a".into(), "1.0".into(), "x".into()]);
        t.push_csv(vec!["a, b".into(), "1".into()]);
        assert_eq!(
            t.markdown(),
            "| name | value | note |\n|---|---:|---|\n| a | 1.0 | x |\n"
        );
        assert_eq!(t.csv_text(), "name,value\n\"a, b\",1\n");
        assert!(!t.is_empty());
        // A pipe in a cell does not split it.
        let mut t = Table::new(&["regressor"]);
        t.push(vec!["|residual| GP".into()]);
        assert!(
            t.markdown().ends_with("| \\|residual\\| GP |\n"),
            "{}",
            t.markdown()
        );
        assert!(Table::new(&["x"]).is_empty());
    }
}

//! Where each value of a YAML file is: a map from the value's path
//! (`regressors[1].kernel`) to its line and column, built from the YAML
//! parser's events, so that errors found after parsing (a bad value, an
//! invalid combination) point at the file, line and column.

use std::collections::HashMap;

use serde_saphyr::granit_parser::{Event, Parser};

use crate::error::ConfigError;

/// A position in a file (1-based line and column).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Position {
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1.
    pub column: usize,
}

/// Value positions of one YAML document, by path.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Locator {
    values: HashMap<String, Position>,
    keys: HashMap<String, Position>,
}

enum Frame {
    Mapping { path: String, key: Option<String> },
    Sequence { path: String, index: usize },
}

/// `parent.key` or `key` at the root.
pub fn join_key(parent: &str, key: &str) -> String {
    if parent.is_empty() {
        key.to_string()
    } else {
        format!("{parent}.{key}")
    }
}

impl Locator {
    /// Indexes `text`; a document the parser rejects gives an empty index
    /// (the deserialiser reports the syntax error itself).
    pub fn new(text: &str) -> Self {
        let mut out = Self::default();
        let mut stack: Vec<Frame> = Vec::new();
        for event in Parser::new_from_str(text) {
            let Ok((event, span)) = event else {
                break;
            };
            let here = Position {
                line: span.start.line(),
                column: span.start.col() + 1,
            };
            let is_node = matches!(
                event,
                Event::Scalar(..)
                    | Event::SequenceStart(..)
                    | Event::MappingStart(..)
                    | Event::Alias(_)
            );
            // The path a node in the current position gets, or `None` when
            // the node is a mapping key.
            let mut node_path = None;
            if is_node {
                match stack.last_mut() {
                    None => node_path = Some(String::new()),
                    Some(Frame::Sequence { path, index }) => {
                        node_path = Some(format!("{path}[{index}]"));
                        *index += 1;
                    }
                    Some(Frame::Mapping { path, key }) => match key.take() {
                        Some(k) => node_path = Some(join_key(path, &k)),
                        None => {
                            if let Event::Scalar(value, ..) = &event {
                                let key_path = join_key(path, value);
                                out.keys.insert(key_path, here);
                                *key = Some(value.to_string());
                            } else {
                                // A complex key: index nothing under it.
                                *key = Some(String::from("?"));
                            }
                        }
                    },
                }
            }
            if let Some(p) = &node_path {
                out.values.entry(p.clone()).or_insert(here);
            }
            match event {
                Event::MappingStart(..) => stack.push(Frame::Mapping {
                    path: node_path.unwrap_or_default(),
                    key: None,
                }),
                Event::SequenceStart(..) => stack.push(Frame::Sequence {
                    path: node_path.unwrap_or_default(),
                    index: 0,
                }),
                Event::MappingEnd | Event::SequenceEnd => {
                    stack.pop();
                }
                _ => {}
            }
        }
        out
    }

    /// The position of the value at `path`, or of its key; else that of the
    /// nearest enclosing value that exists.
    pub fn find(&self, path: &str) -> Option<Position> {
        let mut p = path.to_string();
        loop {
            if let Some(pos) = self.values.get(&p).or_else(|| self.keys.get(&p)) {
                return Some(*pos);
            }
            let cut = p.rfind(['.', '['])?;
            p.truncate(cut);
        }
    }

    /// The position of the key naming `path` (for unknown-field errors).
    pub fn key(&self, path: &str) -> Option<Position> {
        self.keys.get(path).copied()
    }

    /// A [`ConfigError::Located`] in `file` at the value at `path` (at its
    /// key first when `at_key`, as for an unknown field), or the nearest
    /// enclosing value.
    pub fn error(
        &self,
        file: &std::path::Path,
        path: &str,
        problem: String,
        expected: String,
        at_key: bool,
    ) -> ConfigError {
        let pos = if at_key { self.key(path) } else { None }
            .or_else(|| self.find(path))
            .unwrap_or_default();
        ConfigError::Located {
            file: file.to_path_buf(),
            line: pos.line,
            column: pos.column,
            path: path.to_string(),
            problem,
            expected,
        }
    }

    /// Every indexed value path with its position.
    pub fn values(&self) -> impl Iterator<Item = (&String, &Position)> {
        self.values.iter()
    }

    /// Every indexed key path with its position.
    pub fn keys(&self) -> impl Iterator<Item = (&String, &Position)> {
        self.keys.iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const YAML: &str = "name: t\ndataset: { kind: simulated, seed: 7 }\nregressors:\n  - kind: zero\n  - kind: exact_gp\n    kernel: rbf + linear\nsweep:\n  regressors[1].kernel: [rbf, matern52]\n";

    #[test]
    fn values_are_found_by_path() {
        let l = Locator::new(YAML);
        assert_eq!(l.find("name"), Some(Position { line: 1, column: 7 }));
        assert_eq!(
            l.find("dataset.seed"),
            Some(Position {
                line: 2,
                column: 35
            })
        );
        assert_eq!(
            l.find("regressors[1]"),
            Some(Position { line: 5, column: 5 })
        );
        assert_eq!(
            l.find("regressors[1].kernel"),
            Some(Position {
                line: 6,
                column: 13
            })
        );
        assert_eq!(
            l.find("sweep.regressors[1].kernel[1]"),
            Some(Position {
                line: 8,
                column: 31
            })
        );
        assert_eq!(
            l.key("regressors[1].kernel"),
            Some(Position { line: 6, column: 5 })
        );
        // A missing value falls back to its nearest existing parent.
        assert_eq!(
            l.find("regressors[1].restarts"),
            Some(Position { line: 5, column: 5 })
        );
        assert_eq!(l.find("nothing.here"), None);
    }
}

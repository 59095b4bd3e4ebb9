//! Reading an experiment file into one JSON tree: `base:` files merged
//! under it, and the file, line and column of every value remembered so
//! that errors can point at them.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::error::ConfigError;
use crate::plan::locate::{Locator, Position, join_key};
use crate::plan::paths::merge;

/// Longest chain of `base:` files.
const MAX_BASE_DEPTH: usize = 8;

/// Where the values of the merged tree came from.
#[derive(Debug, Default)]
pub(crate) struct Provenance {
    files: Vec<PathBuf>,
    values: HashMap<String, (usize, Position)>,
    keys: HashMap<String, (usize, Position)>,
}

impl Provenance {
    fn add_file(&mut self, file: &Path, locator: &Locator, shadowed: &[String]) {
        let index = self.files.len();
        self.files.push(file.to_path_buf());
        // Lists and scalars of the new file replace the base's entirely.
        for prefix in shadowed {
            let (dot, bracket) = (format!("{prefix}."), format!("{prefix}["));
            self.values
                .retain(|k, _| !(k.starts_with(&dot) || k.starts_with(&bracket)));
            self.keys
                .retain(|k, _| !(k.starts_with(&dot) || k.starts_with(&bracket)));
        }
        for (path, pos) in locator.values() {
            self.values.insert(path.clone(), (index, *pos));
        }
        for (path, pos) in locator.keys() {
            self.keys.insert(path.clone(), (index, *pos));
        }
    }

    /// The file and position of `path` (or of the nearest parent known).
    pub(crate) fn find(&self, path: &str, prefer_key: bool) -> Option<(PathBuf, Position)> {
        let mut p = path.to_string();
        let first = if prefer_key { self.keys.get(&p) } else { None };
        if let Some((f, pos)) = first {
            return Some((self.files[*f].clone(), *pos));
        }
        loop {
            if let Some((f, pos)) = self.values.get(&p).or_else(|| self.keys.get(&p)) {
                return Some((self.files[*f].clone(), *pos));
            }
            let cut = p.rfind(['.', '['])?;
            p.truncate(cut);
        }
    }
}

/// Paths of the non-mapping values of `value` (the ones that replace a
/// base's wholesale when overlaid).
fn replaced_paths(value: &Value, prefix: &str, out: &mut Vec<String>) {
    if let Value::Object(map) = value {
        for (k, v) in map {
            let path = join_key(prefix, k);
            if v.is_object() {
                replaced_paths(v, &path, out);
            } else {
                out.push(path);
            }
        }
    }
}

pub(crate) fn read_tree(
    file: &Path,
    depth: usize,
    provenance: &mut Provenance,
) -> Result<Value, ConfigError> {
    let text = std::fs::read_to_string(file).map_err(|source| ConfigError::Io {
        path: file.to_path_buf(),
        source,
    })?;
    tree_of_text(file, &text, depth, provenance)
}

/// [`read_tree`] of `text`, read as if it were `file` (which need not
/// exist: its folder is where `base:` is looked for).
pub(crate) fn tree_of_text(
    file: &Path,
    text: &str,
    depth: usize,
    provenance: &mut Provenance,
) -> Result<Value, ConfigError> {
    let mut value: Value = serde_saphyr::from_str(text).map_err(|e| ConfigError::Parse {
        path: file.to_path_buf(),
        detail: e.to_string(),
    })?;
    let locator = Locator::new(text);
    let located = |path: &str, problem: String, expected: String| {
        locator.error(file, path, problem, expected, false)
    };
    let Value::Object(map) = &mut value else {
        return Err(located(
            "",
            "the file is not a mapping".into(),
            "an experiment: `name:`, `dataset:`, `regressors:` …".into(),
        ));
    };
    let base = map.remove("base");
    let mut merged = match base {
        None => Value::Object(Default::default()),
        Some(Value::String(b)) => {
            if depth >= MAX_BASE_DEPTH {
                return Err(located(
                    "base",
                    format!("more than {MAX_BASE_DEPTH} `base:` files in a chain"),
                    "a shorter chain (a file extending itself?)".into(),
                ));
            }
            let dir = file.parent().unwrap_or_else(|| Path::new("."));
            let base_file = dir.join(&b);
            if !base_file.is_file() {
                return Err(located(
                    "base",
                    format!("base file `{b}` not found"),
                    format!("an experiment file (relative to {})", dir.display()),
                ));
            }
            read_tree(&base_file, depth + 1, provenance)?
        }
        Some(other) => {
            return Err(located(
                "base",
                format!("`base: {other}`"),
                "the path of the experiment file this one extends".into(),
            ));
        }
    };
    let mut shadowed = Vec::new();
    replaced_paths(&value, "", &mut shadowed);
    provenance.add_file(file, &locator, &shadowed);
    merge(&mut merged, value);
    Ok(merged)
}

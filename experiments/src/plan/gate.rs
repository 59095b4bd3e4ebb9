//! Reads a gate file ([`GateFile`]): every error names the file, line and
//! column of the value at fault, and what was expected.

use std::path::Path;

use serde_json::Value;

use crate::config::Issue;
use crate::config::gate::GateFile;
use crate::error::ConfigError;
use crate::plan::locate::Locator;
use crate::plan::messages::split_serde_message;

/// Reads and checks the gate file `file`.
///
/// # Errors
/// [`ConfigError::Io`] for a file that cannot be read,
/// [`ConfigError::Parse`] for malformed YAML, and
/// [`ConfigError::Located`] for a value that does not fit the schema or
/// is not acceptable.
pub fn load_gate(file: &Path) -> Result<GateFile, ConfigError> {
    let text = std::fs::read_to_string(file).map_err(|source| ConfigError::Io {
        path: file.to_path_buf(),
        source,
    })?;
    let value: Value = serde_saphyr::from_str(&text).map_err(|e| ConfigError::Parse {
        path: file.to_path_buf(),
        detail: e.to_string(),
    })?;
    let locator = Locator::new(&text);
    let located = |path: &str, problem: String, expected: String, key: bool| {
        locator.error(file, path, problem, expected, key)
    };
    let gate: GateFile = serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        let message = e.inner().to_string();
        let (problem, expected) = split_serde_message(&message, &path);
        located(
            &path,
            problem,
            expected,
            message.starts_with("unknown field"),
        )
    })?;
    gate.validate().map_err(
        |Issue {
             path,
             problem,
             expected,
         }| located(&path, problem, expected, false),
    )?;
    Ok(gate)
}

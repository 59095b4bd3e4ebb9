//! Writing result files: atomically (a crash never leaves a half-written
//! file) and under names made from labels.

use std::path::Path;

/// Writes `contents` to `path` atomically (temporary file + rename).
///
/// # Errors
/// The I/O error, with the path.
pub fn write_atomically(path: &Path, contents: &[u8]) -> std::io::Result<()> {
    // The temporary name is unique per process, so shards writing the same
    // file (the plan, the final report) never share one.
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("file");
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    std::fs::write(&tmp, contents)?;
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}

/// A file-name-safe form of a label.
pub fn slug(label: &str) -> String {
    let mut out = String::new();
    for c in label.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.ends_with('-') {
            out.push('-');
        }
    }
    out.trim_matches('-').to_string()
}

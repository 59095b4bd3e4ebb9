//! Writing result files: atomically (a crash never leaves a half-written
//! file) and under names made from labels.

use std::fs::File;
use std::io::Write;
use std::path::Path;

use anyhow::Context;

/// Writes `contents` to `path` atomically (temporary file + rename).
///
/// # Errors
/// The I/O error; see [`write_atomically_with`].
pub fn write_atomically(path: &Path, contents: &[u8]) -> std::io::Result<()> {
    write_atomically_with(path, |file| file.write_all(contents))
}

/// [`write_atomically`], its error naming the file it was writing.
///
/// # Errors
/// `writing <path>`, caused by the I/O error.
pub fn write_file(path: &Path, contents: &[u8]) -> anyhow::Result<()> {
    write_atomically(path, contents).with_context(|| format!("writing {}", path.display()))
}

/// Writes `path` atomically with `write`, which fills a new temporary file
/// beside it; the file is synced and renamed onto `path`. When anything
/// fails, the temporary file is removed and `path` is as it was.
///
/// # Errors
/// The error of `write`, of the sync or of the rename.
pub fn write_atomically_with(
    path: &Path,
    write: impl FnOnce(&mut File) -> std::io::Result<()>,
) -> std::io::Result<()> {
    // The temporary name is unique per process, so shards writing the same
    // file (the plan, the final report) never share one.
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("file");
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let result = File::create(&tmp).and_then(|mut file| {
        write(&mut file)?;
        file.sync_all()?;
        drop(file);
        std::fs::rename(&tmp, path)
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    /// The names in `dir`, sorted.
    fn names(dir: &Path) -> Vec<String> {
        let mut out: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        out.sort();
        out
    }

    #[test]
    fn a_write_that_fails_part_way_leaves_no_file_and_the_old_one_intact() {
        let dir = tempfile::tempdir().unwrap();
        let kept = dir.path().join("plan.json");
        write_atomically(&kept, b"{\"complete\": true}").unwrap();
        let target = dir.path().join("metrics.json");
        write_atomically(&target, b"old").unwrap();
        let failed = write_atomically_with(&target, |file| {
            file.write_all(&[b'x'; 4096])?;
            Err(std::io::Error::new(
                std::io::ErrorKind::StorageFull,
                "no space left (injected)",
            ))
        });
        assert_eq!(failed.unwrap_err().kind(), std::io::ErrorKind::StorageFull);
        assert_eq!(names(dir.path()), ["metrics.json", "plan.json"]);
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        assert_eq!(std::fs::read(&kept).unwrap(), b"{\"complete\": true}");
    }

    #[test]
    fn a_failed_write_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("missing-folder").join("report.md");
        let e = write_file(&target, b"text").unwrap_err();
        assert!(
            format!("{e:#}").starts_with(&format!("writing {}: ", target.display())),
            "{e:#}"
        );
        assert_eq!(names(dir.path()), Vec::<String>::new());
    }
}

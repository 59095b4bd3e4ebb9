//! The online learner's checkpoints: its model file with what it must
//! match to be resumed (the rover description's SHA-256, the input
//! columns, the model kind) and how many targets it has learned.
//!
//! A checkpoint is written atomically: to a temporary file in the same
//! folder, synced, renamed over the old one, and the folder synced, so a
//! crash or a failed write at any point leaves the previous checkpoint
//! whole (POSIX `rename` replaces atomically; the folder's sync makes the
//! rename itself durable).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use gpodo_regressors::model_file::{ModelFile, SavedState};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// What names a checkpoint file.
pub const CHECKPOINT_FORMAT: &str = "gpodo-online-checkpoint";
/// The version written.
pub const CHECKPOINT_VERSION: u32 = 1;

/// What a checkpoint must match to be resumed.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckpointKey {
    /// The rover description's SHA-256 (hex).
    pub rover_sha256: String,
    /// The model's input columns, in its order.
    pub input_columns: Vec<String>,
    /// The model kind (`ilgr`, `sparse_spectrum`, `streaming_sparse_gp`).
    pub kind: String,
}

/// A checkpoint on disk.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Checkpoint {
    /// Always [`CHECKPOINT_FORMAT`].
    pub format: String,
    /// [`CHECKPOINT_VERSION`] when written.
    pub version: u32,
    /// What it must match.
    pub key: CheckpointKey,
    /// Targets learned when it was written.
    pub targets_learned: u64,
    /// The model.
    pub model: ModelFile,
}

/// Why a checkpoint could not be written, read or resumed.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// The file could not be written or read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file is not a checkpoint of this version.
    #[error("{}: {detail}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        detail: String,
    },
    /// The checkpoint was written for another rover, columns or kind.
    #[error("{}: `{field}` is {found}, this node's is {expected}; not resumed", path.display())]
    Mismatch {
        /// The file.
        path: PathBuf,
        /// The field that differs.
        field: &'static str,
        /// The checkpoint's value.
        found: String,
        /// This node's.
        expected: String,
    },
}

/// The SHA-256 of `bytes`, in hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The kind a saved state is of, as checkpoints name it.
pub fn state_kind(state: &SavedState) -> &'static str {
    match state {
        SavedState::ExactGp(_) => "exact_gp",
        SavedState::SparseGp(_) => "sparse_gp",
        SavedState::Ilgr(_) => "ilgr",
        SavedState::SparseSpectrum(_) => "sparse_spectrum",
        SavedState::StreamingSparseGp(_) => "streaming_sparse_gp",
    }
}

impl Checkpoint {
    /// A checkpoint of `model` after `targets_learned` targets, for the
    /// rover whose description's SHA-256 is `rover_sha256`
    /// ([`sha256_hex`] of its file).
    pub fn new(model: ModelFile, rover_sha256: String, targets_learned: u64) -> Self {
        let key = CheckpointKey {
            rover_sha256,
            input_columns: model.input_names.clone(),
            kind: state_kind(&model.state).to_string(),
        };
        Self {
            format: CHECKPOINT_FORMAT.into(),
            version: CHECKPOINT_VERSION,
            key,
            targets_learned,
            model,
        }
    }

    /// Writes the checkpoint to `path` atomically.
    ///
    /// # Errors
    /// [`CheckpointError::Io`]; the file at `path` is then as it was.
    pub fn write(&self, path: &Path) -> Result<(), CheckpointError> {
        self.write_with(path, |file, bytes| file.write_all(bytes))
    }

    /// [`Self::write`] with the bytes written to the temporary file by
    /// `write` (a test injects faults here).
    ///
    /// # Errors
    /// As [`Self::write`].
    pub fn write_with(
        &self,
        path: &Path,
        write: impl FnOnce(&mut std::fs::File, &[u8]) -> std::io::Result<()>,
    ) -> Result<(), CheckpointError> {
        let io = |source| CheckpointError::Io {
            path: path.to_path_buf(),
            source,
        };
        let bytes = serde_json::to_vec(self).map_err(|e| io(std::io::Error::other(e)))?;
        let folder = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = path
            .file_name()
            .map_or_else(|| "checkpoint".into(), |n| n.to_string_lossy().into_owned());
        let tmp = folder.join(format!(".{name}.{}.partial", std::process::id()));
        let written = (|| {
            let mut file = std::fs::File::create(&tmp)?;
            write(&mut file, &bytes)?;
            file.sync_all()?;
            drop(file);
            std::fs::rename(&tmp, path)?;
            std::fs::File::open(&folder)?.sync_all()
        })();
        if written.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        written.map_err(io)
    }

    /// Reads a checkpoint.
    ///
    /// # Errors
    /// [`CheckpointError::Io`], or [`CheckpointError::Invalid`] for a file
    /// that is not a whole checkpoint of this version.
    pub fn read(path: &Path) -> Result<Self, CheckpointError> {
        let bytes = std::fs::read(path).map_err(|source| CheckpointError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let invalid = |detail: String| CheckpointError::Invalid {
            path: path.to_path_buf(),
            detail,
        };
        let checkpoint: Self = serde_json::from_slice(&bytes)
            .map_err(|e| invalid(format!("not a gpodo checkpoint: {e}")))?;
        if checkpoint.format != CHECKPOINT_FORMAT || checkpoint.version != CHECKPOINT_VERSION {
            return Err(invalid(format!(
                "format {} version {}; expected {CHECKPOINT_FORMAT} version {CHECKPOINT_VERSION}",
                checkpoint.format, checkpoint.version
            )));
        }
        Ok(checkpoint)
    }

    /// Checks that the checkpoint read from `path` may be resumed by a
    /// node with `key`.
    ///
    /// # Errors
    /// [`CheckpointError::Mismatch`] naming the first field that differs.
    pub fn check(&self, path: &Path, key: &CheckpointKey) -> Result<(), CheckpointError> {
        let mismatch = |field, found: String, expected: String| CheckpointError::Mismatch {
            path: path.to_path_buf(),
            field,
            found,
            expected,
        };
        if self.key.rover_sha256 != key.rover_sha256 {
            return Err(mismatch(
                "rover_sha256",
                self.key.rover_sha256.clone(),
                key.rover_sha256.clone(),
            ));
        }
        if self.key.input_columns != key.input_columns {
            return Err(mismatch(
                "input_columns",
                format!("{:?}", self.key.input_columns),
                format!("{:?}", key.input_columns),
            ));
        }
        if self.key.kind != key.kind {
            return Err(mismatch("kind", self.key.kind.clone(), key.kind.clone()));
        }
        Ok(())
    }
}

//! The errors of reading, writing and addressing images.

use std::path::PathBuf;

/// Why an image could not be read, written or addressed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum VisionError {
    /// The file could not be opened, read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The PNG is malformed, or not of a kind gpodo reads.
    #[error("{}: {detail}", path.display())]
    Png {
        /// The file.
        path: PathBuf,
        /// What is wrong, and what was expected.
        detail: String,
    },
    /// Pixel data or a box that does not fit the image.
    #[error("{what}: {detail}")]
    Shape {
        /// What was being built or addressed.
        what: String,
        /// What did not fit.
        detail: String,
    },
    /// A setting out of its range.
    #[error("{field}: expected {expected}")]
    InvalidParameter {
        /// The setting.
        field: &'static str,
        /// What it must be.
        expected: &'static str,
    },
}

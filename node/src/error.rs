//! Why a model cannot be run live, or a sample not used.

use std::path::PathBuf;

/// Why a model cannot be run live, or a sample not used.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    /// The model file cannot be read, or cannot be run on this robot.
    #[error("{}: {detail}", path.display())]
    Model {
        /// The model file.
        path: PathBuf,
        /// What is wrong.
        detail: String,
    },
    /// The model reads columns this robot's streams do not give.
    #[error(
        "{}: the model reads {missing:?}, which this robot's streams do not give (it gives {given:?})",
        path.display()
    )]
    MissingColumns {
        /// The model file.
        path: PathBuf,
        /// The columns it reads that are missing.
        missing: Vec<String>,
        /// The columns this robot gives.
        given: Vec<String>,
    },
    /// The topic map cannot drive the node on this rover.
    #[error("the topic map: {0}")]
    Topics(String),
    /// DDS failed (a participant, topic, reader or writer that cannot be
    /// made, or a write that fails).
    #[error("DDS: {0}")]
    Dds(String),
    /// A sample that cannot be used (the node warns and goes on).
    #[error("sample at {time_secs} s: {detail}")]
    Sample {
        /// Its time stamp (s).
        time_secs: f64,
        /// What is wrong.
        detail: String,
    },
}

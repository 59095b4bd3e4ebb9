//! The frame selector kinds an experiment may name in YAML, as a closed enum
//! (`kind: fixed_rate`, ...), validated when the configuration is read and
//! built into a runtime `Box<dyn FrameSelector>`.

use gpodo_traits::FrameSelector;
use serde::{Deserialize, Serialize};

use crate::{FixedRate, FrontendError};

/// A frame selector as written in an experiment file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SelectorSpec {
    /// Process frames at a fixed rate.
    FixedRate {
        /// Frames per second (the paper: 2.5 and 0.5).
        fps: f64,
    },
}

impl SelectorSpec {
    /// Builds the runtime selector.
    ///
    /// # Errors
    /// [`FrontendError::InvalidSpec`] naming the bad field.
    pub fn build(&self) -> Result<Box<dyn FrameSelector>, FrontendError> {
        Ok(match self {
            Self::FixedRate { fps } => Box::new(FixedRate::new(*fps)?),
        })
    }
}

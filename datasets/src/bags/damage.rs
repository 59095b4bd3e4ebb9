//! What to do with a damaged part of a recording, and what skipping it
//! cost.

use serde::{Deserialize, Serialize};

/// What a reader does when part of a recording is damaged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OnDamage {
    /// Stop with an error naming the damage (the default).
    #[default]
    Stop,
    /// Skip each damaged MCAP chunk (a CRC that disagrees with its data,
    /// an unreadable record) and go on with the next one, counting what is
    /// lost. ROS 1 and `.db3` bags still stop: their containers have no
    /// CRCs to tell a damaged chunk from an intact one.
    Skip,
}

/// What the damaged parts of a recording held, when they were skipped.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Damage {
    /// Chunks skipped.
    pub chunks_skipped: usize,
    /// Messages lost: the summary's count less those read (`None` without
    /// summary statistics to count against).
    pub messages_lost: Option<u64>,
    /// Seconds of recording the skipped parts span (their message time
    /// ranges, from the summary's chunk index or the chunk's own header).
    pub seconds_lost: f64,
    /// One line per damaged part: where it is and what is wrong.
    pub parts: Vec<String>,
}

impl Damage {
    /// Whether nothing was damaged.
    pub fn is_empty(&self) -> bool {
        self.parts.is_empty()
    }
}

impl std::fmt::Display for Damage {
    /// `skipped 1 damaged chunk: 412 messages and 4.100 s of recording
    /// lost (chunk at byte …)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let messages = self
            .messages_lost
            .map_or_else(|| "an unknown number of".into(), |n| n.to_string());
        write!(
            f,
            "skipped {} damaged chunk{}: {messages} messages and {:.3} s of recording lost ({})",
            self.chunks_skipped,
            if self.chunks_skipped == 1 { "" } else { "s" },
            self.seconds_lost,
            self.parts.join("; ")
        )
    }
}

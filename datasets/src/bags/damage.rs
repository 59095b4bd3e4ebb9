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

/// Which checksums a read could verify: a writer may store 0 for "none".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct Checksums {
    /// Chunks whose CRC was checked against their data.
    pub chunks_checked: usize,
    /// Chunks stored without a CRC (0): their damage is seen only where it
    /// breaks a record's structure.
    pub chunks_without: usize,
    /// The data section's CRC: `Some(true)` checked, `Some(false)` stored
    /// as 0, `None` not reached.
    pub data_section: Option<bool>,
    /// The summary section's CRC (in the footer), likewise.
    pub summary: Option<bool>,
}

impl std::fmt::Display for Checksums {
    /// `CRCs of 3 chunks, the data section and the summary checked` or what
    /// the file stores without.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut checked = Vec::new();
        let mut without = Vec::new();
        let plural = |n: usize| if n == 1 { "" } else { "s" };
        if self.chunks_checked > 0 {
            checked.push(format!(
                "{} chunk{}",
                self.chunks_checked,
                plural(self.chunks_checked)
            ));
        }
        if self.chunks_without > 0 {
            without.push(format!(
                "{} chunk{}",
                self.chunks_without,
                plural(self.chunks_without)
            ));
        }
        for (what, state) in [
            ("the data section", self.data_section),
            ("the summary", self.summary),
        ] {
            match state {
                Some(true) => checked.push(what.to_string()),
                Some(false) => without.push(what.to_string()),
                None => {}
            }
        }
        match (checked.is_empty(), without.is_empty()) {
            (true, true) => f.write_str("no CRCs"),
            (false, true) => write!(f, "the CRCs of {}", checked.join(", ")),
            (true, false) => write!(
                f,
                "no CRCs: the file stores none for {}",
                without.join(", ")
            ),
            (false, false) => write!(
                f,
                "the CRCs of {}, and none stored for {}",
                checked.join(", "),
                without.join(", ")
            ),
        }
    }
}

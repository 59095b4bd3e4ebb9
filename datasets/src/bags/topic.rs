//! One topic of a bag read as typed messages, for a role that needs certain
//! types: an unknown topic, a recorded type the role cannot use, or a
//! message that does not decode is an error naming the file, topic, type
//! and message index.

use std::path::Path;

use super::messages::{RosMessage, decode};
use super::{BagError, ros1_type_name, visit_messages};

/// A decoded message with its receive time.
#[derive(Debug, Clone, PartialEq)]
pub struct Stamped {
    /// Receive (log) time, ns since the epoch.
    pub log_time_ns: u64,
    /// The message.
    pub message: RosMessage,
}

/// Why a topic could not be read for its role.
#[derive(Debug, thiserror::Error)]
pub enum TopicError {
    /// The bag itself could not be read.
    #[error(transparent)]
    Bag(#[from] BagError),
    /// No message on that topic.
    #[error("{file}: no topic `{topic}` (the bag has {})", available.join(", "))]
    UnknownTopic {
        /// The bag.
        file: String,
        /// The topic asked for.
        topic: String,
        /// The topics it has.
        available: Vec<String>,
    },
    /// The topic's recorded type is not one the role uses.
    #[error("{file}: topic `{topic}` is `{recorded}`, but the {role} role needs one of {}", expected.join(", "))]
    WrongType {
        /// The bag.
        file: String,
        /// The topic.
        topic: String,
        /// Its recorded type.
        recorded: String,
        /// The role.
        role: String,
        /// The types the role reads (ROS 1 spelling).
        expected: Vec<String>,
    },
    /// A message does not decode as its recorded type.
    #[error("{file}: topic `{topic}` ({recorded}), message {index} of the bag: {detail}")]
    Undecodable {
        /// The bag.
        file: String,
        /// The topic.
        topic: String,
        /// Its recorded type.
        recorded: String,
        /// The message's index in the bag.
        index: usize,
        /// Why.
        detail: String,
    },
}

/// Every message of `topic` in the bag at `path`, decoded, for `role`
/// (a name for errors), whose recorded type must be one of `expected`
/// (ROS 1 spelling, e.g. `sensor_msgs/Imu`).
///
/// # Errors
/// [`TopicError`] naming the file, topic, type and message index.
pub fn read_topic(
    path: &Path,
    topic: &str,
    role: &str,
    expected: &[&str],
) -> Result<Vec<Stamped>, TopicError> {
    let file = path.display().to_string();
    let mut topics = std::collections::BTreeSet::new();
    let mut out = Vec::new();
    let mut failure: Option<TopicError> = None;
    visit_messages(path, |m| {
        if failure.is_some() {
            return;
        }
        topics.insert(m.topic.to_string());
        if m.topic != topic {
            return;
        }
        let recorded = ros1_type_name(m.message_type);
        if !expected.contains(&recorded.as_str()) {
            failure = Some(TopicError::WrongType {
                file: file.clone(),
                topic: topic.into(),
                recorded: m.message_type.into(),
                role: role.into(),
                expected: expected.iter().map(|s| s.to_string()).collect(),
            });
            return;
        }
        match decode(m.message_type, m.encoding, m.data) {
            Ok(message) => out.push(Stamped {
                log_time_ns: m.log_time_ns,
                message,
            }),
            Err(e) => {
                failure = Some(TopicError::Undecodable {
                    file: file.clone(),
                    topic: topic.into(),
                    recorded: m.message_type.into(),
                    index: m.index,
                    detail: e.0,
                });
            }
        }
    })?;
    if let Some(e) = failure {
        return Err(e);
    }
    if out.is_empty() {
        return Err(TopicError::UnknownTopic {
            file,
            topic: topic.into(),
            available: topics.into_iter().collect(),
        });
    }
    Ok(out)
}

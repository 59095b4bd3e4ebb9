//! One topic of a bag read as typed messages, for a role that needs certain
//! types: an unknown topic, a recorded type the role cannot use, or a
//! message that does not decode is an error naming the file, topic, type
//! and message index.

use std::path::Path;

use super::messages::{RosMessage, decode};
use super::{BagError, Damage, OnDamage, ros1_type_name, visit_messages_with};

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

/// One topic to read, for a role that needs one of `expected` (ROS 1
/// spelling, e.g. `sensor_msgs/Imu`).
#[derive(Debug, Clone, Copy)]
pub struct TopicRequest<'a> {
    /// The topic.
    pub topic: &'a str,
    /// The role, for errors.
    pub role: &'a str,
    /// The types the role reads.
    pub expected: &'a [&'a str],
    /// Whether a bag may lack the topic (then it reads as no messages).
    pub optional: bool,
}

/// Every message of each requested topic in the bag at `path`, decoded, in
/// one pass over the file (a bag is decompressed once, whatever the number
/// of roles); one vector per request, in request order, and what damaged
/// chunks were skipped (`on_damage`).
///
/// # Errors
/// [`TopicError`] naming the file, topic, type and message index.
pub fn read_topics(
    path: &Path,
    requests: &[TopicRequest<'_>],
    on_damage: OnDamage,
) -> Result<(Vec<Vec<Stamped>>, Damage), TopicError> {
    let file = path.display().to_string();
    let mut topics = std::collections::BTreeSet::new();
    let mut out: Vec<Vec<Stamped>> = vec![Vec::new(); requests.len()];
    let mut failure: Option<TopicError> = None;
    let visited = visit_messages_with(path, on_damage, |m| {
        if failure.is_some() {
            return;
        }
        topics.insert(m.topic.to_string());
        for (r, messages) in requests.iter().zip(out.iter_mut()) {
            if m.topic != r.topic {
                continue;
            }
            let recorded = ros1_type_name(m.message_type);
            if !r.expected.contains(&recorded.as_str()) {
                failure = Some(TopicError::WrongType {
                    file: file.clone(),
                    topic: r.topic.into(),
                    recorded: m.message_type.into(),
                    role: r.role.into(),
                    expected: r.expected.iter().map(|s| s.to_string()).collect(),
                });
                return;
            }
            match decode(m.message_type, m.encoding, m.data) {
                Ok(message) => messages.push(Stamped {
                    log_time_ns: m.log_time_ns,
                    message,
                }),
                Err(e) => {
                    failure = Some(TopicError::Undecodable {
                        file: file.clone(),
                        topic: r.topic.into(),
                        recorded: m.message_type.into(),
                        index: m.index,
                        detail: e.0,
                    });
                    return;
                }
            }
        }
    })?;
    if let Some(e) = failure {
        return Err(e);
    }
    if let Some(r) = requests
        .iter()
        .zip(&out)
        .find_map(|(r, m)| (m.is_empty() && !r.optional).then_some(r))
    {
        return Err(TopicError::UnknownTopic {
            file,
            topic: r.topic.into(),
            available: topics.into_iter().collect(),
        });
    }
    Ok((out, visited.damage))
}

/// Every message of `topic` in the bag at `path`, decoded, for `role`
/// (a name for errors), whose recorded type must be one of `expected`.
///
/// # Errors
/// As [`read_topics`].
pub fn read_topic(
    path: &Path,
    topic: &str,
    role: &str,
    expected: &[&str],
) -> Result<Vec<Stamped>, TopicError> {
    let request = TopicRequest {
        topic,
        role,
        expected,
        optional: false,
    };
    Ok(read_topics(path, &[request], OnDamage::Stop)?.0.remove(0))
}

//! What a bag holds: topics, types, message counts, rates and duration.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::{BagError, BagFormat, Checksums, Damage, OnDamage, visit_messages_with};

/// One topic of a bag.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TopicInfo {
    /// The topic.
    pub topic: String,
    /// Its type as recorded.
    pub message_type: String,
    /// Its serialisation (`cdr`, `ros1`).
    pub encoding: String,
    /// Messages.
    pub count: usize,
    /// First receive time (ns since the epoch).
    pub first_ns: u64,
    /// Last receive time (ns).
    pub last_ns: u64,
    /// The median interval between successive messages in time order
    /// (ns); `None` with fewer than two messages at distinct times.
    pub median_interval_ns: Option<u64>,
    /// Messages the file's summary declares for the topic (MCAP with
    /// summary statistics), beside the `count` actually read.
    pub declared_count: Option<u64>,
    /// The rate the summary's statistics give: the declared count over the
    /// recording's declared span (Hz; MCAP with summary statistics). It
    /// does not depend on any message's stamp being right.
    pub summary_rate_hz: Option<f64>,
    /// What a topic map needs of its messages: frame ids (`frame` or
    /// `frame → child` for odometry), joint names, a TF message's
    /// `parent → child` pairs, an image's `frame: encoding W×H` (or its
    /// compression), or a camera info's `frame: W×H, model`, each once, in the order first seen (from
    /// the first 100 messages; every message of a TF topic).
    pub names: Vec<String>,
}

/// How many messages of a topic `bag info` decodes for its frame ids and
/// joint names (a TF topic: all of them).
const NAMES_FROM_MESSAGES: usize = 100;

/// The names a topic map needs from one decoded message.
fn names_of(message: &super::messages::RosMessage) -> Vec<String> {
    use super::messages::RosMessage as M;
    match message {
        M::Imu(m) => vec![m.header.frame_id.clone()],
        M::Odometry(m) => vec![format!("{} → {}", m.header.frame_id, m.child_frame_id)],
        M::NavSatFix(m) => vec![m.header.frame_id.clone()],
        M::JointState(m) => m.name.clone(),
        M::PoseStamped(h, _) | M::PoseWithCovarianceStamped(h, _, _) | M::TwistStamped(h, _) => {
            vec![h.frame_id.clone()]
        }
        M::Tf(transforms) => transforms
            .iter()
            .map(|t| format!("{} → {}", t.header.frame_id, t.child_frame_id))
            .collect(),
        M::Image(m) => vec![format!(
            "{}: {} {}×{}",
            m.header.frame_id, m.encoding, m.width, m.height
        )],
        M::CompressedImage(m) => vec![format!("{}: {}", m.header.frame_id, m.format)],
        M::CameraInfo(m) => vec![format!(
            "{}: {}×{}, {}",
            m.header.frame_id, m.width, m.height, m.distortion_model
        )],
    }
}

impl TopicInfo {
    /// Mean rate: `(count − 1)` intervals over the span (Hz; 0 for fewer
    /// than two messages). One stamp far from the others makes it tiny.
    pub fn rate_hz(&self) -> f64 {
        let span = self.last_ns.saturating_sub(self.first_ns) as f64 * 1e-9;
        if self.count < 2 || span <= 0.0 {
            0.0
        } else {
            (self.count - 1) as f64 / span
        }
    }

    /// The typical rate: one over the median interval (Hz), which a few
    /// stamps far from the others do not move; `None` when it cannot be
    /// computed.
    pub fn typical_rate_hz(&self) -> Option<f64> {
        self.median_interval_ns
            .filter(|&dt| dt > 0)
            .map(|dt| 1e9 / dt as f64)
    }
}

/// Nanoseconds since the epoch as exact decimal seconds (`s.nnnnnnnnn`),
/// the same digits `--json` gives, never rounded through an `f64`.
fn exact_secs(ns: u64) -> String {
    format!("{}.{:09}", ns / 1_000_000_000, ns % 1_000_000_000)
}

/// The median of the positive intervals between the sorted `stamps`.
fn median_interval(mut stamps: Vec<u64>) -> Option<u64> {
    stamps.sort_unstable();
    let mut intervals: Vec<u64> = stamps
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|&d| d > 0)
        .collect();
    if intervals.is_empty() {
        return None;
    }
    let mid = intervals.len() / 2;
    Some(*intervals.select_nth_unstable(mid).1)
}

/// A bag's summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BagInfo {
    /// The file.
    pub path: PathBuf,
    /// Its format.
    pub format: BagFormat,
    /// Messages in all.
    pub messages: usize,
    /// First receive time (ns since the epoch).
    pub start_ns: u64,
    /// Last receive time (ns).
    pub end_ns: u64,
    /// Every topic, by name.
    pub topics: Vec<TopicInfo>,
    /// The damaged chunks skipped ([`OnDamage::Skip`]); empty for an
    /// intact file.
    pub damage: Damage,
    /// The checksums the file stored and the read checked (MCAP).
    pub checksums: Option<Checksums>,
}

impl BagInfo {
    /// Reads every message of the bag at `path`; any damage is an error.
    ///
    /// # Errors
    /// [`BagError`].
    pub fn read(path: &Path) -> Result<Self, BagError> {
        Self::read_with(path, OnDamage::Stop)
    }

    /// Reads every message of the bag at `path`, stopping at damage or
    /// skipping damaged MCAP chunks as `on_damage` says.
    ///
    /// # Errors
    /// [`BagError`].
    pub fn read_with(path: &Path, on_damage: OnDamage) -> Result<Self, BagError> {
        // Per topic: what is reported, every stamp (for the median
        // interval) and whether it is a TF topic (decoded whole).
        let mut topics: BTreeMap<String, (TopicInfo, Vec<u64>, bool)> = BTreeMap::new();
        let visited = visit_messages_with(path, on_damage, |m| {
            if !topics.contains_key(m.topic) {
                let info = TopicInfo {
                    topic: m.topic.to_string(),
                    message_type: m.message_type.to_string(),
                    encoding: m.encoding.to_string(),
                    count: 0,
                    first_ns: m.log_time_ns,
                    last_ns: m.log_time_ns,
                    median_interval_ns: None,
                    declared_count: None,
                    summary_rate_hz: None,
                    names: Vec::new(),
                };
                let is_tf = super::ros1_type_name(m.message_type) == "tf2_msgs/TFMessage";
                topics.insert(m.topic.to_string(), (info, Vec::new(), is_tf));
            }
            let Some((entry, stamps, is_tf)) = topics.get_mut(m.topic) else {
                return;
            };
            entry.count += 1;
            stamps.push(m.log_time_ns);
            if (*is_tf || entry.count <= NAMES_FROM_MESSAGES)
                && let Ok(message) = super::messages::decode(m.message_type, m.encoding, m.data)
            {
                for name in names_of(&message) {
                    if !entry.names.contains(&name) {
                        entry.names.push(name);
                    }
                }
            }
            entry.first_ns = entry.first_ns.min(m.log_time_ns);
            entry.last_ns = entry.last_ns.max(m.log_time_ns);
        })?;
        let topics: Vec<TopicInfo> = topics
            .into_values()
            .map(|(mut info, stamps, _)| {
                info.median_interval_ns = median_interval(stamps);
                info.declared_count = visited
                    .declared_counts
                    .as_ref()
                    .map(|c| c.get(&info.topic).copied().unwrap_or(0));
                info.summary_rate_hz = info
                    .declared_count
                    .zip(visited.declared_span_ns)
                    .map(|(n, (start, end))| (n, end.saturating_sub(start) as f64 * 1e-9))
                    .filter(|&(_, secs)| secs > 0.0)
                    .map(|(n, secs)| n as f64 / secs);
                info
            })
            .collect();
        let start_ns = topics.iter().map(|t| t.first_ns).min().unwrap_or(0);
        let end_ns = topics.iter().map(|t| t.last_ns).max().unwrap_or(0);
        Ok(Self {
            path: path.to_path_buf(),
            format: visited.format,
            messages: visited.messages,
            start_ns,
            end_ns,
            topics,
            damage: visited.damage,
            checksums: visited.checksums,
        })
    }

    /// What reading the file checked.
    pub fn checked(&self) -> String {
        match self.format {
            BagFormat::Mcap => format!(
                "every record's length, {}, stamps within the summary's span, counts against the summary; rates from the messages read{}",
                self.checksums.unwrap_or_default(),
                if self.topics.iter().any(|t| t.summary_rate_hz.is_some()) {
                    " and from the summary's statistics"
                } else {
                    " (the summary has no statistics, or a zero span, to give rates)"
                }
            ),
            BagFormat::Ros1 => {
                "every record's header and length, the index section (a ROS 1 bag stores no checksums); rates from the messages read".into()
            }
            BagFormat::Db3 => {
                "SQLite's own structure checks (it stores no checksums); rates from the messages read".into()
            }
        }
    }

    /// Duration from the first to the last message (s).
    pub fn duration_secs(&self) -> f64 {
        self.end_ns.saturating_sub(self.start_ns) as f64 * 1e-9
    }

    /// The summary as `ros2 bag info` lays it out.
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "Files:             {}\nFormat:            {}\nDuration:          {:.3} s\nStart:             {} (s since epoch)\nEnd:               {}\nMessages:          {}\nTopics:\n",
            self.path.display(),
            self.format,
            self.duration_secs(),
            exact_secs(self.start_ns),
            exact_secs(self.end_ns),
            self.messages
        );
        s.insert_str(
            s.find("Topics:").unwrap_or(s.len()),
            &format!("Checked:           {}\n", self.checked()),
        );
        if !self.damage.is_empty() {
            s.insert_str(
                s.find("Topics:").unwrap_or(s.len()),
                &format!("Damage:            {}\n", self.damage),
            );
        }
        let width = self.topics.iter().map(|t| t.topic.len()).max().unwrap_or(0);
        let type_width = self
            .topics
            .iter()
            .map(|t| t.message_type.len())
            .max()
            .unwrap_or(0);
        for t in &self.topics {
            let decoded = super::messages::SUPPORTED_TYPES
                .contains(&super::ros1_type_name(&t.message_type).as_str());
            // The typical rate; where the mean over the whole span is far
            // below it, a stamp lies far from the others.
            let rate = match t.typical_rate_hz() {
                Some(r) if t.rate_hz() < 0.5 * r => format!(
                    "{r:8.2} Hz, but {:.3} Hz over its {:.1} s: stamps far apart",
                    t.rate_hz(),
                    t.last_ns.saturating_sub(t.first_ns) as f64 * 1e-9
                ),
                Some(r) => format!("{r:8.2} Hz"),
                None => "rate unknown (fewer than two distinct stamps)".into(),
            };
            let mut declared = match t.declared_count {
                Some(n) if n != t.count as u64 => format!("; the summary declares {n}"),
                _ => String::new(),
            };
            // Beside the typical rate, unless stamps far apart stretch the
            // summary's declared span too (the line says so already).
            if let Some(r) = t
                .summary_rate_hz
                .filter(|&r| t.typical_rate_hz().is_none_or(|typical| r >= 0.5 * typical))
            {
                declared.push_str(&format!("; the summary: {r:.2} Hz over the recording"));
            }
            s.push_str(&format!(
                "  {:width$}  {:type_width$}  {:>7} msgs  {rate}  ({}{}{declared})\n",
                t.topic,
                t.message_type,
                t.count,
                t.encoding,
                if decoded {
                    ""
                } else {
                    "; not a type gpodo reads"
                }
            ));
            if !t.names.is_empty() {
                let what = match super::ros1_type_name(&t.message_type).as_str() {
                    "sensor_msgs/JointState" => "joints",
                    "tf2_msgs/TFMessage" => "transforms",
                    _ => "frames",
                };
                s.push_str(&format!(
                    "  {:width$}  {what}: {}\n",
                    "",
                    t.names.join(", ")
                ));
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_interval_ignores_a_stamp_far_from_the_others() {
        // 10 Hz for 5 s, then one stamp an hour later, out of order.
        let mut stamps: Vec<u64> = (0..50).map(|k| k * 100_000_000).collect();
        stamps.insert(7, 3_600_000_000_000);
        assert_eq!(median_interval(stamps), Some(100_000_000));
        assert_eq!(median_interval(vec![5, 5, 5]), None);
        assert_eq!(median_interval(vec![]), None);
    }

    #[test]
    fn times_are_printed_to_the_nanosecond() {
        assert_eq!(
            exact_secs(1_432_235_498_025_043_011),
            "1432235498.025043011"
        );
        assert_eq!(exact_secs(5), "0.000000005");
    }
}

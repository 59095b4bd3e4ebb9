//! Robot recordings as ROS bags: ROS 2 MCAP (chunked, zstd or lz4) through
//! the `mcap` crate and ROS 1 bag v2.0 (bz2 or lz4 chunks) through the
//! `rosbag` crate, recognised by their magic bytes rather than their file
//! names. [`visit_messages`] walks every message of either kind in file
//! order with its topic, recorded type and receive time; [`messages`]
//! decodes the message types gpodo uses from either serialisation
//! ([`wire`]); [`BagInfo`] is what `gpodo bag info` prints (what `ros2 bag
//! info` shows); [`write::write_mcap`] writes a rover log as a ROS 2 MCAP.

mod cdr_write;
mod damage;
pub mod enu;
pub mod frames;
pub mod images;
pub mod import;
mod info;
mod log_messages;
mod mcap_walk;
pub mod messages;
pub mod tf;
pub mod topic;
pub mod wire;
pub mod write;
pub mod write_camera;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

pub use damage::{Checksums, Damage, OnDamage};
pub use info::{BagInfo, TopicInfo};

/// The first bytes of an MCAP file.
const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";
/// The first bytes of a ROS 1 bag, version 2.0.
const ROSBAG_MAGIC: &[u8] = b"#ROSBAG V2.0\n";
/// The first bytes of an SQLite database (a ROS 2 `.db3` bag).
const SQLITE_MAGIC: &[u8] = b"SQLite format 3\0";

/// The container formats gpodo reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BagFormat {
    /// ROS 2 MCAP (messages in CDR).
    #[default]
    Mcap,
    /// ROS 1 bag v2.0 (messages in ROS 1 serialisation).
    Ros1,
    /// ROS 2 SQLite (`.db3`, messages in CDR); read with the `db3` feature.
    Db3,
}

impl std::fmt::Display for BagFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Mcap => "MCAP (ROS 2)",
            Self::Ros1 => "ROS 1 bag v2.0",
            Self::Db3 => "SQLite (ROS 2 .db3)",
        })
    }
}

/// Why a bag could not be read.
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    /// The file could not be opened or read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file is not a bag gpodo reads.
    #[error("{}: {detail}", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// What its first bytes are, and what was expected.
        detail: String,
    },
    /// The container is damaged (a bad chunk, record or index).
    #[error("{}: message {index}: {detail}", path.display())]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// How many messages were read before the damage.
        index: usize,
        /// The reader's message.
        detail: String,
    },
}

/// One message as stored: where it was published, its recorded type and
/// encoding, when it was received, and its serialised bytes.
#[derive(Debug, Clone, Copy)]
pub struct RawMessage<'a> {
    /// Its position in the file (from 0).
    pub index: usize,
    /// The topic.
    pub topic: &'a str,
    /// The type as recorded (`sensor_msgs/msg/Imu` in ROS 2,
    /// `sensor_msgs/Imu` in ROS 1).
    pub message_type: &'a str,
    /// The serialisation: `cdr` (ROS 2) or `ros1`.
    pub encoding: &'a str,
    /// Receive (log) time, nanoseconds since the Unix epoch.
    pub log_time_ns: u64,
    /// The serialised message.
    pub data: &'a [u8],
}

/// The ROS 1 form of a type name: `sensor_msgs/msg/Imu` → `sensor_msgs/Imu`.
pub fn ros1_type_name(recorded: &str) -> String {
    match recorded.split('/').collect::<Vec<_>>().as_slice() {
        [package, "msg", name] => format!("{package}/{name}"),
        _ => recorded.to_string(),
    }
}

/// The format of the file at `path`, from its first bytes.
///
/// # Errors
/// [`BagError::Io`], or [`BagError::UnknownFormat`] naming what was found.
pub fn detect_format(path: &Path) -> Result<BagFormat, BagError> {
    use std::io::Read;
    let io = |source| BagError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut head = Vec::with_capacity(16);
    std::fs::File::open(path)
        .map_err(io)?
        .take(16)
        .read_to_end(&mut head)
        .map_err(io)?;
    if head.starts_with(MCAP_MAGIC) {
        return Ok(BagFormat::Mcap);
    }
    if head.starts_with(ROSBAG_MAGIC) {
        return Ok(BagFormat::Ros1);
    }
    if cfg!(feature = "db3") && head.starts_with(SQLITE_MAGIC) {
        return Ok(BagFormat::Db3);
    }
    let shown: String = head
        .iter()
        .map(|b| {
            if b.is_ascii_graphic() || *b == b' ' {
                (*b as char).to_string()
            } else {
                format!("\\x{b:02x}")
            }
        })
        .collect();
    let detail = if head.starts_with(SQLITE_MAGIC) {
        "an SQLite database (a ROS 2 .db3 bag): build gpodo with `--features db3` to read it, or convert it to MCAP, e.g. `ros2 bag convert` or `rosbags-convert --dst-storage mcap`".to_string()
    } else {
        format!(
            "not a bag: it begins `{shown}`; expected an MCAP file (`\\x89MCAP0`) or a ROS 1 bag (`#ROSBAG V2.0`)"
        )
    };
    Err(BagError::UnknownFormat {
        path: path.to_path_buf(),
        detail,
    })
}

/// Calls `visit` with every message of the bag at `path`, in file order,
/// and returns the format and the number of messages; any damage is an
/// error.
///
/// # Errors
/// [`BagError`] naming the file and, for damage, the message index.
pub fn visit_messages(
    path: &Path,
    visit: impl FnMut(RawMessage<'_>),
) -> Result<(BagFormat, usize), BagError> {
    let visited = visit_messages_with(path, OnDamage::Stop, visit)?;
    Ok((visited.format, visited.messages))
}

/// What a walk over a bag found.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Visited {
    /// The container format.
    pub format: BagFormat,
    /// Messages visited.
    pub messages: usize,
    /// What was skipped ([`OnDamage::Skip`]); empty for an intact file.
    pub damage: Damage,
    /// Messages per topic as the file's summary declares them (MCAP with
    /// summary statistics; `None` otherwise).
    pub declared_counts: Option<BTreeMap<String, u64>>,
    /// The checksums an MCAP file stored and the read checked (`None` for
    /// formats without checksums).
    pub checksums: Option<Checksums>,
    /// The first and last receive times the file's summary declares (ns;
    /// MCAP with summary statistics).
    pub declared_span_ns: Option<(u64, u64)>,
}

/// Calls `visit` with every message of the bag at `path`, in file order;
/// a damaged MCAP chunk stops the walk or is skipped, as `on_damage` says.
///
/// # Errors
/// [`BagError`] naming the file and, for damage, the message index.
pub fn visit_messages_with(
    path: &Path,
    on_damage: OnDamage,
    mut visit: impl FnMut(RawMessage<'_>),
) -> Result<Visited, BagError> {
    let file = bag_file(path)?;
    let path = file.as_path();
    let format = detect_format(path)?;
    Ok(match format {
        BagFormat::Mcap => mcap_walk::visit_mcap(path, on_damage, &mut visit)?,
        BagFormat::Ros1 => Visited {
            format,
            messages: visit_ros1(path, &mut visit)?,
            ..Visited::default()
        },
        BagFormat::Db3 => Visited {
            format,
            messages: visit_db3(path, &mut visit)?,
            ..Visited::default()
        },
    })
}

/// The file of the bag at `path`: `path` itself, or, for a ROS 2 bag
/// folder (what `ros2 bag record` writes: `metadata.yaml` beside its
/// storage files) or its `metadata.yaml`, the one `.mcap` or `.db3` file
/// inside that folder.
///
/// # Errors
/// [`BagError::UnknownFormat`] for a folder without exactly one such file,
/// naming what it holds.
pub fn bag_file(path: &Path) -> Result<PathBuf, BagError> {
    // A ROS 2 bag's `metadata.yaml` stands for its folder.
    if path.file_name().is_some_and(|n| n == "metadata.yaml")
        && let Some(folder) = path.parent().filter(|f| f.is_dir())
    {
        return bag_file(folder);
    }
    if !path.is_dir() {
        return Ok(path.to_path_buf());
    }
    let io = |source| BagError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut storage: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(io)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().is_some_and(|e| e == "mcap" || e == "db3"))
        .collect();
    storage.sort();
    match storage.as_slice() {
        [one] => Ok(one.clone()),
        [] => Err(BagError::UnknownFormat {
            path: path.to_path_buf(),
            detail: "a folder without a `.mcap` or `.db3` file; expected a bag file, or a ROS 2 bag folder holding one".into(),
        }),
        many => Err(BagError::UnknownFormat {
            path: path.to_path_buf(),
            detail: format!(
                "a ROS 2 bag folder split into {} files ({}); name each file",
                many.len(),
                many.iter()
                    .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }),
    }
}

/// Every message of a ROS 2 SQLite bag, in time order (as `ros2 bag play`
/// replays it): the `topics` table names each topic's type and
/// serialisation, the `messages` table holds the receive time and bytes.
#[cfg(feature = "db3")]
fn visit_db3(path: &Path, visit: &mut dyn FnMut(RawMessage<'_>)) -> Result<usize, BagError> {
    use rusqlite::{Connection, OpenFlags};
    let corrupt = |index: usize, e: rusqlite::Error| BagError::Corrupt {
        path: path.to_path_buf(),
        index,
        detail: format!("SQLite: {e}"),
    };
    let db = Connection::open_with_flags(path, OpenFlags::SQLITE_OPEN_READ_ONLY)
        .map_err(|e| corrupt(0, e))?;
    let mut topics = std::collections::BTreeMap::new();
    {
        let mut query = db
            .prepare("SELECT id, name, type, serialization_format FROM topics")
            .map_err(|e| corrupt(0, e))?;
        let rows = query
            .query_map([], |r| {
                Ok((
                    r.get::<_, i64>(0)?,
                    (
                        r.get::<_, String>(1)?,
                        r.get::<_, String>(2)?,
                        r.get::<_, String>(3)?,
                    ),
                ))
            })
            .map_err(|e| corrupt(0, e))?;
        for row in rows {
            let (id, topic) = row.map_err(|e| corrupt(0, e))?;
            topics.insert(id, topic);
        }
    }
    let mut query = db
        .prepare("SELECT topic_id, timestamp, data FROM messages ORDER BY timestamp, id")
        .map_err(|e| corrupt(0, e))?;
    let mut rows = query.query([]).map_err(|e| corrupt(0, e))?;
    let mut index = 0;
    while let Some(row) = rows.next().map_err(|e| corrupt(index, e))? {
        let topic_id: i64 = row.get(0).map_err(|e| corrupt(index, e))?;
        let stamp: i64 = row.get(1).map_err(|e| corrupt(index, e))?;
        let data: Vec<u8> = row.get(2).map_err(|e| corrupt(index, e))?;
        let Some((topic, message_type, encoding)) = topics.get(&topic_id) else {
            return Err(BagError::Corrupt {
                path: path.to_path_buf(),
                index,
                detail: format!("a message of topic id {topic_id}, which the topics table lacks"),
            });
        };
        visit(RawMessage {
            index,
            topic,
            message_type,
            encoding,
            log_time_ns: u64::try_from(stamp).unwrap_or(0),
            data: &data,
        });
        index += 1;
    }
    Ok(index)
}

/// Without the `db3` feature an SQLite file is refused by [`detect_format`]
/// before it gets here.
#[cfg(not(feature = "db3"))]
fn visit_db3(path: &Path, _visit: &mut dyn FnMut(RawMessage<'_>)) -> Result<usize, BagError> {
    Err(BagError::UnknownFormat {
        path: path.to_path_buf(),
        detail: "a ROS 2 .db3 bag: build gpodo with `--features db3` to read it".into(),
    })
}

/// The `index_pos` field of a ROS 1 bag's header record: where its index
/// section starts (0 for a recording that was never closed).
fn ros1_index_pos(head: &[u8]) -> Option<u64> {
    let rest = head.strip_prefix(ROSBAG_MAGIC)?;
    let header_len = u32::from_le_bytes(rest.get(..4)?.try_into().ok()?) as usize;
    let mut fields = rest.get(4..4 + header_len)?;
    while fields.len() >= 4 {
        let len = u32::from_le_bytes(fields[..4].try_into().ok()?) as usize;
        let field = fields.get(4..4 + len)?;
        if let Some(value) = field.strip_prefix(b"index_pos=") {
            return Some(u64::from_le_bytes(value.get(..8)?.try_into().ok()?));
        }
        fields = &fields[4 + len..];
    }
    None
}

/// Checks what the `rosbag` crate takes on trust (it slices the file at the
/// header's index position): the header names an index inside the file.
fn check_ros1_layout(path: &Path) -> Result<(), BagError> {
    use std::io::Read as _;
    let io = |source| BagError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let size = file.metadata().map_err(io)?.len();
    let mut head = Vec::with_capacity(4096 + 64);
    file.by_ref()
        .take(4096 + 64)
        .read_to_end(&mut head)
        .map_err(io)?;
    let corrupt = |detail: String| BagError::Corrupt {
        path: path.to_path_buf(),
        index: 0,
        detail,
    };
    match ros1_index_pos(&head) {
        None => Err(corrupt("the bag header record is damaged".into())),
        Some(0) => Err(corrupt(
            "the bag has no index (a recording that was not closed; `rosbag reindex` repairs it)"
                .into(),
        )),
        Some(pos) if pos > size || (pos as usize) < head.len().min(4096) => Err(corrupt(format!(
            "the header puts the index at byte {pos}, but the file has {size} bytes (truncated?)"
        ))),
        Some(_) => Ok(()),
    }
}

fn visit_ros1(path: &Path, visit: &mut dyn FnMut(RawMessage<'_>)) -> Result<usize, BagError> {
    use rosbag::{ChunkRecord, MessageRecord, RosBag};
    check_ros1_layout(path)?;
    let bag = RosBag::new(path).map_err(|source| BagError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let corrupt = |index: usize, e: rosbag::Error| BagError::Corrupt {
        path: path.to_path_buf(),
        index,
        detail: e.to_string(),
    };
    // Connections (topic and type by id) precede their messages in each
    // chunk.
    let mut connections: std::collections::BTreeMap<u32, (String, String)> =
        std::collections::BTreeMap::new();
    let mut index = 0;
    for record in bag.chunk_records() {
        let ChunkRecord::Chunk(chunk) = record.map_err(|e| corrupt(index, e))? else {
            continue;
        };
        for message in chunk.messages() {
            match message.map_err(|e| corrupt(index, e))? {
                MessageRecord::Connection(c) => {
                    connections.insert(c.id, (c.topic.to_string(), c.tp.to_string()));
                }
                MessageRecord::MessageData(m) => {
                    let Some((topic, message_type)) = connections.get(&m.conn_id) else {
                        return Err(BagError::Corrupt {
                            path: path.to_path_buf(),
                            index,
                            detail: format!(
                                "a message of connection {} before its connection record",
                                m.conn_id
                            ),
                        });
                    };
                    visit(RawMessage {
                        index,
                        topic,
                        message_type,
                        encoding: "ros1",
                        log_time_ns: m.time,
                        data: m.data,
                    });
                    index += 1;
                }
            }
        }
    }
    // The index section closes a complete file: a damaged one means the
    // file was cut or overwritten, even if every chunk read.
    for record in bag.index_records() {
        record.map_err(|e| BagError::Corrupt {
            path: path.to_path_buf(),
            index,
            detail: format!("the index section after the messages is damaged ({e}): truncated?"),
        })?;
    }
    Ok(index)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ros2_type_names_take_their_ros1_form() {
        assert_eq!(ros1_type_name("sensor_msgs/msg/Imu"), "sensor_msgs/Imu");
        assert_eq!(ros1_type_name("sensor_msgs/Imu"), "sensor_msgs/Imu");
        assert_eq!(ros1_type_name("weird"), "weird");
    }

    #[test]
    fn a_ros2_bag_folder_is_read_through_its_one_storage_file() {
        let dir = tempfile::tempdir().unwrap();
        let folder = dir.path().join("run_1");
        std::fs::create_dir(&folder).unwrap();
        std::fs::write(
            folder.join("metadata.yaml"),
            "rosbag2_bagfile_information: {}\n",
        )
        .unwrap();
        let e = bag_file(&folder).unwrap_err().to_string();
        assert!(
            e.contains("run_1") && e.contains("without a `.mcap`"),
            "{e}"
        );
        std::fs::write(folder.join("run_1_0.mcap"), b"x").unwrap();
        assert_eq!(bag_file(&folder).unwrap(), folder.join("run_1_0.mcap"));
        assert_eq!(
            bag_file(&folder.join("metadata.yaml")).unwrap(),
            folder.join("run_1_0.mcap")
        );
        std::fs::write(folder.join("run_1_1.mcap"), b"x").unwrap();
        let e = bag_file(&folder).unwrap_err().to_string();
        assert!(e.contains("run_1_0.mcap, run_1_1.mcap"), "{e}");
        let file = dir.path().join("a.bag");
        assert_eq!(bag_file(&file).unwrap(), file);
    }

    #[test]
    fn a_file_that_is_not_a_bag_is_named_with_its_first_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let csv = dir.path().join("log.bag");
        std::fs::write(&csv, "time,x\n0,1\n").unwrap();
        let e = detect_format(&csv).unwrap_err().to_string();
        assert!(e.contains("log.bag") && e.contains("begins `time,x"), "{e}");
        let db3 = dir.path().join("x.mcap");
        std::fs::write(&db3, b"SQLite format 3\0rest").unwrap();
        if cfg!(feature = "db3") {
            assert_eq!(detect_format(&db3).unwrap(), BagFormat::Db3);
        } else {
            let e = detect_format(&db3).unwrap_err().to_string();
            assert!(e.contains("SQLite") && e.contains("MCAP"), "{e}");
        }
    }
}

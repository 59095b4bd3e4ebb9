//! What writing ROS 2 messages shares, for the log's messages
//! (`write.rs`) and the camera's (`write_camera.rs`): the little-endian
//! CDR encoder, the `ros2msg` schema text with its dependencies, the
//! common schema fragments, and the stamps log times are written at.

/// The time the log's 0 s is written at: 2023-11-14T22:13:20Z, in
/// nanoseconds since the Unix epoch.
pub const EPOCH_NS: u64 = 1_700_000_000_000_000_000;

/// The stamp of a log time (s): [`EPOCH_NS`] plus whole nanoseconds.
pub(super) fn stamp_ns(time_secs: f64) -> u64 {
    EPOCH_NS.saturating_add_signed((time_secs * 1e9).round() as i64)
}

/// The separator between a schema and its dependencies in `ros2msg`
/// schemas (as `rosbag2` writes them).
const SEPARATOR: &str =
    "================================================================================\n";

/// `builtin_interfaces/Time`'s definition.
pub(super) const TIME: &str = "int32 sec\nuint32 nanosec\n";
/// `std_msgs/Header`'s definition.
pub(super) const HEADER: &str = "builtin_interfaces/Time stamp\nstring frame_id\n";

/// A `ros2msg` schema: the type's own definition, then each dependency
/// under `MSG: <name>`.
pub(super) fn schema(definition: &str, dependencies: &[(&str, &str)]) -> String {
    let mut text = definition.to_string();
    for (name, body) in dependencies {
        text.push_str(SEPARATOR);
        text.push_str(&format!("MSG: {name}\n"));
        text.push_str(body);
    }
    text
}

/// Little-endian CDR after the 4-byte encapsulation header; alignment
/// counts from after that header.
pub(super) struct Cdr(pub(super) Vec<u8>);

impl Cdr {
    pub(super) fn new() -> Self {
        Self(vec![0, 1, 0, 0])
    }

    pub(super) fn align(&mut self, n: usize) {
        while !(self.0.len() - 4).is_multiple_of(n) {
            self.0.push(0);
        }
    }

    pub(super) fn u32(&mut self, v: u32) {
        self.align(4);
        self.0.extend(v.to_le_bytes());
    }

    pub(super) fn i32(&mut self, v: i32) {
        self.align(4);
        self.0.extend(v.to_le_bytes());
    }

    pub(super) fn f64s(&mut self, v: &[f64]) {
        for x in v {
            self.align(8);
            self.0.extend(x.to_le_bytes());
        }
    }

    pub(super) fn sequence(&mut self, v: &[f64]) {
        self.u32(v.len() as u32);
        self.f64s(v);
    }

    pub(super) fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.0.extend(s.as_bytes());
        self.0.push(0);
    }

    pub(super) fn header(&mut self, stamp_ns: u64, frame: &str) {
        // `sec` is an int32: fine until 2038.
        self.i32((stamp_ns / 1_000_000_000) as i32);
        self.u32((stamp_ns % 1_000_000_000) as u32);
        self.string(frame);
    }
}

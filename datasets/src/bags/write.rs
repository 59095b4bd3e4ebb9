//! A rover log written as a ROS 2 MCAP bag (`gpodo simulate --format
//! mcap`), with the standard message types and full `ros2msg` schemas, so
//! that ROS tools (and Python's `mcap-ros2-support`) decode it as they
//! decode a bag recorded by `ros2 bag record`:
//!
//! | topic | type | content |
//! | --- | --- | --- |
//! | `/joint_states` | `sensor_msgs/msg/JointState` | every joint: `<wheel>_wheel`, `<joint>_steer`, `<bogie>_bogie` (rad, rad/s) |
//! | `/imu/data` | `sensor_msgs/msg/Imu` | only when the log has an IMU: gyro, specific force; orientation from the log's roll and pitch and the ground truth's yaw |
//! | `/ground_truth/pose` | `geometry_msgs/msg/PoseStamped` | `world_from_body` in frame `world` |
//! | `/tf` | `tf2_msgs/msg/TFMessage` | the same pose as the transform `world` → `base_link` |
//! | `/odom` | `nav_msgs/msg/Odometry` | only when the log has the robot's own odometry: its twist in `base_link` |
//! | `/vo/pose` | `geometry_msgs/msg/PoseStamped` | only from [`write_mcap_with_vo`]: a visual-odometry trajectory in frame `vo` |
//!
//! Stamps are [`EPOCH_NS`] plus the log's time, in whole nanoseconds, as
//! header stamps and as log times. [`written_topic_map`] is the topic map
//! that imports such a file back.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};

pub use super::cdr_write::EPOCH_NS;
use super::cdr_write::{Cdr, stamp_ns};
use super::import::{GroundTruthSource, JointMap, JointRef, TopicMap};
pub use super::log_messages::{
    DiagnosticStatus, diagnostic_array_message, diagnostic_status_message, odometry_message,
};
use super::log_messages::{
    imu_message, imu_schema, joint_state_schema, odometry_schema, pose_stamped,
    pose_stamped_schema, tf_message, tf_schema,
};
use crate::DatasetError;
use crate::log::RoverLog;
use crate::log::write::StagedFile;

/// A `sensor_msgs/JointState` of sample `s`: every joint in `names`
/// order, the wheels in `units`.
fn joint_state_message(
    t: u64,
    names: &[String],
    s: &gpodo_traits::ProprioceptiveSample,
    units: WheelUnits,
) -> Vec<u8> {
    let mut m = Cdr::new();
    m.header(t, "base_link");
    m.u32(names.len() as u32);
    for n in names {
        m.string(n);
    }
    let wheel = |j: &gpodo_traits::JointState| {
        (
            j.position_rad / units.position_scale,
            j.rate_radps / units.rate_scale,
        )
    };
    let all: Vec<(f64, f64)> = s
        .wheels
        .iter()
        .map(wheel)
        .chain(
            s.steering
                .iter()
                .chain(&s.bogies)
                .map(|j| (j.position_rad, j.rate_radps)),
        )
        .collect();
    m.sequence(&all.iter().map(|j| j.0).collect::<Vec<_>>());
    m.sequence(&all.iter().map(|j| j.1).collect::<Vec<_>>());
    m.sequence(&[]);
    m.0
}

/// An MCAP of ROS 2 `nav_msgs/msg/Odometry` topics, built in memory and
/// written (to a temporary name, then renamed) when finished.
pub struct OdometryMcap {
    writer: mcap::Writer<Cursor<Vec<u8>>>,
    channels: Vec<u16>,
    sequence: u32,
    path: PathBuf,
}

impl OdometryMcap {
    /// An MCAP at `path` with one Odometry channel per topic.
    ///
    /// # Errors
    /// [`DatasetError::Io`] naming the file.
    pub fn new(path: &Path, topics: &[&str]) -> Result<Self, DatasetError> {
        let mcap_error = |e: mcap::McapError| DatasetError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::other(e),
        };
        let mut writer = ros2_writer().map_err(mcap_error)?;
        let schema = writer
            .add_schema(
                "nav_msgs/msg/Odometry",
                "ros2msg",
                odometry_schema().as_bytes(),
            )
            .map_err(mcap_error)?;
        let channels = topics
            .iter()
            .map(|topic| writer.add_channel(schema, topic, "cdr", &BTreeMap::new()))
            .collect::<Result<Vec<u16>, _>>()
            .map_err(mcap_error)?;
        Ok(Self {
            writer,
            channels,
            sequence: 0,
            path: path.to_path_buf(),
        })
    }

    /// Writes `data` (an [`odometry_message`]) on the `topic`-th topic, at
    /// `stamp_ns`.
    ///
    /// # Errors
    /// [`DatasetError::Io`] naming the file, or for a topic it does not
    /// have.
    pub fn write(&mut self, topic: usize, stamp_ns: u64, data: &[u8]) -> Result<(), DatasetError> {
        let io = |detail: String| DatasetError::Io {
            path: self.path.clone(),
            source: std::io::Error::other(detail),
        };
        let channel = *self
            .channels
            .get(topic)
            .ok_or_else(|| io(format!("no topic {topic}")))?;
        put(&mut self.writer, channel, self.sequence, stamp_ns, data)
            .map_err(|e| io(e.to_string()))?;
        self.sequence += 1;
        Ok(())
    }

    /// Closes the file and writes it; returns its path.
    ///
    /// # Errors
    /// [`DatasetError::Io`] naming the file.
    pub fn finish(mut self) -> Result<PathBuf, DatasetError> {
        let path = self.path.clone();
        self.writer.finish().map_err(|e| DatasetError::Io {
            path: path.clone(),
            source: std::io::Error::other(e),
        })?;
        let bytes = self.writer.into_inner().into_inner();
        StagedFile::stage(&path, &bytes)?.commit()
    }
}

/// An in-memory MCAP writer with ROS 2's profile and gpodo's chunk size.
fn ros2_writer() -> Result<mcap::Writer<Cursor<Vec<u8>>>, mcap::McapError> {
    mcap::WriteOptions::new()
        .profile("ros2")
        .chunk_size(Some(CHUNK_BYTES))
        .create(Cursor::new(Vec::new()))
}

fn joint_names(log: &RoverLog) -> Vec<String> {
    log.wheel_names
        .iter()
        .map(|n| format!("{n}_wheel"))
        .chain(log.steer_names.iter().map(|n| format!("{n}_steer")))
        .chain(log.bogie_names.iter().map(|n| format!("{n}_bogie")))
        .collect()
}

/// How a written bag records its wheel joints: the radians per recorded
/// unit a topic map's `position_scale` and `rate_scale` give (the default,
/// 1 and 1, is the wheel's own rad and rad/s, as ROS specifies).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelUnits {
    /// Wheel radians per recorded position unit.
    pub position_scale: f64,
    /// Wheel rad/s per recorded rate unit.
    pub rate_scale: f64,
}

impl Default for WheelUnits {
    fn default() -> Self {
        Self {
            position_scale: 1.0,
            rate_scale: 1.0,
        }
    }
}

/// The unit of a recorded wheel rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum WheelRate {
    /// rad/s of the wheel.
    #[default]
    RadPerSec,
    /// Revolutions per minute of the motor, before the gearbox.
    MotorRpm,
    /// rad/min of the motor, before the gearbox.
    MotorRadPerMin,
}

impl WheelUnits {
    /// Wheel encoders as motor controllers record them: positions in
    /// `ticks_per_turn` ticks per motor turn (`None`: the wheel's rad),
    /// rates in `rate`, behind a `gear_ratio`:1 gearbox (motor turns per
    /// wheel turn).
    pub fn encoders(ticks_per_turn: Option<f64>, gear_ratio: f64, rate: WheelRate) -> Self {
        use std::f64::consts::TAU;
        Self {
            position_scale: ticks_per_turn.map_or(1.0, |t| TAU / (t * gear_ratio)),
            rate_scale: match rate {
                WheelRate::RadPerSec => 1.0,
                WheelRate::MotorRpm => TAU / (60.0 * gear_ratio),
                WheelRate::MotorRadPerMin => 1.0 / (60.0 * gear_ratio),
            },
        }
    }
}

/// The topic map that imports a bag written by [`write_mcap`] back into the
/// log's joints, at `rate_hz`.
pub fn written_topic_map(log: &RoverLog, rate_hz: f64) -> TopicMap {
    written_topic_map_in(log, rate_hz, WheelUnits::default())
}

/// The topic map that imports a bag written by [`write_mcap_with`] with
/// its wheels in `units`.
pub fn written_topic_map_in(log: &RoverLog, rate_hz: f64, units: WheelUnits) -> TopicMap {
    let refs = |names: &[String], suffix: &str| -> BTreeMap<String, JointRef> {
        let scales = if suffix == "wheel" {
            units
        } else {
            WheelUnits::default()
        };
        names
            .iter()
            .map(|n| {
                (
                    n.clone(),
                    JointRef {
                        joint: format!("{n}_{suffix}"),
                        position_scale: scales.position_scale,
                        rate_scale: scales.rate_scale,
                    },
                )
            })
            .collect()
    };
    let has_joints =
        !(log.wheel_names.is_empty() && log.steer_names.is_empty() && log.bogie_names.is_empty());
    let has_odometry = log.samples.first().is_some_and(|s| s.odometry.is_some());
    TopicMap {
        imu: log
            .samples
            .first()
            .is_some_and(|s| s.imu.is_some())
            .then(|| "/imu/data".into()),
        imu_rotation_rpy_rad: [0.0; 3],
        ground_truth: GroundTruthSource::Topic("/ground_truth/pose".into()),
        gnss_heading: Default::default(),
        joints: has_joints.then(|| JointMap {
            topic: "/joint_states".into(),
            wheels: refs(&log.wheel_names, "wheel"),
            steering: refs(&log.steer_names, "steer"),
            bogies: refs(&log.bogie_names, "bogie"),
        }),
        odometry: has_odometry.then(|| "/odom".into()),
        vo: None,
        camera: None,
        rate_hz,
        max_gap_secs: 0.5,
        time: Default::default(),
        skip_damaged: false,
    }
}

/// Writes one message on `channel_id`, logged and published at `time`
/// (ns).
fn put(
    writer: &mut mcap::Writer<Cursor<Vec<u8>>>,
    channel_id: u16,
    sequence: u32,
    time: u64,
    data: &[u8],
) -> Result<(), mcap::McapError> {
    let header = mcap::records::MessageHeader {
        channel_id,
        sequence,
        log_time: time,
        publish_time: time,
    };
    writer.write_to_known_channel(&header, data)
}

/// What [`write_mcap`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct WrittenBag {
    /// The file.
    pub path: PathBuf,
    /// Messages written.
    pub messages: u64,
    /// Its size (bytes).
    pub bytes: u64,
}

/// Uncompressed bytes per MCAP chunk: small enough that a damaged chunk
/// (skipped with `skip_damaged`) loses seconds of a recording, not
/// minutes. It makes a file 2 % larger than the 768 KiB default (the
/// simulated 1723-s test run: 9.76 MB against 9.56 MB).
const CHUNK_BYTES: u64 = 64 * 1024;

/// Writes `log` as the ROS 2 MCAP bag `<dir>/<name>.mcap` (zstd chunks),
/// atomically: in full under a temporary name, then renamed.
///
/// # Errors
/// [`DatasetError::InvalidLog`] when the log does not validate,
/// [`DatasetError::Io`] when the file cannot be written.
pub fn write_mcap(log: &RoverLog, dir: &Path) -> Result<WrittenBag, DatasetError> {
    write_mcap_with_vo(log, dir, &[])
}

/// [`write_mcap`], plus a visual-odometry trajectory `(log time, pose)`,
/// in time order, on `/vo/pose` (each pose written before the first sample
/// not earlier than it; those after the last sample at the end).
///
/// # Errors
/// As [`write_mcap`].
pub fn write_mcap_with_vo(
    log: &RoverLog,
    dir: &Path,
    vo: &[(f64, nalgebra::Isometry3<f64>)],
) -> Result<WrittenBag, DatasetError> {
    write_mcap_with(log, dir, vo, WheelUnits::default())
}

/// [`write_mcap_with_vo`], with the wheel joints recorded in `units` (as a
/// motor controller that counts encoder ticks and motor rpm would).
///
/// # Errors
/// As [`write_mcap`].
pub fn write_mcap_with(
    log: &RoverLog,
    dir: &Path,
    vo: &[(f64, nalgebra::Isometry3<f64>)],
    units: WheelUnits,
) -> Result<WrittenBag, DatasetError> {
    write_mcap_with_camera(log, dir, vo, units, None)
}

/// [`write_mcap_with`], plus a stereo camera's frames: each pair as two
/// `sensor_msgs/msg/Image` (mono8) on `/camera/left/image_raw` and
/// `/camera/right/image_raw` with their `sensor_msgs/msg/CameraInfo` on
/// `/camera/{left,right}/camera_info`, written in time order among the
/// other messages and rendered one pair at a time.
///
/// # Errors
/// As [`write_mcap`], and the camera's errors.
pub fn write_mcap_with_camera(
    log: &RoverLog,
    dir: &Path,
    vo: &[(f64, nalgebra::Isometry3<f64>)],
    units: WheelUnits,
    mut camera: Option<&mut super::write_camera::CameraStream<'_>>,
) -> Result<WrittenBag, DatasetError> {
    if !(units.position_scale.is_finite()
        && units.position_scale > 0.0
        && units.rate_scale.is_finite()
        && units.rate_scale > 0.0)
    {
        return Err(DatasetError::InvalidLog {
            log: log.name.clone(),
            sample: None,
            detail: format!("wheel units must be positive: {units:?}"),
        });
    }
    log.validate()?;
    let path = dir.join(format!("{}.mcap", log.name));
    let mcap_error = |e: mcap::McapError| DatasetError::Io {
        path: path.clone(),
        source: std::io::Error::other(e),
    };
    let mut writer = ros2_writer().map_err(mcap_error)?;
    let none = BTreeMap::new();
    let mut channel = |ty: &str, text: String, topic: &str| -> Result<u16, DatasetError> {
        let schema = writer
            .add_schema(ty, "ros2msg", text.as_bytes())
            .map_err(mcap_error)?;
        writer
            .add_channel(schema, topic, "cdr", &none)
            .map_err(mcap_error)
    };
    let joints = channel(
        "sensor_msgs/msg/JointState",
        joint_state_schema(),
        "/joint_states",
    )?;
    let has_imu = log.samples.first().is_some_and(|s| s.imu.is_some());
    let imu = if has_imu {
        Some(channel("sensor_msgs/msg/Imu", imu_schema(), "/imu/data")?)
    } else {
        None
    };
    let pose = channel(
        "geometry_msgs/msg/PoseStamped",
        pose_stamped_schema(),
        "/ground_truth/pose",
    )?;
    let tf = channel("tf2_msgs/msg/TFMessage", tf_schema(), "/tf")?;
    let has_odometry = log.samples.first().is_some_and(|s| s.odometry.is_some());
    let odom = if has_odometry {
        Some(channel(
            "nav_msgs/msg/Odometry",
            odometry_schema(),
            "/odom",
        )?)
    } else {
        None
    };
    let vo_channel = if vo.is_empty() {
        None
    } else {
        Some(channel(
            "geometry_msgs/msg/PoseStamped",
            pose_stamped_schema(),
            "/vo/pose",
        )?)
    };
    let camera_channels = match camera.as_ref() {
        Some(_) => Some(super::write_camera::CameraChannels::add(&mut channel)?),
        None => None,
    };
    let names = joint_names(log);
    let mut messages = 0u64;
    let mut vo_next = 0;
    let mut frame_next = 0;
    for (k, (s, p)) in log.samples.iter().zip(&log.ground_truth).enumerate() {
        let t = stamp_ns(s.time_secs);
        let joint_state = joint_state_message(t, &names, s, units);
        let imu_data = s.imu.map(|imu| imu_message(t, &imu, p));
        let g = pose_stamped(t, "world", p);
        let f = tf_message(t, p);

        let mut out = Vec::new();
        if let Some(channel) = vo_channel {
            while let Some((time, p)) = vo.get(vo_next).filter(|v| v.0 <= s.time_secs) {
                let at = stamp_ns(*time);
                out.push((channel, pose_stamped(at, "vo", p), at));
                vo_next += 1;
            }
        }
        if let (Some(stream), Some(channels)) = (camera.as_deref_mut(), camera_channels) {
            while let Some(&time) = stream
                .times_secs
                .get(frame_next)
                .filter(|&&c| c <= s.time_secs)
            {
                out.extend(channels.frame(stream, frame_next, time)?);
                frame_next += 1;
            }
        }
        out.push((joints, joint_state, t));
        if let (Some(channel), Some(message)) = (imu, imu_data) {
            out.push((channel, message, t));
        }
        out.extend([(pose, g, t), (tf, f, t)]);
        if let (Some(channel), Some(twist)) = (odom, s.odometry) {
            let o = odometry_message(t, "odom", "base_link", p, &[0.0; 36], &twist, &[0.0; 36]);
            out.push((channel, o, t));
        }
        for (channel_id, data, time) in out {
            put(&mut writer, channel_id, k as u32, time, &data).map_err(mcap_error)?;
            messages += 1;
        }
    }
    // Camera frames and VO poses after the last sample close the file, in
    // order.
    if let (Some(stream), Some(channels)) = (camera, camera_channels) {
        while let Some(&time) = stream.times_secs.get(frame_next) {
            for (channel_id, data, at) in channels.frame(stream, frame_next, time)? {
                put(&mut writer, channel_id, frame_next as u32, at, &data).map_err(mcap_error)?;
                messages += 1;
            }
            frame_next += 1;
        }
    }
    if let Some(channel_id) = vo_channel {
        for (k, (time, p)) in vo.iter().enumerate().skip(vo_next) {
            let at = stamp_ns(*time);
            put(
                &mut writer,
                channel_id,
                k as u32,
                at,
                &pose_stamped(at, "vo", p),
            )
            .map_err(mcap_error)?;
            messages += 1;
        }
    }
    writer.finish().map_err(mcap_error)?;
    let bytes = writer.into_inner().into_inner();
    let staged = StagedFile::stage(&path, &bytes)?;
    let path = staged.commit()?;
    Ok(WrittenBag {
        path,
        messages,
        bytes: bytes.len() as u64,
    })
}

//! The ROS messages gpodo reads from bags, decoded from either
//! serialisation into the same typed structs: `sensor_msgs/JointState`,
//! `sensor_msgs/Imu`, `sensor_msgs/NavSatFix`, `nav_msgs/Odometry`,
//! `geometry_msgs/PoseStamped`, `PoseWithCovarianceStamped`,
//! `TwistStamped`, `tf2_msgs/TFMessage`, and a camera's
//! `sensor_msgs/Image`, `CompressedImage` and `CameraInfo` (made grey
//! images by [`super::images`]).

use serde::Serialize;

use super::ros1_type_name;
use super::wire::{WireError, WireReader};

/// `std_msgs/Header` (ROS 1's `seq` is dropped: ROS 2 has none).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Header {
    /// Stamp, nanoseconds since the epoch.
    pub stamp_ns: i64,
    /// Coordinate frame.
    pub frame_id: String,
}

/// `sensor_msgs/Image`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Image {
    /// Header (the stamp is the exposure's).
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// Pixel encoding (`mono8`, `bgr8`, `rgb8`, …).
    pub encoding: String,
    /// Whether multi-byte pixels are big-endian.
    pub is_bigendian: u8,
    /// Bytes per row.
    pub step: u32,
    /// The pixels, `step` bytes per row.
    #[serde(skip)]
    pub data: Vec<u8>,
}

/// `sensor_msgs/CompressedImage`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CompressedImage {
    /// Header.
    pub header: Header,
    /// The compression (`png`, `jpeg`, or image_transport's
    /// `mono8; png compressed`, …).
    pub format: String,
    /// The compressed stream.
    #[serde(skip)]
    pub data: Vec<u8>,
}

/// `sensor_msgs/CameraInfo`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CameraInfo {
    /// Header.
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// Distortion model (`plumb_bob`, …).
    pub distortion_model: String,
    /// Distortion coefficients.
    pub d: Vec<f64>,
    /// Intrinsic matrix, row-major.
    pub k: [f64; 9],
    /// Rectification rotation, row-major.
    pub r: [f64; 9],
    /// Projection matrix of the rectified image, row-major 3 × 4 (for the
    /// right camera of a pair, `P[3] = −f · baseline`).
    pub p: [f64; 12],
    /// Binning (x, y).
    pub binning: [u32; 2],
    /// Region of interest: x offset, y offset, height, width.
    pub roi: [u32; 4],
    /// Whether the region of interest is rectified.
    pub roi_do_rectify: bool,
}

/// `geometry_msgs/Pose`: position and unit quaternion `[x, y, z, w]`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Pose {
    /// Position (m).
    pub position: [f64; 3],
    /// Orientation `[x, y, z, w]`.
    pub orientation: [f64; 4],
}

/// `geometry_msgs/Twist`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Twist {
    /// Linear velocity (m/s).
    pub linear: [f64; 3],
    /// Angular velocity (rad/s).
    pub angular: [f64; 3],
}

/// `sensor_msgs/Imu`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Imu {
    /// Header.
    pub header: Header,
    /// Orientation `[x, y, z, w]`.
    pub orientation: [f64; 4],
    /// Its covariance (row-major 3 × 3).
    pub orientation_covariance: [f64; 9],
    /// Angular velocity (rad/s).
    pub angular_velocity: [f64; 3],
    /// Its covariance.
    pub angular_velocity_covariance: [f64; 9],
    /// Linear acceleration (m/s²).
    pub linear_acceleration: [f64; 3],
    /// Its covariance.
    pub linear_acceleration_covariance: [f64; 9],
}

/// `nav_msgs/Odometry`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Odometry {
    /// Header (the pose's frame).
    pub header: Header,
    /// The twist's frame.
    pub child_frame_id: String,
    /// Pose.
    pub pose: Pose,
    /// Its covariance (row-major 6 × 6).
    pub pose_covariance: Vec<f64>,
    /// Twist.
    pub twist: Twist,
    /// Its covariance (row-major 6 × 6).
    pub twist_covariance: Vec<f64>,
}

/// `sensor_msgs/NavSatFix`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NavSatFix {
    /// Header.
    pub header: Header,
    /// Fix status (−1 no fix, 0 fix, 1 SBAS, 2 GBAS).
    pub status: i8,
    /// Satellite services used.
    pub service: u16,
    /// Latitude (degrees).
    pub latitude: f64,
    /// Longitude (degrees).
    pub longitude: f64,
    /// Altitude (m).
    pub altitude: f64,
    /// ENU position covariance (row-major 3 × 3, m²).
    pub position_covariance: [f64; 9],
    /// How the covariance is known (0 unknown … 3 known).
    pub position_covariance_type: u8,
}

/// `sensor_msgs/JointState`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointState {
    /// Header.
    pub header: Header,
    /// Joint names.
    pub name: Vec<String>,
    /// Positions (rad or m).
    pub position: Vec<f64>,
    /// Velocities.
    pub velocity: Vec<f64>,
    /// Efforts.
    pub effort: Vec<f64>,
}

/// `geometry_msgs/TransformStamped`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TransformStamped {
    /// Header (the parent frame).
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// Translation (m).
    pub translation: [f64; 3],
    /// Rotation `[x, y, z, w]`.
    pub rotation: [f64; 4],
}

/// A decoded message.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum RosMessage {
    /// `sensor_msgs/Imu`.
    Imu(Imu),
    /// `nav_msgs/Odometry`.
    Odometry(Odometry),
    /// `sensor_msgs/NavSatFix`.
    NavSatFix(NavSatFix),
    /// `sensor_msgs/JointState`.
    JointState(JointState),
    /// `geometry_msgs/PoseStamped`.
    PoseStamped(Header, Pose),
    /// `geometry_msgs/PoseWithCovarianceStamped`: pose and its 6 × 6
    /// covariance.
    PoseWithCovarianceStamped(Header, Pose, Vec<f64>),
    /// `geometry_msgs/TwistStamped`.
    TwistStamped(Header, Twist),
    /// `tf2_msgs/TFMessage`.
    Tf(Vec<TransformStamped>),
    /// `sensor_msgs/Image`.
    Image(Image),
    /// `sensor_msgs/CompressedImage`.
    CompressedImage(CompressedImage),
    /// `sensor_msgs/CameraInfo`.
    CameraInfo(CameraInfo),
}

/// The types [`decode`] reads, in their ROS 1 spelling.
pub const SUPPORTED_TYPES: [&str; 11] = [
    "sensor_msgs/Imu",
    "nav_msgs/Odometry",
    "sensor_msgs/NavSatFix",
    "sensor_msgs/JointState",
    "geometry_msgs/PoseStamped",
    "geometry_msgs/PoseWithCovarianceStamped",
    "geometry_msgs/TwistStamped",
    "tf2_msgs/TFMessage",
    "sensor_msgs/Image",
    "sensor_msgs/CompressedImage",
    "sensor_msgs/CameraInfo",
];

fn header(r: &mut WireReader<'_>) -> Result<Header, WireError> {
    let stamp_ns = if r.is_cdr() {
        let sec = i64::from(r.i32()?);
        sec * 1_000_000_000 + i64::from(r.u32()?)
    } else {
        let _seq = r.u32()?;
        let sec = i64::from(r.u32()?);
        sec * 1_000_000_000 + i64::from(r.u32()?)
    };
    Ok(Header {
        stamp_ns,
        frame_id: r.string()?,
    })
}

fn pose(r: &mut WireReader<'_>) -> Result<Pose, WireError> {
    Ok(Pose {
        position: r.f64s()?,
        orientation: r.f64s()?,
    })
}

fn twist(r: &mut WireReader<'_>) -> Result<Twist, WireError> {
    Ok(Twist {
        linear: r.f64s()?,
        angular: r.f64s()?,
    })
}

fn covariance36(r: &mut WireReader<'_>) -> Result<Vec<f64>, WireError> {
    Ok(r.f64s::<36>()?.to_vec())
}

/// The header and image size of a `sensor_msgs/Image` or
/// `sensor_msgs/CameraInfo` (both begin with header, height, width),
/// read without the pixels or the calibration after them.
///
/// # Errors
/// Bytes too short to hold them.
pub fn decode_image_header(encoding: &str, data: &[u8]) -> Result<(Header, u32, u32), WireError> {
    let mut r = WireReader::new(data, encoding)?;
    let h = header(&mut r)?;
    let height = r.u32()?;
    let width = r.u32()?;
    Ok((h, width, height))
}

/// A `std_msgs/Bool`'s value.
///
/// # Errors
/// Bytes that do not hold one.
pub fn decode_bool(encoding: &str, data: &[u8]) -> Result<bool, WireError> {
    let mut r = WireReader::new(data, encoding)?;
    let value = r.bool()?;
    r.finish()?;
    Ok(value)
}

/// Decodes one message of type `message_type` (ROS 1 or ROS 2 spelling)
/// serialised as `encoding` (`ros1` or `cdr`).
///
/// # Errors
/// An unsupported type, or bytes that do not hold that type.
pub fn decode(message_type: &str, encoding: &str, data: &[u8]) -> Result<RosMessage, WireError> {
    let mut r = WireReader::new(data, encoding)?;
    let r = &mut r;
    let message = match ros1_type_name(message_type).as_str() {
        "sensor_msgs/Imu" => RosMessage::Imu(Imu {
            header: header(r)?,
            orientation: r.f64s()?,
            orientation_covariance: r.f64s()?,
            angular_velocity: r.f64s()?,
            angular_velocity_covariance: r.f64s()?,
            linear_acceleration: r.f64s()?,
            linear_acceleration_covariance: r.f64s()?,
        }),
        "nav_msgs/Odometry" => RosMessage::Odometry(Odometry {
            header: header(r)?,
            child_frame_id: r.string()?,
            pose: pose(r)?,
            pose_covariance: covariance36(r)?,
            twist: twist(r)?,
            twist_covariance: covariance36(r)?,
        }),
        "sensor_msgs/NavSatFix" => RosMessage::NavSatFix(NavSatFix {
            header: header(r)?,
            status: r.i8()?,
            service: r.u16()?,
            latitude: r.f64()?,
            longitude: r.f64()?,
            altitude: r.f64()?,
            position_covariance: r.f64s()?,
            position_covariance_type: r.u8()?,
        }),
        "sensor_msgs/JointState" => RosMessage::JointState(JointState {
            header: header(r)?,
            name: r.strings()?,
            position: r.f64_seq()?,
            velocity: r.f64_seq()?,
            effort: r.f64_seq()?,
        }),
        "geometry_msgs/PoseStamped" => RosMessage::PoseStamped(header(r)?, pose(r)?),
        "geometry_msgs/PoseWithCovarianceStamped" => {
            RosMessage::PoseWithCovarianceStamped(header(r)?, pose(r)?, covariance36(r)?)
        }
        "geometry_msgs/TwistStamped" => RosMessage::TwistStamped(header(r)?, twist(r)?),
        "tf2_msgs/TFMessage" => RosMessage::Tf(r.seq(|r| {
            Ok(TransformStamped {
                header: header(r)?,
                child_frame_id: r.string()?,
                translation: r.f64s()?,
                rotation: r.f64s()?,
            })
        })?),
        "sensor_msgs/Image" => RosMessage::Image(Image {
            header: header(r)?,
            height: r.u32()?,
            width: r.u32()?,
            encoding: r.string()?,
            is_bigendian: r.u8()?,
            step: r.u32()?,
            data: r.bytes()?.to_vec(),
        }),
        "sensor_msgs/CompressedImage" => RosMessage::CompressedImage(CompressedImage {
            header: header(r)?,
            format: r.string()?,
            data: r.bytes()?.to_vec(),
        }),
        "sensor_msgs/CameraInfo" => RosMessage::CameraInfo(CameraInfo {
            header: header(r)?,
            height: r.u32()?,
            width: r.u32()?,
            distortion_model: r.string()?,
            d: r.f64_seq()?,
            k: r.f64s()?,
            r: r.f64s()?,
            p: r.f64s()?,
            binning: [r.u32()?, r.u32()?],
            roi: [r.u32()?, r.u32()?, r.u32()?, r.u32()?],
            roi_do_rectify: r.bool()?,
        }),
        other => {
            return Err(WireError(format!(
                "type `{other}` is not one gpodo reads (it reads {})",
                SUPPORTED_TYPES.join(", ")
            )));
        }
    };
    r.finish()?;
    Ok(message)
}

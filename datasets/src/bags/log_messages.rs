//! A rover log's ROS 2 messages encoded as CDR, with their `ros2msg`
//! schemas: the joint states' and IMU's schemas, the ground truth as a
//! `PoseStamped` and a TF message, the robot's odometry, and the
//! node's diagnostics. [`super::write`] puts them in an MCAP.

use nalgebra::UnitQuaternion;

use super::cdr_write::{Cdr, HEADER, TIME, schema};

const VECTOR3: &str = "float64 x\nfloat64 y\nfloat64 z\n";
const POINT: &str = "float64 x\nfloat64 y\nfloat64 z\n";
const QUATERNION: &str = "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";
const POSE: &str = "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n";
const TRANSFORM: &str = "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n";
const TWIST: &str = "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n";

pub(super) fn joint_state_schema() -> String {
    schema(
        "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n",
        &[
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
        ],
    )
}

pub(super) fn imu_schema() -> String {
    schema(
        "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n\
         geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n\
         geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n",
        &[
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
            ("geometry_msgs/Quaternion", QUATERNION),
            ("geometry_msgs/Vector3", VECTOR3),
        ],
    )
}

pub(super) fn pose_stamped_schema() -> String {
    schema(
        "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
        &[
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
            ("geometry_msgs/Pose", POSE),
            ("geometry_msgs/Point", POINT),
            ("geometry_msgs/Quaternion", QUATERNION),
        ],
    )
}

pub(super) fn tf_schema() -> String {
    schema(
        "geometry_msgs/TransformStamped[] transforms\n",
        &[
            (
                "geometry_msgs/TransformStamped",
                "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n",
            ),
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
            ("geometry_msgs/Transform", TRANSFORM),
            ("geometry_msgs/Vector3", VECTOR3),
            ("geometry_msgs/Quaternion", QUATERNION),
        ],
    )
}

pub(super) fn odometry_schema() -> String {
    schema(
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n\
         geometry_msgs/TwistWithCovariance twist\n",
        &[
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
            (
                "geometry_msgs/PoseWithCovariance",
                "geometry_msgs/Pose pose\nfloat64[36] covariance\n",
            ),
            ("geometry_msgs/Pose", POSE),
            ("geometry_msgs/Point", POINT),
            ("geometry_msgs/Quaternion", QUATERNION),
            (
                "geometry_msgs/TwistWithCovariance",
                "geometry_msgs/Twist twist\nfloat64[36] covariance\n",
            ),
            ("geometry_msgs/Twist", TWIST),
            ("geometry_msgs/Vector3", VECTOR3),
        ],
    )
}

/// A `sensor_msgs/Imu`: the gyro and specific force of `imu`, its
/// orientation from the IMU's roll and pitch and the ground truth `p`'s
/// yaw.
pub(super) fn imu_message(
    t: u64,
    imu: &gpodo_traits::ImuSample,
    p: &nalgebra::Isometry3<f64>,
) -> Vec<u8> {
    let yaw = p.rotation.euler_angles().2;
    let q = UnitQuaternion::from_euler_angles(imu.roll_rad, imu.pitch_rad, yaw);
    let mut i = Cdr::new();
    i.header(t, "base_link");
    i.f64s(&[q.i, q.j, q.k, q.w]);
    i.f64s(&[0.0; 9]);
    i.f64s(imu.gyro_radps.as_slice());
    i.f64s(&[0.0; 9]);
    i.f64s(imu.accel_mps2.as_slice());
    i.f64s(&[0.0; 9]);
    i.0
}

/// A `tf2_msgs/TFMessage` of one transform, `world` → `base_link` at `p`.
pub(super) fn tf_message(t: u64, p: &nalgebra::Isometry3<f64>) -> Vec<u8> {
    let r = p.rotation;
    let position = p.translation.vector;
    let mut f = Cdr::new();
    f.u32(1);
    f.header(t, "world");
    f.string("base_link");
    f.f64s(position.as_slice());
    f.f64s(&[r.i, r.j, r.k, r.w]);
    f.0
}

/// A `geometry_msgs/PoseStamped` in `frame`, stamped `stamp_ns`.
pub(super) fn pose_stamped(stamp_ns: u64, frame: &str, pose: &nalgebra::Isometry3<f64>) -> Vec<u8> {
    let r = pose.rotation;
    let mut m = Cdr::new();
    m.header(stamp_ns, frame);
    m.f64s(pose.translation.vector.as_slice());
    m.f64s(&[r.i, r.j, r.k, r.w]);
    m.0
}

/// A `nav_msgs/msg/Odometry` in CDR: `frame` → `child` at `stamp_ns`,
/// the pose and the twist (in `child`) each with its row-major 6 × 6
/// covariance (x, y, z, then rotation about x, y, z).
pub fn odometry_message(
    stamp_ns: u64,
    frame: &str,
    child: &str,
    pose: &nalgebra::Isometry3<f64>,
    pose_covariance: &[f64; 36],
    twist: &gpodo_traits::BodyTwist,
    twist_covariance: &[f64; 36],
) -> Vec<u8> {
    let r = pose.rotation;
    let mut o = Cdr::new();
    o.header(stamp_ns, frame);
    o.string(child);
    o.f64s(pose.translation.vector.as_slice());
    o.f64s(&[r.i, r.j, r.k, r.w]);
    o.f64s(pose_covariance);
    o.f64s(twist.linear_mps.as_slice());
    o.f64s(twist.angular_radps.as_slice());
    o.f64s(twist_covariance);
    o.0
}

/// One `diagnostic_msgs/msg/DiagnosticStatus`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DiagnosticStatus {
    /// 0 OK, 1 WARN, 2 ERROR, 3 STALE.
    pub level: u8,
    /// The component's name.
    pub name: String,
    /// A one-line summary of its state.
    pub message: String,
    /// The hardware it runs on (may be empty).
    pub hardware_id: String,
    /// Key-value pairs of figures.
    pub values: Vec<(String, String)>,
}

/// A `diagnostic_msgs/msg/DiagnosticArray` in CDR, stamped `stamp_ns`.
pub fn diagnostic_array_message(stamp_ns: u64, status: &[DiagnosticStatus]) -> Vec<u8> {
    let mut d = Cdr::new();
    d.header(stamp_ns, "");
    d.u32(status.len() as u32);
    for s in status {
        diagnostic_status(&mut d, s);
    }
    d.0
}

/// One `diagnostic_msgs/msg/DiagnosticStatus` in CDR (a message of its
/// own, as a topic of decisions carries it).
pub fn diagnostic_status_message(status: &DiagnosticStatus) -> Vec<u8> {
    let mut d = Cdr::new();
    diagnostic_status(&mut d, status);
    d.0
}

fn diagnostic_status(d: &mut Cdr, s: &DiagnosticStatus) {
    d.0.push(s.level);
    d.string(&s.name);
    d.string(&s.message);
    d.string(&s.hardware_id);
    d.u32(s.values.len() as u32);
    for (key, value) in &s.values {
        d.string(key);
        d.string(value);
    }
}

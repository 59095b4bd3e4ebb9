//! The CDR bytes of the odometry and diagnostics gpodo publishes, against
//! the `rosbags` package's serialiser of ROS 2 Humble's
//! `nav_msgs/msg/Odometry` and `diagnostic_msgs/msg/DiagnosticArray`
//! (skipped without it, unless `GPODO_REQUIRE_PYTHON` is set, as in CI).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use gpodo_datasets::bags::write::odometry_message;
use gpodo_testkit::{python_with, run_python};
use gpodo_traits::BodyTwist;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

const SERIALISE: &str = r#"
import json, sys
from rosbags.typesys import Stores, get_typestore
ts = get_typestore(Stores.ROS2_HUMBLE)
T = ts.types
v = json.loads(sys.argv[1])
Vec3 = T['geometry_msgs/msg/Vector3']
msg = T['nav_msgs/msg/Odometry'](
    header=T['std_msgs/msg/Header'](
        stamp=T['builtin_interfaces/msg/Time'](sec=v['sec'], nanosec=v['nanosec']),
        frame_id=v['frame']),
    child_frame_id=v['child'],
    pose=T['geometry_msgs/msg/PoseWithCovariance'](
        pose=T['geometry_msgs/msg/Pose'](
            position=T['geometry_msgs/msg/Point'](*v['position']),
            orientation=T['geometry_msgs/msg/Quaternion'](*v['orientation'])),
        covariance=__import__('numpy').array(v['pose_covariance'], dtype='float64')),
    twist=T['geometry_msgs/msg/TwistWithCovariance'](
        twist=T['geometry_msgs/msg/Twist'](linear=Vec3(*v['linear']), angular=Vec3(*v['angular'])),
        covariance=__import__('numpy').array(v['twist_covariance'], dtype='float64')),
)
print(bytes(ts.serialize_cdr(msg, 'nav_msgs/msg/Odometry')).hex())
"#;

#[test]
fn odometry_is_the_bytes_rosbags_writes() {
    let Some(python) = python_with(&["rosbags", "numpy"], "rosbags") else {
        return;
    };
    let stamp_ns: u64 = 1_700_000_123_456_789_012;
    let rotation = UnitQuaternion::from_euler_angles(0.1, -0.2, 2.5);
    let pose = Isometry3::from_parts(Translation3::new(1.5, -2.25, 0.125), rotation);
    let twist = BodyTwist {
        linear_mps: Vector3::new(0.05, -0.001, 0.0002),
        angular_radps: Vector3::new(0.001, -0.002, 0.03),
    };
    let pose_covariance: [f64; 36] = std::array::from_fn(|k| k as f64 * 0.5);
    let twist_covariance: [f64; 36] = std::array::from_fn(|k| {
        if k % 7 == 0 {
            1e-6 * (k + 1) as f64
        } else {
            0.0
        }
    });
    // Frame names of odd lengths, so the string padding is exercised.
    let (frame, child) = ("odom", "base_footprint");
    let ours = odometry_message(
        stamp_ns,
        frame,
        child,
        &pose,
        &pose_covariance,
        &twist,
        &twist_covariance,
    );
    let q = pose.rotation;
    let values = serde_json::json!({
        "sec": stamp_ns / 1_000_000_000,
        "nanosec": stamp_ns % 1_000_000_000,
        "frame": frame,
        "child": child,
        "position": pose.translation.vector.as_slice(),
        "orientation": [q.i, q.j, q.k, q.w],
        "pose_covariance": pose_covariance.as_slice(),
        "linear": twist.linear_mps.as_slice(),
        "angular": twist.angular_radps.as_slice(),
        "twist_covariance": twist_covariance.as_slice(),
    });
    let theirs = run_python(&python, SERIALISE, &[values.to_string().as_ref()]);
    let ours_hex: String = ours.iter().map(|b| format!("{b:02x}")).collect();
    assert_eq!(ours_hex, theirs.trim(), "gpodo's CDR against rosbags'");
}

const SERIALISE_DIAGNOSTICS: &str = r#"
import json, sys
from rosbags.typesys import Stores, get_typestore
ts = get_typestore(Stores.ROS2_HUMBLE)
T = ts.types
v = json.loads(sys.argv[1])
msg = T['diagnostic_msgs/msg/DiagnosticArray'](
    header=T['std_msgs/msg/Header'](
        stamp=T['builtin_interfaces/msg/Time'](sec=v['sec'], nanosec=v['nanosec']),
        frame_id=''),
    status=[T['diagnostic_msgs/msg/DiagnosticStatus'](
        level=s['level'], name=s['name'], message=s['message'], hardware_id=s['hardware_id'],
        values=[T['diagnostic_msgs/msg/KeyValue'](key=k, value=x) for k, x in s['values']])
        for s in v['status']],
)
print(bytes(ts.serialize_cdr(msg, 'diagnostic_msgs/msg/DiagnosticArray')).hex())
"#;

#[test]
fn diagnostics_are_the_bytes_rosbags_writes() {
    use gpodo_datasets::bags::write::{DiagnosticStatus, diagnostic_array_message};
    let Some(python) = python_with(&["rosbags", "numpy"], "rosbags") else {
        return;
    };
    let stamp_ns: u64 = 1_700_000_001_000_000_123;
    // Strings of every length modulo 4, an empty list of values, and a
    // level byte before strings (its padding).
    let status = vec![
        DiagnosticStatus {
            level: 1,
            name: "gpodo live: /odom/gp".into(),
            message: "stale IMU".into(),
            hardware_id: String::new(),
            values: vec![
                ("model kind".into(), "exact_gp".into()),
                ("latency p99 (ms)".into(), "0.123".into()),
                ("a".into(), "".into()),
            ],
        },
        DiagnosticStatus {
            level: 0,
            name: "x".into(),
            message: "ok".into(),
            hardware_id: "rover".into(),
            values: vec![],
        },
    ];
    let ours = diagnostic_array_message(stamp_ns, &status);
    let values = serde_json::json!({
        "sec": stamp_ns / 1_000_000_000,
        "nanosec": stamp_ns % 1_000_000_000,
        "status": status.iter().map(|s| serde_json::json!({
            "level": s.level,
            "name": s.name,
            "message": s.message,
            "hardware_id": s.hardware_id,
            "values": s.values,
        })).collect::<Vec<_>>(),
    });
    let theirs = run_python(
        &python,
        SERIALISE_DIAGNOSTICS,
        &[values.to_string().as_ref()],
    );
    let ours_hex: String = ours.iter().map(|b| format!("{b:02x}")).collect();
    assert_eq!(ours_hex, theirs.trim(), "gpodo's CDR against rosbags'");
}

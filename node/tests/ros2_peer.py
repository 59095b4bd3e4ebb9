"""A ROS 2 peer of `gpodo live` on Cyclone DDS, without ROS.

It publishes a recording's joint states and IMU messages as ROS 2 does
(topics `rt/...`, types `sensor_msgs::msg::dds_::JointState_` and `Imu_`,
final types in XCDR1, best effort), in the recording's order, and writes
what it receives on `rt/odom/gp` and `rt/diagnostics` to a JSON file.
Half way it restarts its publishers (new writers, as a driver that
restarts), and for a tenth of the recording it publishes as fast as it
can (a burst, about ten times the recorded rate and more).

    ros2_peer.py DOMAIN BAG JOINT_TOPIC IMU_TOPIC OUT.json

Cyclone DDS is configured by the caller (CYCLONEDDS_URI): loopback only,
unicast peers on 127.0.0.1.
"""

import json
import sys
import time
from dataclasses import dataclass

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, float64, int32, sequence, uint8, uint32
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from mcap_ros2.reader import read_ros2_messages


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
    header: Header
    name: sequence[str]
    position: sequence[float64]
    velocity: sequence[float64]
    effort: sequence[float64]


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64
    y: float64
    z: float64
    w: float64


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Imu(IdlStruct, typename="sensor_msgs::msg::dds_::Imu_"):
    header: Header
    orientation: Quaternion
    orientation_covariance: array[float64, 9]
    angular_velocity: Vector3
    angular_velocity_covariance: array[float64, 9]
    linear_acceleration: Vector3
    linear_acceleration_covariance: array[float64, 9]


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point
    orientation: Quaternion


@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    pose: Pose
    covariance: array[float64, 36]


@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3
    angular: Vector3


@dataclass
class TwistWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    twist: Twist
    covariance: array[float64, 36]


@dataclass
class Odometry(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    header: Header
    child_frame_id: str
    pose: PoseWithCovariance
    twist: TwistWithCovariance


@dataclass
class KeyValue(IdlStruct, typename="diagnostic_msgs::msg::dds_::KeyValue_"):
    key: str
    value: str


@dataclass
class DiagnosticStatus(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticStatus_"):
    level: uint8
    name: str
    message: str
    hardware_id: str
    values: sequence[KeyValue]


@dataclass
class DiagnosticArray(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticArray_"):
    header: Header
    status: sequence[DiagnosticStatus]


def header(h):
    return Header(Time(h.stamp.sec, h.stamp.nanosec), h.frame_id)


def vec3(v, cls=Vector3):
    return cls(v.x, v.y, v.z)


def to_idl(msg):
    if hasattr(msg, "name"):
        return JointState(
            header(msg.header),
            list(msg.name),
            [float(x) for x in msg.position],
            [float(x) for x in msg.velocity],
            [float(x) for x in msg.effort],
        )
    o = msg.orientation
    return Imu(
        header(msg.header),
        Quaternion(o.x, o.y, o.z, o.w),
        [float(x) for x in msg.orientation_covariance],
        vec3(msg.angular_velocity),
        [float(x) for x in msg.angular_velocity_covariance],
        vec3(msg.linear_acceleration),
        [float(x) for x in msg.linear_acceleration_covariance],
    )


def stamp_ns(h):
    return h.stamp.sec * 1_000_000_000 + h.stamp.nanosec


def wait(condition, seconds, what):
    end = time.time() + seconds
    while not condition():
        if time.time() > end:
            sys.exit(f"ros2_peer: timed out waiting for {what}")
        time.sleep(0.05)


def main():
    domain, bag, joint_topic, imu_topic, out = sys.argv[1:6]
    # The replay's order: by header stamp, the IMU first at a tie.
    messages = []
    for m in read_ros2_messages(bag, topics=[joint_topic, imu_topic]):
        is_joint = m.channel.topic == joint_topic
        messages.append((stamp_ns(m.ros_msg.header), int(is_joint), to_idl(m.ros_msg)))
    messages.sort(key=lambda t: (t[0], t[1]))
    expected = sum(1 for m in messages if m[1] == 1)

    dp = DomainParticipant(int(domain))
    xcdr1 = Policy.DataRepresentation(use_cdrv0_representation=True)
    sensors = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(100), xcdr1)
    outputs = Qos(
        Policy.Reliability.Reliable(duration(milliseconds=100)),
        Policy.History.KeepLast(1000),
        xcdr1,
    )
    ros = lambda t: "rt/" + t.lstrip("/")
    joint_topic_dds = Topic(dp, ros(joint_topic), JointState)
    imu_topic_dds = Topic(dp, ros(imu_topic), Imu)

    def publishers():
        return (
            DataWriter(dp, joint_topic_dds, qos=sensors),
            DataWriter(dp, imu_topic_dds, qos=sensors),
        )

    joints_w, imu_w = publishers()
    odom_r = DataReader(dp, Topic(dp, "rt/odom/gp", Odometry), qos=outputs)
    diag_r = DataReader(dp, Topic(dp, "rt/diagnostics", DiagnosticArray), qos=outputs)

    def matched():
        wait(
            lambda: joints_w.get_matched_subscriptions()
            and imu_w.get_matched_subscriptions()
            and odom_r.get_matched_publications()
            and diag_r.get_matched_publications(),
            60,
            "gpodo live's readers and writers",
        )
        # A writer that sees its reader is not yet seen by the reader: the
        # node's reader drops best-effort samples of a writer it has not
        # discovered. Give its discovery time (more than enough on a
        # loaded machine) before the first sample.
        time.sleep(1.0)

    matched()
    received, diagnostics = [], []

    def drain():
        # (A writer that leaves sends an invalid sample: its state, no data.)
        for o in odom_r.take(N=1000):
            if not isinstance(o, Odometry):
                continue
            p, q = o.pose.pose.position, o.pose.pose.orientation
            t, a = o.twist.twist.linear, o.twist.twist.angular
            received.append(
                {
                    "stamp_ns": stamp_ns(o.header),
                    "frame_id": o.header.frame_id,
                    "child_frame_id": o.child_frame_id,
                    "position": [p.x, p.y, p.z],
                    "orientation": [q.x, q.y, q.z, q.w],
                    "linear": [t.x, t.y, t.z],
                    "angular": [a.x, a.y, a.z],
                    "twist_covariance": list(o.twist.covariance),
                }
            )
        for d in diag_r.take(N=100):
            if not isinstance(d, DiagnosticArray):
                continue
            for s in d.status:
                diagnostics.append(
                    {
                        "level": int(s.level),
                        "name": s.name,
                        "message": s.message,
                        "values": {kv.key: kv.value for kv in s.values},
                    }
                )

    total = len(messages)
    burst = range(total // 5, total // 5 + total // 10)
    for k, (_, _, message) in enumerate(messages):
        if k == total // 2:
            # The driver restarts: its writers go, new ones come.
            del joints_w, imu_w
            joints_w, imu_w = publishers()
            matched()
        (joints_w if isinstance(message, JointState) else imu_w).write(message)
        if k not in burst:
            # Paced at about 500 messages a second elsewhere.
            time.sleep(0.002)
        drain()
    end = time.time() + 30
    while (len(received) < expected or not diagnostics) and time.time() < end:
        drain()
        time.sleep(0.05)
    with open(out, "w") as f:
        json.dump({"sent_joint_states": expected, "odometry": received, "diagnostics": diagnostics}, f)


if __name__ == "__main__":
    main()

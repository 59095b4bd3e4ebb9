"""A ROS 2 peer of `gpodo live --gate` on Cyclone DDS, without ROS: the
camera driver, the robot's sensors and the visual odometry behind the
gate.

It publishes a recording's joint states, IMU messages and stereo pairs
(images and camera infos, best effort, as camera drivers do) in the
recording's order, one at a time, each after the node has answered the
one before: a joint state's odometry on `/odom/gp`, a pair's decision on
the decisions topic. For each pair the gate forwards it takes the four
gated messages (reliable), checks that each is the message it sent,
byte for byte, and answers as the VO: the odometry the table gives for
that stamp (a null pose, rtabmap's, where the VO lost track), on the VO's
topic, waiting until the node's reader has it.

    ros2_gate_peer.py DOMAIN BAG TOPICS.json VO.json OUT.json

TOPICS.json names the joint, IMU, camera, gated, VO and decision topics;
VO.json maps each stamp (ns, as a string) to `[x, y, z, qx, qy, qz, qw]`.
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
from cyclonedds.idl.types import array, float64, sequence, uint8, uint32
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from mcap_ros2.reader import read_ros2_messages

from ros2_peer import (
    DiagnosticStatus,
    Header,
    Imu,
    JointState,
    Odometry,
    Point,
    Pose,
    PoseWithCovariance,
    Quaternion,
    Time,
    Twist,
    TwistWithCovariance,
    Vector3,
    header,
    stamp_ns,
    to_idl,
    wait,
)


@dataclass
class Image(IdlStruct, typename="sensor_msgs::msg::dds_::Image_"):
    header: Header
    height: uint32
    width: uint32
    encoding: str
    is_bigendian: uint8
    step: uint32
    data: sequence[uint8]


@dataclass
class RegionOfInterest(IdlStruct, typename="sensor_msgs::msg::dds_::RegionOfInterest_"):
    x_offset: uint32
    y_offset: uint32
    height: uint32
    width: uint32
    do_rectify: bool


@dataclass
class CameraInfo(IdlStruct, typename="sensor_msgs::msg::dds_::CameraInfo_"):
    header: Header
    height: uint32
    width: uint32
    distortion_model: str
    d: sequence[float64]
    k: array[float64, 9]
    r: array[float64, 9]
    p: array[float64, 12]
    binning_x: uint32
    binning_y: uint32
    roi: RegionOfInterest


def image_idl(m):
    return Image(
        header(m.header), m.height, m.width, m.encoding, m.is_bigendian, m.step, bytes(m.data)
    )


def info_idl(m):
    r = m.roi
    return CameraInfo(
        header(m.header),
        m.height,
        m.width,
        m.distortion_model,
        [float(x) for x in m.d],
        [float(x) for x in m.k],
        [float(x) for x in m.r],
        [float(x) for x in m.p],
        m.binning_x,
        m.binning_y,
        RegionOfInterest(r.x_offset, r.y_offset, r.height, r.width, bool(r.do_rectify)),
    )


def odometry(stamp, pose):
    x, y, z, qx, qy, qz, qw = pose
    covariance = [0.0] * 36
    for i in range(3):
        covariance[i * 7] = 1e-4
    sec, nanosec = divmod(stamp, 1_000_000_000)
    return Odometry(
        Header(Time(sec, nanosec), "vo"),
        "base_link",
        PoseWithCovariance(Pose(Point(x, y, z), Quaternion(qx, qy, qz, qw)), covariance),
        TwistWithCovariance(Twist(Vector3(0, 0, 0), Vector3(0, 0, 0)), [0.0] * 36),
    )


def main():
    domain, bag, topics_path, vo_path, out = sys.argv[1:6]
    topics = json.load(open(topics_path))
    vo = json.load(open(vo_path))
    camera = [topics["left_image"], topics["right_image"], topics["left_info"], topics["right_info"]]
    rank = {topics["imu"]: 0, topics["joints"]: 1}
    messages = []
    for m in read_ros2_messages(bag, topics=[topics["joints"], topics["imu"], *camera]):
        t = m.channel.topic
        if t in camera:
            part = camera.index(t)
            idl = image_idl(m.ros_msg) if part < 2 else info_idl(m.ros_msg)
            messages.append((stamp_ns(m.ros_msg.header), 2, part, idl))
        else:
            messages.append((stamp_ns(m.ros_msg.header), rank[t], -1, to_idl(m.ros_msg)))
    messages.sort(key=lambda t: (t[0], t[1], t[2]))

    dp = DomainParticipant(int(domain))
    xcdr1 = Policy.DataRepresentation(use_cdrv0_representation=True)
    sensors = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(100), xcdr1)
    reliable = Qos(
        Policy.Reliability.Reliable(duration(milliseconds=100)),
        Policy.History.KeepLast(1000),
        xcdr1,
    )
    ros = lambda t: "rt/" + t.lstrip("/")
    types = [Image, Image, CameraInfo, CameraInfo]
    joints_w = DataWriter(dp, Topic(dp, ros(topics["joints"]), JointState), qos=sensors)
    imu_w = DataWriter(dp, Topic(dp, ros(topics["imu"]), Imu), qos=sensors)
    camera_w = [DataWriter(dp, Topic(dp, ros(t), c), qos=sensors) for t, c in zip(camera, types)]
    vo_w = DataWriter(dp, Topic(dp, ros(topics["vo_odometry"]), Odometry), qos=reliable)
    odom_r = DataReader(dp, Topic(dp, "rt/odom/gp", Odometry), qos=reliable)
    decisions_r = DataReader(dp, Topic(dp, ros(topics["decisions"]), DiagnosticStatus), qos=reliable)
    gated_r = [DataReader(dp, Topic(dp, ros(t), c), qos=reliable) for t, c in zip(topics["gated"], types)]
    writers = [joints_w, imu_w, vo_w, *camera_w]
    readers = [odom_r, decisions_r, *gated_r]
    wait(
        lambda: all(w.get_matched_subscriptions() for w in writers)
        and all(r.get_matched_publications() for r in readers),
        60,
        "gpodo live's readers and writers",
    )
    # The node's best-effort readers drop samples of a writer they have not
    # discovered yet: give discovery time before the first sample.
    time.sleep(1.0)

    odometry_stamps, decisions, gated = set(), {}, [{} for _ in range(4)]

    def drain():
        for o in odom_r.take(N=1000):
            if isinstance(o, Odometry):
                odometry_stamps.add(stamp_ns(o.header))
        for d in decisions_r.take(N=100):
            if isinstance(d, DiagnosticStatus):
                values = {kv.key: kv.value for kv in d.values}
                sec, nsec = values["stamp"].split(".")
                decisions[int(sec) * 1_000_000_000 + int(nsec)] = values
        for k, r in enumerate(gated_r):
            for g in r.take(N=100):
                if isinstance(g, types[k]):
                    gated[k][stamp_ns(g.header)] = g

    def until(condition, what):
        end = time.time() + 20
        while not condition():
            if time.time() > end:
                sys.exit(f"ros2_gate_peer: timed out waiting for {what}")
            drain()
            time.sleep(0.0005)

    sent = {}
    answered, identical, different = 0, 0, 0
    for stamp, kind, part, message in messages:
        if kind == 0:
            imu_w.write(message)
        elif kind == 1:
            joints_w.write(message)
            until(lambda: stamp in odometry_stamps, f"the odometry of the joint state at {stamp}")
        else:
            camera_w[part].write(message)
            sent.setdefault(stamp, [None] * 4)[part] = message
            if any(m is None for m in sent[stamp]):
                continue
            until(lambda: stamp in decisions, f"the decision on the pair at {stamp}")
            if decisions[stamp]["decision"] != "processed":
                continue
            until(lambda: all(stamp in g for g in gated), f"the gated pair at {stamp}")
            for k in range(4):
                # The CDR bytes, as they went on the wire.
                if gated[k][stamp].serialize() == sent[stamp][k].serialize():
                    identical += 1
                else:
                    different += 1
                    print(f"part {k} at {stamp} differs: {gated[k][stamp]!r:.300}", file=sys.stderr)
            vo_w.write(odometry(stamp, vo[str(stamp)]))
            vo_w.wait_for_acks(duration(seconds=10))
            answered += 1
    with open(out, "w") as f:
        json.dump(
            {
                "pairs_sent": len(sent),
                "decisions": {str(k): v for k, v in decisions.items()},
                "gated_identical": identical,
                "gated_different": different,
                "vo_answers": answered,
            },
            f,
        )


if __name__ == "__main__":
    main()

"""The soak benchmark's ROS 2 peer on Cyclone DDS, without ROS: a robot
and the VO behind `gpodo live --gate`, for DURATION seconds.

It publishes, on the wall clock, joint states at 100 Hz (the joints of
one joint state of BAG, moving at that message's velocities), IMU
messages at 200 Hz and stereo pairs at 2.5 fps (512 x 384 mono8, with
their camera infos), best effort or reliable; it subscribes (reliable) to
the gated pairs, the decisions, `/odom/gp` and `/diagnostics`, and
answers each gated pair as the VO: a pose 5 % ahead of the wheels along
x. It writes to OUT.json what it sent and received: the pairs sent and
those that came back gated, the decisions and how many came after their
pair, the odometry's latency from sending a joint state to receiving its
`/odom/gp` (p50, p99), and the node's own latency p99 from each
`/diagnostics`.

    peer.py DOMAIN BAG TOPICS.json DURATION OUT.json best_effort|reliable
"""

import json
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "../../node/tests"))

from cyclonedds.core import Policy, Qos  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402
from mcap_ros2.reader import read_ros2_messages  # noqa: E402
from ros2_gate_peer import CameraInfo, Image, RegionOfInterest, odometry  # noqa: E402
from ros2_peer import (  # noqa: E402
    DiagnosticArray,
    DiagnosticStatus,
    Header,
    Imu,
    JointState,
    Odometry,
    Time,
    stamp_ns,
    to_idl,
    wait,
)


def header(ns, frame):
    sec, nanosec = divmod(ns, 1_000_000_000)
    return Header(Time(sec, nanosec), frame)


def percentile(values, p):
    if not values:
        return None
    s = sorted(values)
    k = max(1, min(len(s), int(-(-p * len(s) // 100))))
    return s[k - 1]


def main():
    domain, bag, topics_path, secs, out, camera_qos = sys.argv[1:7]
    topics = json.load(open(topics_path))
    duration_secs = float(secs)
    joint0 = imu0 = None
    for m in read_ros2_messages(bag, topics=[topics["joints"], topics["imu"]]):
        if m.channel.topic == topics["joints"] and joint0 is None:
            joint0 = to_idl(m.ros_msg)
        if m.channel.topic == topics["imu"] and imu0 is None:
            imu0 = to_idl(m.ros_msg)
        if joint0 and imu0:
            break

    # The joints move on at the recorded message's velocities.
    joint0_pos, joint0_vel = list(joint0.position), list(joint0.velocity)

    dp = DomainParticipant(int(domain))
    xcdr1 = Policy.DataRepresentation(use_cdrv0_representation=True)
    best_effort = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(100), xcdr1)
    reliable = Qos(
        Policy.Reliability.Reliable(duration(milliseconds=100)),
        Policy.History.KeepLast(100),
        xcdr1,
    )
    cameras = reliable if camera_qos == "reliable" else best_effort
    ros = lambda t: "rt/" + t.lstrip("/")
    types = [Image, Image, CameraInfo, CameraInfo]
    names = ["left_image", "right_image", "left_info", "right_info"]
    joints_w = DataWriter(dp, Topic(dp, ros(topics["joints"]), JointState), qos=best_effort)
    imu_w = DataWriter(dp, Topic(dp, ros(topics["imu"]), Imu), qos=best_effort)
    camera_w = [DataWriter(dp, Topic(dp, ros(topics[n]), c), qos=cameras) for n, c in zip(names, types)]
    vo_w = DataWriter(dp, Topic(dp, ros(topics["vo_odometry"]), Odometry), qos=reliable)
    odom_r = DataReader(dp, Topic(dp, "rt/odom/gp", Odometry), qos=reliable)
    diag_r = DataReader(dp, Topic(dp, "rt/diagnostics", DiagnosticArray), qos=reliable)
    decisions_r = DataReader(dp, Topic(dp, ros(topics["decisions"]), DiagnosticStatus), qos=reliable)
    gated_r = DataReader(dp, Topic(dp, ros(topics["gated"][0]), Image), qos=reliable)
    writers = [joints_w, imu_w, vo_w, *camera_w]
    readers = [odom_r, diag_r, decisions_r, gated_r]
    wait(
        lambda: all(w.get_matched_subscriptions() for w in writers)
        and all(r.get_matched_publications() for r in readers),
        60,
        "gpodo live's readers and writers",
    )
    time.sleep(1.0)

    width, height = 512, 384
    pixels = bytes((i * 7919) % 251 for i in range(width * height))
    k = [419.0, 0.0, 256.0, 0.0, 419.0, 192.0, 0.0, 0.0, 1.0]
    roi = RegionOfInterest(0, 0, 0, 0, False)

    def info(ns, frame, tx):
        p = [419.0, 0.0, 256.0, tx, 0.0, 419.0, 192.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        return CameraInfo(header(ns, frame), height, width, "plumb_bob", [0.0] * 5, k,
                          [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0], p, 0, 0, roi)

    sent_joints, odom_latency = {}, []
    pairs_sent, decisions, gated, diagnostics_p99 = {}, {}, {}, []
    answered = 0
    start_wall = time.time()
    start_ns = time.time_ns()
    due = {"joint": 0.0, "imu": 0.0, "pair": 0.0}
    period = {"joint": 0.01, "imu": 0.005, "pair": 0.4}
    speed = 0.05

    def drain():
        nonlocal answered
        now = time.time()
        for o in odom_r.take(N=1000):
            if isinstance(o, Odometry):
                sent = sent_joints.pop(stamp_ns(o.header), None)
                if sent is not None:
                    odom_latency.append(now - sent)
        for d in decisions_r.take(N=100):
            if isinstance(d, DiagnosticStatus):
                v = {kv.key: kv.value for kv in d.values}
                sec, nsec = v["stamp"].split(".")
                decisions[int(sec) * 1_000_000_000 + int(nsec)] = (now, v["decision"])
        for g in gated_r.take(N=100):
            if isinstance(g, Image):
                s = stamp_ns(g.header)
                gated[s] = now
                t = (s - start_ns) * 1e-9
                vo_w.write(odometry(s, [1.05 * speed * t, 0, 0, 0, 0, 0, 1]))
                answered += 1
        for a in diag_r.take(N=100):
            if isinstance(a, DiagnosticArray):
                for st in a.status:
                    for kv in st.values:
                        if kv.key == "latency p99 (ms)" and kv.value:
                            diagnostics_p99.append(float(kv.value))

    while True:
        elapsed = time.time() - start_wall
        if elapsed >= duration_secs:
            break
        stream = min(due, key=due.get)
        if due[stream] > elapsed:
            drain()
            time.sleep(max(0.0, min(due[stream] - (time.time() - start_wall), 0.002)))
            continue
        ns = start_ns + int(due[stream] * 1e9)
        t = due[stream]
        if stream == "joint":
            m = joint0
            m.header = header(ns, m.header.frame_id)
            m.position = [p + v * t for p, v in zip(joint0_pos, joint0_vel)]
            joints_w.write(m)
            sent_joints[ns] = time.time()
        elif stream == "imu":
            m = imu0
            m.header = header(ns, m.header.frame_id)
            imu_w.write(m)
        else:
            left = Image(header(ns, "left"), height, width, "mono8", 0, width, pixels)
            right = Image(header(ns, "right"), height, width, "mono8", 0, width, pixels)
            for w, msg in zip(camera_w, [left, right, info(ns, "left", 0.0), info(ns, "right", -50.0)]):
                w.write(msg)
            pairs_sent[ns] = time.time()
        due[stream] += period[stream]
    end = time.time() + 5
    while time.time() < end:
        drain()
        time.sleep(0.01)
    late = sum(1 for s, (at, d) in decisions.items() if d == "processed" and s in gated and at > gated[s])
    decided = set(decisions) & set(pairs_sent)
    forwarded = [s for s in decided if decisions[s][1] == "processed"]
    with open(out, "w") as f:
        json.dump(
            {
                "seconds": duration_secs,
                "camera_qos": camera_qos,
                "pairs_sent": len(pairs_sent),
                "pairs_decided": len(decided),
                "pairs_forwarded": len(forwarded),
                "forwarded_pairs_received": sum(1 for s in forwarded if s in gated),
                "decisions_after_their_pair": late,
                "vo_answers": answered,
                "odometry_received": len(odom_latency),
                "odometry_latency_ms": {
                    "p50": 1e3 * percentile(odom_latency, 50),
                    "p99": 1e3 * percentile(odom_latency, 99),
                },
                "node_latency_p99_ms": diagnostics_p99,
            },
            f,
        )


if __name__ == "__main__":
    main()

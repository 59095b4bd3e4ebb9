"""Decodes an MCAP written by `gpodo simulate --format mcap` with the ROS
ecosystem's own reader (`mcap-ros2-support`) and prints, as JSON, the
message count per topic and message 10 of each topic: the test compares
them with gpodo's rover-log CSV of the same run."""

import json
import sys

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

K = 10


def main(path):
    counts = {}
    out = {"counts": counts}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for schema, channel, message, msg in reader.iter_decoded_messages():
            k = counts.get(channel.topic, 0)
            counts[channel.topic] = k + 1
            if k != K:
                continue
            if channel.topic == "/joint_states":
                out["joint_states"] = {
                    "name": list(msg.name),
                    "position": list(msg.position),
                    "velocity": list(msg.velocity),
                }
            elif channel.topic == "/imu/data":
                stamp = msg.header.stamp
                out["imu"] = {
                    "stamp_ns": stamp.sec * 1_000_000_000 + stamp.nanosec,
                    "angular_velocity": [msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z],
                    "linear_acceleration": [msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z],
                }
            elif channel.topic == "/ground_truth/pose":
                p, q = msg.pose.position, msg.pose.orientation
                out["pose"] = {
                    "frame_id": msg.header.frame_id,
                    "position": [p.x, p.y, p.z],
                    "orientation": [q.x, q.y, q.z, q.w],
                }
            elif channel.topic == "/tf":
                t = msg.transforms[0]
                out["tf"] = {
                    "parent": t.header.frame_id,
                    "child": t.child_frame_id,
                    "translation": [t.transform.translation.x, t.transform.translation.y, t.transform.translation.z],
                }
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main(sys.argv[1])

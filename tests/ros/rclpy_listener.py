"""A real ROS 2 node (rclpy) that writes what it receives as JSON lines: run by test_ros_node.py.

Usage: python rclpy_listener.py NAMESPACE FIXTURE[,FIXTURE...] SECONDS OUT.jsonl STOP_FILE

Listens until STOP_FILE exists (at most SECONDS).

Subscribes to /NS/F/pose, /NS/F/joint_states and /diagnostics with the service's QoS, and
writes one line per message, then a line with the publishers' type hashes rclpy saw and its own.
"""

import json
import os
import socket
import sys
import time

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState


def stamp(h):
    return h.stamp.sec + h.stamp.nanosec * 1e-9


def only_loopback() -> None:
    """Refuse to start a node whose discovery multicast could leave this machine (not in the test's namespace)."""
    seen = sorted(name for _, name in socket.if_nameindex())
    if seen != ["hxnet0", "hxnet1", "lo"]:
        sys.exit(f"not started: the interfaces {seen} are not the test's network namespace's (tests/ros/netns.py)")


def main() -> None:
    ns, fixtures, seconds, out, stop = sys.argv[1], sys.argv[2].split(","), float(sys.argv[3]), sys.argv[4], sys.argv[5]
    only_loopback()
    rclpy.init()
    node = Node("hexapod_test_listener")
    qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
    lines = []

    def keep(kind, fixture, msg):
        if kind == "pose":
            p, o = msg.pose.position, msg.pose.orientation
            row = {"frame": msg.header.frame_id, "pose": [p.x, p.y, p.z, o.x, o.y, o.z, o.w]}
        elif kind == "joints":
            row = {"name": list(msg.name), "position": list(msg.position)}
        else:
            row = {
                "status": [
                    {
                        "level": int.from_bytes(s.level, "little") if isinstance(s.level, bytes) else int(s.level),
                        "name": s.name,
                        "values": {kv.key: kv.value for kv in s.values},
                    }
                    for s in msg.status
                ]
            }
        lines.append(
            {
                "kind": kind,
                "fixture": fixture,
                "t": stamp(msg.header),
                "sec": msg.header.stamp.sec,
                "nanosec": msg.header.stamp.nanosec,
                **row,
            }
        )

    for f in fixtures:
        node.create_subscription(PoseStamped, f"/{ns}/{f}/pose", lambda m, f=f: keep("pose", f, m), qos)
        node.create_subscription(JointState, f"/{ns}/{f}/joint_states", lambda m, f=f: keep("joints", f, m), qos)
    node.create_subscription(DiagnosticArray, "/diagnostics", lambda m: keep("diagnostics", None, m), qos)
    hashes = {}
    end = time.monotonic() + seconds
    print("listening", flush=True)
    while time.monotonic() < end and not os.path.exists(stop):
        rclpy.spin_once(node, timeout_sec=0.05)
        if not hashes:
            topic = f"/{ns}/{fixtures[0]}/pose"
            pubs = node.get_publishers_info_by_topic(topic)
            subs = node.get_subscriptions_info_by_topic(topic)
            if pubs and subs:
                hashes = {
                    "publisher": str(pubs[0].topic_type_hash),
                    "own": str(subs[0].topic_type_hash),
                    "type": pubs[0].topic_type,
                }
    lines.append({"kind": "hashes", **hashes})
    with open(out, "w") as fh:
        fh.write("".join(json.dumps(x) + "\n" for x in lines))
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()

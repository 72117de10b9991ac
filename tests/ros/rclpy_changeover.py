"""A real ROS 2 node (rclpy) on the changeover topics: run by test_ros_changeover.py.

Usage: python rclpy_changeover.py NAMESPACE FIXTURE REQUESTS.json OUT.json SECONDS

Publishes a probe (a malformed request) on /NS/target every 0.5 s until its result is heard on
/NS/target_result, so that both ways are matched at both ends (a DDS match can be seen by one side
before the other, and a volatile result written before it is lost); then publishes each ``data`` of
REQUESTS.json (a list of strings), one every 0.3 s, and writes to OUT.json the results of these
requests and the guidance messages of /NS/FIXTURE/guidance it received (JSON texts decoded), within
SECONDS.
"""

import json
import socket
import sys
import time

import rclpy
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import String


def only_loopback() -> None:
    """Refuse to start a node whose discovery multicast could leave this machine (not in the test's namespace)."""
    seen = sorted(name for _, name in socket.if_nameindex())
    if seen != ["hxnet0", "hxnet1", "lo"]:
        sys.exit(f"not started: the interfaces {seen} are not the test's network namespace's (tests/ros/netns.py)")


def main() -> None:
    ns, fixture, requests, out, seconds = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], float(sys.argv[5])
    todo = json.loads(open(requests).read())
    only_loopback()
    rclpy.init()
    node = Node("hexapod_test_changeover")
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    results, guidance, probes = [], [], []

    def heard(msg: String) -> None:
        result = json.loads(msg.data)
        (probes if result.get("fixture") is None else results).append(result)

    node.create_subscription(String, f"/{ns}/target_result", heard, qos)
    node.create_subscription(String, f"/{ns}/{fixture}/guidance", lambda m: guidance.append(json.loads(m.data)), qos)
    pub = node.create_publisher(String, f"/{ns}/target", qos)
    end = time.monotonic() + seconds
    sent, next_send = 0, time.monotonic()
    while time.monotonic() < end and (len(results) < len(todo) or len(guidance) < 3):
        rclpy.spin_once(node, timeout_sec=0.05)
        if time.monotonic() < next_send:
            continue
        if not probes:
            pub.publish(String(data="probe"))  # not JSON: answered "malformed target request", fixture null
            next_send = time.monotonic() + 0.5
        elif sent < len(todo):
            pub.publish(String(data=todo[sent]))
            sent, next_send = sent + 1, time.monotonic() + 0.3
    with open(out, "w") as fh:
        json.dump({"results": results, "probes": probes, "guidance": guidance[-3:]}, fh)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()

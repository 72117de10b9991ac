"""A real ROS 2 node (rclpy) on the changeover topics: run by test_ros_changeover.py.

Usage: python rclpy_changeover.py NAMESPACE FIXTURE REQUESTS.json OUT.json SECONDS

Publishes each ``data`` of REQUESTS.json (a list of strings) on /NS/target once the service's
reader is matched, one every 0.3 s, and writes to OUT.json the target results and the guidance
messages of /NS/FIXTURE/guidance it received (JSON texts decoded), within SECONDS.
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
    results, guidance = [], []
    answers = node.create_subscription(
        String, f"/{ns}/target_result", lambda m: results.append(json.loads(m.data)), qos
    )
    # the service's result writer matched to this reader (not only seen in the graph): a result
    # written before the match would be lost (volatile durability)
    matched = getattr(answers, "get_publisher_count", lambda: 1)
    node.create_subscription(String, f"/{ns}/{fixture}/guidance", lambda m: guidance.append(json.loads(m.data)), qos)
    pub = node.create_publisher(String, f"/{ns}/target", qos)
    end = time.monotonic() + seconds
    sent, next_send = 0, None
    while time.monotonic() < end and (len(results) < len(todo) or len(guidance) < 3):
        rclpy.spin_once(node, timeout_sec=0.05)
        if (
            next_send is None
            and pub.get_subscription_count() > 0
            and node.count_publishers(f"/{ns}/target_result")
            and matched() > 0
        ):
            next_send = time.monotonic() + 1.0  # both ways matched: the service's result writer hears this node too
        if sent < len(todo) and next_send is not None and time.monotonic() >= next_send:
            pub.publish(String(data=todo[sent]))
            sent, next_send = sent + 1, time.monotonic() + 0.3
    with open(out, "w") as fh:
        json.dump({"results": results, "guidance": guidance[-3:]}, fh)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()

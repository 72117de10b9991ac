"""Print the poses the service publishes on ROS 2: ``ros2 topic echo`` for a PyPI-only ROS 2 node.

Usage::

    pip install "ros-jazzy-rclpy[fastrtps]" ros-jazzy-geometry-msgs   # unofficial ROS 2 Jazzy wheels
    python ros2_echo.py /hexapod/right/pose [--count N]

One line per message: the stamp (s), the frame, x y z (m) and qx qy qz qw. No environment
variable is needed on the machine that runs ``hexapod serve`` (``ROS_DOMAIN_ID`` when the
``[ros] domain_id`` is not 0). Stops after ``--count`` messages (default: Ctrl-C).
"""

import argparse

import rclpy
from geometry_msgs.msg import PoseStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy


def main() -> None:
    """Subscribe to the topic with the service's QoS and print each pose."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("topic", help="a pose topic, e.g. /hexapod/right/pose")
    parser.add_argument("--count", type=int, default=0, help="stop after this many messages (0: never)")
    args = parser.parse_args()
    rclpy.init()
    node = Node("hexapod_echo")
    seen = 0

    def show(msg: PoseStamped) -> None:
        nonlocal seen
        p, q = msg.pose.position, msg.pose.orientation
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        numbers = " ".join(f"{v:.6f}" for v in (p.x, p.y, p.z, q.x, q.y, q.z, q.w))
        print(f"{stamp:.6f} {msg.header.frame_id} {numbers}", flush=True)
        seen += 1

    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)  # the service's: reliable, keep last 10
    node.create_subscription(PoseStamped, args.topic, show, qos)
    try:
        while rclpy.ok() and (args.count == 0 or seen < args.count):
            rclpy.spin_once(node, timeout_sec=0.1)
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()

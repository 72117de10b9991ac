"""Skips of the ``ros`` tests, each with the reason: the ros extra or the rclpy wheels are missing."""

from __future__ import annotations

import functools
import importlib.util
import os
import subprocess
import sys

import pytest

EXTRA = ("cyclonedds", "rosbags", "mcap")
RCLPY = ("rclpy", "geometry_msgs", "sensor_msgs", "diagnostic_msgs")


def missing(modules: tuple[str, ...]) -> list[str]:
    return [m for m in modules if importlib.util.find_spec(m) is None]


def need_extra() -> None:
    absent = missing(EXTRA)
    if absent:
        pytest.skip(f"{', '.join(absent)} not installed: pip install 'hexapod_model[ros]'")


@functools.cache
def rclpy_problem() -> str | None:
    """Why a ROS 2 node cannot run here (None when it can): missing wheels or an rclpy that does not start."""
    absent = missing(RCLPY)
    if absent:
        return (
            f"{', '.join(absent)} not installed: pip install 'ros-jazzy-rclpy[fastrtps]' ros-jazzy-geometry-msgs "
            "ros-jazzy-sensor-msgs ros-jazzy-diagnostic-msgs (unofficial ROS 2 Jazzy wheels)"
        )
    probe = "import rclpy, geometry_msgs.msg, sensor_msgs.msg, diagnostic_msgs.msg; rclpy.init(); rclpy.shutdown()"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        return f"the installed rclpy does not start: {last}"
    return None


def need_rclpy() -> None:
    need_extra()
    problem = rclpy_problem()
    if problem is not None:
        pytest.skip(problem)


def run_domain() -> int:
    """A ROS 2 domain of this test run (1-200): another run's or a cell's traffic on domain 0 stays apart."""
    return 1 + os.getpid() % 200

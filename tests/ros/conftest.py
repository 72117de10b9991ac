"""Skips of the ``ros`` tests, each with the reason: the ros extra or the rclpy wheels are missing."""

from __future__ import annotations

import importlib.util

import pytest

EXTRA = ("cyclonedds", "rosbags", "mcap")
RCLPY = ("rclpy", "geometry_msgs", "sensor_msgs", "diagnostic_msgs")


def missing(modules: tuple[str, ...]) -> list[str]:
    return [m for m in modules if importlib.util.find_spec(m) is None]


def need_extra() -> None:
    absent = missing(EXTRA)
    if absent:
        pytest.skip(f"{', '.join(absent)} not installed: pip install 'hexapod_model[ros]'")


def need_rclpy() -> None:
    need_extra()
    absent = missing(RCLPY)
    if absent:
        pytest.skip(
            f"{', '.join(absent)} not installed: pip install 'ros-jazzy-rclpy[fastrtps]' ros-jazzy-geometry-msgs "
            "ros-jazzy-sensor-msgs ros-jazzy-diagnostic-msgs (unofficial ROS 2 Jazzy wheels)"
        )

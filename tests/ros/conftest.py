"""Skips of the ``ros`` tests, each with the reason: the ros extra or the rclpy wheels are missing.

A test marked ``netns`` (it starts a stock ROS 2 node) runs in a network namespace of its own
(:mod:`tests.ros.netns`); :func:`need_rclpy` fails anywhere else.
"""

from __future__ import annotations

import functools
import importlib.util
import os
import subprocess
import sys

import pytest

from . import netns

EXTRA = ("cyclonedds", "rosbags", "mcap")
RCLPY = ("rclpy", "geometry_msgs", "sensor_msgs", "diagnostic_msgs")


def missing(modules: tuple[str, ...]) -> list[str]:
    return [m for m in modules if importlib.util.find_spec(m) is None]


def need_extra() -> None:
    absent = missing(EXTRA)
    if absent:
        pytest.skip(f"{', '.join(absent)} not installed: pip install 'hexapod_model[ros]'")


def wheels_missing() -> str | None:
    """Which ROS 2 wheels are not installed, with the command that installs them (None: all are)."""
    absent = missing(RCLPY)
    if not absent:
        return None
    return (
        f"{', '.join(absent)} not installed: pip install 'ros-jazzy-rclpy[fastrtps]' ros-jazzy-geometry-msgs "
        "ros-jazzy-sensor-msgs ros-jazzy-diagnostic-msgs (unofficial ROS 2 Jazzy wheels)"
    )


@functools.cache
def rclpy_problem() -> str | None:
    """Why a ROS 2 node cannot run here (None when it can): missing wheels or an rclpy that does not start."""
    absent = wheels_missing()
    if absent is not None:
        return absent
    probe = "import rclpy, geometry_msgs.msg, sensor_msgs.msg, diagnostic_msgs.msg; rclpy.init(); rclpy.shutdown()"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        return f"the installed rclpy does not start: {last}"
    return None


def need_rclpy() -> None:
    """Skip without the ros extra or a working rclpy; fail outside the test's network namespace."""
    netns.check_inside()
    need_extra()
    problem = rclpy_problem()
    if problem is not None:
        pytest.skip(problem)


def run_domain() -> int:
    """A ROS 2 domain of this test run (1-200): another run's or a cell's traffic on domain 0 stays apart."""
    return 1 + os.getpid() % 200


@pytest.hookimpl(tryfirst=True)
def pytest_pyfunc_call(pyfuncitem: pytest.Function) -> bool | None:
    """A test marked ``netns`` runs in a child pytest in a network namespace of its own (:mod:`tests.ros.netns`)."""
    if pyfuncitem.get_closest_marker("netns") is None:
        return None
    if netns.inside():
        netns.check_inside()
        return None  # the test body runs here, in the namespace
    need_extra()  # the cheap skips first: no child run for a test that would skip
    absent = wheels_missing()
    if absent is not None:
        pytest.skip(absent)
    netns.run_in_netns(pyfuncitem)
    return True

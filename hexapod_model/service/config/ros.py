"""The optional ``[ros]`` table of ``fixture.toml``: ROS 2 topics over DDS (``hexapod_model.ros``).

A ``[ros]`` table turns publishing on (``enabled = false`` keeps the table but publishes
nothing). Discovery stays on this machine unless told otherwise: DDS uses the interface
``interface`` (default the loopback, ``127.0.0.1``), never multicast, and finds other
participants by unicast at ``peers`` (default ``["127.0.0.1"]``). For a cell network give the
address of this computer's cell interface and the cell computers' addresses. Format and the
published topics: ``docs/ros2.md``.
"""

from __future__ import annotations

import ipaddress
import re
from dataclasses import dataclass

from .table import Table

NAMESPACE_PATTERN = re.compile(r"^[A-Za-z][A-Za-z0-9_]*(/[A-Za-z][A-Za-z0-9_]*)*$")  # a ROS 2 name, no leading /
FRAME_PATTERN = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_/.-]*$")


@dataclass(frozen=True)
class RosConfig:
    """Publishing the service's records as ROS 2 topics.

    Attributes:
        enabled: publish (a ``[ros]`` table without ``enabled`` publishes).
        namespace: topics are ``/<namespace>/<fixture>/pose`` etc. (ROS 2 name, no leading ``/``).
        domain_id: the ROS 2 domain (``ROS_DOMAIN_ID``), 0-232.
        interface: IPv4 address of the network interface DDS uses (``127.0.0.1``: this machine only).
        peers: addresses DDS discovery contacts by unicast (no multicast is ever sent).
        diagnostics_period: s between two ``/diagnostics`` messages of an unchanged fixture (a
            change of status or flags is published at once).
        robot_frame: parent frame of a fixture's placement on ``/tf_static`` (when the fixture's
            cell placement is configured).
    """

    enabled: bool = True
    namespace: str = "hexapod"
    domain_id: int = 0
    interface: str = "127.0.0.1"
    peers: tuple[str, ...] = ("127.0.0.1",)
    diagnostics_period: float = 1.0
    robot_frame: str = "base_link"


def ros_config(t: Table) -> RosConfig:
    """Validate a ``[ros]`` table (:class:`~hexapod_model.service.errors.ConfigError` names the bad field)."""
    namespace = t.text("namespace", "hexapod").strip("/")
    if not NAMESPACE_PATTERN.match(namespace):
        raise t.error("namespace", namespace, "expected a ROS 2 name: letters, digits, '_' and '/' between words")
    interface = _address(t, "interface", t.take("interface", "127.0.0.1"))
    peers = t.take("peers", ["127.0.0.1"])
    if not isinstance(peers, list) or not peers:
        raise t.error("peers", peers, "expected a list of one or more IPv4 addresses")
    robot_frame = t.text("robot_frame", "base_link")
    if not FRAME_PATTERN.match(robot_frame):
        raise t.error("robot_frame", robot_frame, "expected a tf frame name (letters, digits, '_', '/', '.', '-')")
    cfg = RosConfig(
        enabled=t.boolean("enabled", True),
        namespace=namespace,
        domain_id=t.integer("domain_id", 0, 0, 232),
        interface=interface,
        peers=tuple(_address(t, f"peers[{k}]", p) for k, p in enumerate(peers)),
        diagnostics_period=t.number("diagnostics_period", 1.0, 0.01, 3600.0),
        robot_frame=robot_frame,
    )
    t.finish()
    return cfg


def _address(t: Table, key: str, value: object) -> str:
    try:
        return str(ipaddress.IPv4Address(value))
    except (ipaddress.AddressValueError, ValueError, TypeError):
        raise t.error(key, value, "expected an IPv4 address such as 127.0.0.1") from None

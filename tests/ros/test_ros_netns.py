"""The network namespace of the tests that start a stock ROS 2 node: no interface of this machine.

Whatever a process sends there (a stock node's SPDP multicast to 239.255.0.1 included) stays in the
namespace: its interfaces are loopback and a veth pair of its own, its only addresses loopback's,
a documentation address (TEST-NET-1) and link-local ones, and its default route is the veth card.
"""

from __future__ import annotations

import ipaddress
import subprocess
import sys
from pathlib import Path

import pytest

from . import netns

pytestmark = pytest.mark.ros


def in_namespace(*argv: str) -> str:
    problem = netns.netns_problem()
    if problem is not None:
        pytest.skip(problem)
    done = subprocess.run(netns.in_netns(list(argv)), capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_the_namespace_has_only_loopback_and_its_own_veth_pair():
    links = sorted(line.split(":")[1].strip().split("@")[0] for line in in_namespace("ip", "-o", "link").splitlines())
    assert links == netns.INTERFACES
    assert not any(name.startswith(("eth", "en", "wl")) for name in links)
    flags = in_namespace("ip", "-o", "link", "show", netns.CARD).split("<")[1].split(">")[0].split(",")
    assert {"UP", "MULTICAST"} <= set(flags)


def test_every_address_is_loopback_documentation_or_link_local():
    found = [ipaddress.ip_interface(line.split()[3]) for line in in_namespace("ip", "-o", "addr").splitlines()]
    assert ipaddress.ip_interface(netns.ADDRESS) in found
    for a in found:
        assert a.ip.is_loopback or a.ip.is_link_local or a.network == ipaddress.ip_network("192.0.2.0/24"), a


def test_multicast_and_the_default_route_go_to_the_namespaces_card():
    assert f"default dev {netns.CARD}" in in_namespace("ip", "route", "show")
    assert f"239.255.0.1 dev {netns.CARD}" in in_namespace("ip", "route", "get", "239.255.0.1")


def test_a_process_in_the_namespace_sees_only_its_interfaces():
    seen = in_namespace(sys.executable, "-c", "import socket; print(sorted(n for _, n in socket.if_nameindex()))")
    assert seen.strip() == str(netns.INTERFACES)


def test_need_rclpy_fails_outside_the_namespace(monkeypatch):
    from .conftest import need_rclpy

    monkeypatch.delenv(netns.INSIDE, raising=False)
    with pytest.raises(pytest.fail.Exception, match="mark the test netns"):
        need_rclpy()


def test_every_test_module_that_names_rclpy_is_marked_netns():
    tests = Path(__file__).resolve().parents[1]
    named = [p for p in tests.rglob("test_*.py") if "rclpy" in p.read_text() and p != Path(__file__).resolve()]
    assert named  # the stock node's tests are found
    unmarked = [str(p.relative_to(tests)) for p in named if "pytest.mark.netns" not in p.read_text()]
    assert not unmarked, f"{unmarked} name rclpy but do not run in a network namespace (pytest.mark.netns)"

"""A network namespace of the test run's own, for the tests that start a stock ROS 2 node.

A stock ROS 2 Jazzy node (rclpy, Fast DDS, no discovery setting) announces itself by multicast on
every network interface it sees. A test marked ``netns`` therefore runs its body, in a child
``pytest`` of its one test, inside a network namespace that ``unshare --net`` makes for it (as
root; otherwise with ``--map-root-user``, in a user namespace). The namespace looks like a machine
on a network, and is none: loopback, and a network card that is one end of a veth pair whose other
end is in the namespace too, with a documentation address (192.0.2.1/24) and the default route.
The node sends its multicast there and announces that address, as it would on a cell computer's
Ethernet; nothing reaches this machine's real interfaces. The service (or DDS writer) and the node
both run inside: the test body starts them.

Without ``unshare`` or ``ip`` (iproute2), or where the kernel refuses the namespace, the test
skips with the reason.
"""

from __future__ import annotations

import functools
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

#: set to "1" in the environment of the processes in the namespace
INSIDE = "HEXAPOD_TEST_NETNS"
#: the namespace's network card: one end of a veth pair whose other end is in the namespace too
CARD, PEER = "hxnet0", "hxnet1"
#: its address (TEST-NET-1, RFC 5737: documentation only, routed nowhere)
ADDRESS = "192.0.2.1/24"
#: loopback, and a network card with an address and the default route (a stock node's multicast goes there)
SETUP = " && ".join(
    [
        "ip link set lo up",
        f"ip link add {CARD} type veth peer name {PEER}",
        f"ip addr add {ADDRESS} dev {CARD}",
        f"ip link set {PEER} up",
        f"ip link set {CARD} up",
        f"ip route add default dev {CARD}",
    ]
)
#: the interfaces of the namespace, sorted
INTERFACES = sorted(["lo", CARD, PEER])
TIMEOUT = 1800.0  # s for a child run (the served poses wait for the solver's kernels to compile)


def unshare_command() -> list[str]:
    """The ``unshare`` command line of a new network namespace (a user namespace too when not root)."""
    user = [] if os.geteuid() == 0 else ["--map-root-user"]
    return ["unshare", "--net", *user]


def in_netns(argv: list[str]) -> list[str]:
    """``argv`` run in a new network namespace with loopback and the veth pair of :data:`SETUP` only."""
    return [*unshare_command(), "--", "sh", "-c", SETUP + ' && exec "$@"', "netns", *argv]


@functools.cache
def netns_problem() -> str | None:
    """Why no network namespace can be made here (None when it can)."""
    absent = [tool for tool in ("unshare", "ip") if shutil.which(tool) is None]
    if absent:
        return f"{' and '.join(absent)} not found (util-linux, iproute2): no network namespace for a stock ROS 2 node"
    done = subprocess.run(in_netns(["true"]), capture_output=True, text=True, timeout=60)
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        return f"cannot make a network namespace for a stock ROS 2 node ({' '.join(unshare_command())}): {last}"
    return None


def interfaces() -> list[str]:
    """The names of the network interfaces this process sees (its network namespace's)."""
    return sorted(name for _, name in socket.if_nameindex())


def inside() -> bool:
    """Whether this process runs in a namespace made by :func:`run_in_netns`."""
    return os.environ.get(INSIDE) == "1"


def check_inside() -> None:
    """Fail unless this process is in a namespace of the test run, with no interface but :data:`INTERFACES`."""
    if not inside():
        pytest.fail(
            "a stock ROS 2 node sends multicast on every interface: mark the test netns (tests/ros/netns.py)",
            pytrace=False,
        )
    seen = interfaces()
    if seen != INTERFACES:
        pytest.fail(f"the test's network namespace has the interfaces {seen}, not {INTERFACES}", pytrace=False)


def run_in_netns(item: pytest.Item) -> None:
    """Run the test ``item`` in a child ``pytest`` in a new network namespace: pass, skip or fail as it does."""
    problem = netns_problem()
    if problem is not None:
        pytest.skip(problem)
    env = {**os.environ, INSIDE: "1"}
    env.pop("PYTEST_ADDOPTS", None)  # the child's options are these; coverage is the outer run's
    with tempfile.TemporaryDirectory(prefix="hexapod_netns_") as tmp:
        report = Path(tmp) / "report.xml"
        argv = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"--basetemp={tmp}/basetemp"]
        argv += [f"--junitxml={report}", item.nodeid]
        done = subprocess.run(
            in_netns(argv), cwd=item.config.rootpath, env=env, capture_output=True, text=True, timeout=TIMEOUT
        )
        cases = ET.parse(report).getroot().iter("testcase") if report.exists() else iter(())
        outcomes = [child for case in cases for child in case if child.tag in ("skipped", "failure", "error")]
    if done.returncode == 0 and not outcomes:
        return
    skipped = [o for o in outcomes if o.tag == "skipped"]
    if done.returncode == 0 and skipped and len(skipped) == len(outcomes):
        pytest.skip(skipped[0].get("message", "skipped in the network namespace"))
    pytest.fail(f"in the network namespace (exit status {done.returncode}):\n{done.stdout[-6000:]}", pytrace=False)

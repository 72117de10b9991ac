"""Shared by the service tests: configurations, a bus that only collects, driving a cycle by hand."""

from __future__ import annotations

import functools
import time
import uuid
from pathlib import Path

import can
import numpy as np
import pinocchio as pin

from hexapod_model.service import (
    FixtureCycle,
    FixtureService,
    PoseRecord,
    Simulator,
    config_from_dict,
    geometry_hash,
    simulation_from_dict,
)

from ..conftest import hexapod

IDS = [[0x181 + k for k in range(6)], [0x191 + k for k in range(6)]]


@functools.cache
def kernels_ready(preset: str = "reference", noise: float = 1e-5) -> None:
    """Load (or compile) the kernels a served set runs, before a test runs ``hexapod serve``; once per process.

    ``--duration`` counts from the command's start, the service's warm-up of its kernels
    included: where numba has them in no cache yet (a new checkout, an edited compiled module),
    compiling them takes the whole run, and a test that expects records from a few seconds of
    serving would find none. Loaded here first, the run serves for its whole duration. Compiled
    here, they are in numba's cache next to the package before a ``hexapod serve`` subprocess
    starts: it loads them, instead of compiling them against its bounded wait for ``ready``
    while another test process may be compiling the same ones.
    """
    from hexapod_model.service.cycle.solver import warm_up

    warm_up(hexapod(preset), noise)


def fixture_table(name: str = "left", index: int = 0, **extra) -> dict:
    return {"name": name, "hexapod": "reference", "can_ids": IDS[index], **extra}


def service_config(tmp_path: Path, fixtures: list[dict] | None = None, channel: str | None = None, **top):
    data = {
        "bus": {"interface": "virtual", "channel": channel or f"test-{uuid.uuid4().hex}"},
        "store": {"path": str(tmp_path / "store.sqlite")},
        "http": {"host": "127.0.0.1", "port": 0},
        "fixtures": fixtures or [fixture_table()],
        **top,
    }
    return config_from_dict(data, "test.toml", tmp_path)


def sim_config(service, fixtures: list[dict], seed: int = 3):
    return simulation_from_dict({"seed": seed, "fixtures": fixtures}, service)


def served(config, bus, seconds: float, during=None) -> tuple[list[PoseRecord], object]:
    """The records of a service (reference hexapod, no HTTP) reading ``bus`` for ``seconds``, and ``during()``'s
    answer (called before the service stops)."""
    records: list[PoseRecord] = []
    service = FixtureService(config, bus=bus, hexapods={"left": hexapod("reference")}, http=False)
    service.subscribe(records.append)
    try:
        service.start()
        time.sleep(seconds)
        answer = during(service) if during is not None else service
    finally:
        service.stop()
    return records, answer


class CollectingBus:
    """Stands in for a python-can bus in the simulator: keeps what is sent."""

    def __init__(self):
        self.sent: list[can.Message] = []

    def send(self, msg: can.Message, timeout=None) -> None:
        self.sent.append(msg)


def drive(service, sim, seconds: float, recovered=None, t0: float = 1.0e9, cycle=None):
    """Feed ``seconds`` of simulated sets of the first simulated fixture into its cycle, by hand.

    Frames get their stamps (``t0 + t_sim`` plus the frame spacing) as receipt time. Returns the cycle, the
    records published (with the simulated set each belongs to) and the simulator's truth.
    """
    fixture = sim.fixtures[0]
    cfg = service.fixture(fixture.name)
    hexa = hexapod("reference")
    if cycle is None:
        cycle = FixtureCycle(cfg, hexa, geometry_hash(hexa), recovered, t0)
    bus = CollectingBus()
    simulator = Simulator(service, sim, bus, hexapods={fixture.name: hexa})  # type: ignore[arg-type]
    leg_of = {leg.can_id: k for k, leg in enumerate(cfg.legs)}
    out = []
    n = int(round(seconds * fixture.rate))
    for k in range(n):
        t_sim = k / fixture.rate
        bus.sent.clear()
        sent = simulator.send_set(0, t_sim, stamp=t0 + t_sim, stall_check=False)
        for msg in bus.sent:  # received at the sampling time of its set (a late frame keeps its own)
            rec = cycle.on_frame(leg_of[msg.arbitration_id], msg.data, msg.timestamp)
            if rec is not None:
                out.append((sent, rec))
        if cycle.pending_lock is not None:  # the store's part: committed at once
            episode, event = cycle.pending_lock
            cycle.pending_lock = None
            cycle.lock_stored(episode, event)
    return cycle, out


def pose_error(rec: dict, truth: np.ndarray) -> tuple[float, float]:
    """Position (m) and rotation (rad) error of a record's pose against a 4x4 truth."""
    p = rec.pose
    R = pin.Quaternion(p["qw"], p["qx"], p["qy"], p["qz"]).toRotationMatrix()
    dp = float(np.linalg.norm(np.array([p["x"], p["y"], p["z"]]) - truth[:3, 3]))
    return dp, float(np.linalg.norm(pin.log3(truth[:3, :3].T @ R)))


def stored_locks(records, fixture: str = "left") -> set[float]:
    """``t`` of the first record of each lock of ``fixture`` that some record published as stored."""
    out, prev, first = set(), None, None
    records = [PoseRecord.from_dict(r) if isinstance(r, dict) else r for r in list(records)]  # JSON lines too
    for r in [r for r in records if r.fixture == fixture]:
        if r.state == "locked" and prev != "locked":
            first = r.t
        if r.state == "locked" and r.stored:
            out.add(first)
        prev = r.state
    return out


def record_pose(rec) -> np.ndarray | None:
    """The 4x4 pose of a record, or of a JSON object with a ``pose`` (guidance, ``pose_in_robot``); None without one."""
    p = rec.pose if isinstance(rec, PoseRecord) else rec.get("pose")
    if p is None:
        return None
    T = np.eye(4)
    T[:3, :3] = pin.Quaternion(p["qw"], p["qx"], p["qy"], p["qz"]).normalized().toRotationMatrix()
    T[:3, 3] = [p["x"], p["y"], p["z"]]
    return T

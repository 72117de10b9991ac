"""Which handler reads a frame: the service's table from (extended flag, CAN id) to a fixture's cycle.

A leg's frames (and an inclinometer's) go to its cycle's
:meth:`~hexapod_model.service.cycle.fixture_cycle.FixtureCycle.on_frame`; a CANopen fixture's
TPDOs, EMCYs and heartbeats to its :class:`~hexapod_model.service.cycle.canopen_link.CanopenLink`,
and the bus's SYNC to the one :class:`~hexapod_model.service.cycle.canopen_link.SyncClock` of
its COB-ID. One dictionary look-up a frame, no key tuple built.
"""

from __future__ import annotations

from collections.abc import Callable

from ..config.settings import ServiceConfig
from ..record.pose_record import PoseRecord
from .canopen_link import CanopenLink, SyncClock
from .fixture_cycle import FixtureCycle

Handler = Callable[[int, bytes | bytearray, float], PoseRecord | None]
FrameRoute = tuple[FixtureCycle, Handler, int]  # the cycle a record is published for, the handler, the leg


def frame_routes(config: ServiceConfig, cycles: dict[str, FixtureCycle]) -> dict[bool, dict[int, FrameRoute]]:
    """``{extended: {can_id: (cycle, handler, leg)}}`` of every fixture of ``config``."""
    routes: dict[bool, dict[int, FrameRoute]] = {False: {}, True: {}}
    clocks: dict[int, SyncClock] = {}
    for f in config.fixtures:
        cycle = cycles[f.name]
        if f.canopen is None:
            for k, leg in enumerate(f.legs):
                routes[leg.extended_id][leg.can_id] = (cycle, cycle.on_frame, k)
            if f.inclinometer is not None:  # its frame follows the legs'
                tilt = f.inclinometer
                routes[tilt.extended_id][tilt.can_id] = (cycle, cycle.on_frame, len(f.legs))
            continue
        clock = clocks.setdefault(f.canopen.sync_id, SyncClock())
        routes[False][f.canopen.sync_id] = (cycle, clock.on_sync, 0)
        link = CanopenLink(f.name, f.canopen, cycle.on_frame, clock, f.staleness)
        for can_id, handler, k in link.routes([leg.can_id for leg in f.legs]):
            routes[False][can_id] = (cycle, handler, k)
    return routes

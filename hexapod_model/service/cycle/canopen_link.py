"""CANopen encoders between the bus and a fixture's cycle: SYNC stamps, EMCY errors, heartbeat loss.

A fixture with ``protocol = "canopen"`` (:mod:`~hexapod_model.service.config.fieldbus`) sends
its positions in TPDO1 after each SYNC. :class:`CanopenLink` stands between the bus and the
fixture's :meth:`~hexapod_model.service.cycle.fixture_cycle.FixtureCycle.on_frame`:

* **SYNC** (shared by the bus's CANopen fixtures, :class:`SyncClock`): a TPDO received within
  ``staleness`` of the latest SYNC is stamped with that SYNC's time, so the six frames of one
  instant carry one stamp (the sampling instant, not the arrival order). A SYNC with a counter
  byte (CiA 301, ``0x1019`` of the SYNC producer) has it appended to each TPDO that follows it
  (0 without one): a set whose frames follow different SYNCs is ``sync_mismatch``
  (:mod:`~hexapod_model.service.cycle.frame_checks`), never a pose. A TPDO received more than
  ``staleness`` after the latest SYNC is not used (its instant is unknown: stamped with its own
  receipt time it could join the next SYNC's set); its leg is then missing from its set. Before
  any SYNC was heard TPDOs are stamped with their receipt time (encoders sending on their own
  timer).
* **EMCY** (``0x80`` + node id): an emergency with a non-zero error code marks the leg's
  readings ``encoder_error`` (the status byte the link appends to each TPDO: the layout's error
  bit) until the node's error-reset EMCY (code ``0x0000``); both are logged.
* **heartbeat** (``0x700`` + node id, every ``0x1017`` ms): a leg whose heartbeat is later than
  1.5 periods, or whose NMT state is not *operational*, has its TPDOs dropped: the cycle then
  reports it ``silent_leg``. Without a producer heartbeat time in the EDS nothing is watched.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable

import can

from ..config.fieldbus import CanopenEncoders
from ..record.pose_record import PoseRecord

log = logging.getLogger(__name__)
OPERATIONAL = 0x05  # NMT state in a heartbeat
LATE = 1.5  # heartbeat periods after which a node counts as lost

OnFrame = Callable[[int, bytes | bytearray, float], PoseRecord | None]
Route = tuple[int, OnFrame, int]  # CAN id, handler, leg


class SyncClock:
    """The time (s, bus clock) and the tag of the latest SYNC on the bus.

    The tag is the SYNC's counter byte when it has one, else the number (1..255, rolling) of
    SYNCs heard: either way the frames that follow two different SYNCs carry different tags, so
    a set mixing them is ``sync_mismatch`` even when their stamps cannot separate the instants
    (a sender that stalled, then sent several instants at once).
    """

    def __init__(self) -> None:
        self.t = -math.inf
        self.counter = 0
        self._heard = 0

    def on_sync(self, leg: int, data: bytes | bytearray, t: float) -> None:
        """A SYNC frame stamped ``t``, with its counter byte if it has one (``leg`` unused: the route's signature)."""
        self.t = t
        self._heard = self._heard % 255 + 1
        self.counter = data[0] if data else self._heard


class CanopenLink:
    """One fixture's CANopen encoders, in front of its cycle's ``on_frame``.

    Args:
        name: the fixture's name (for log lines).
        encoders: node ids, SYNC/EMCY ids and heartbeat period (from the EDS).
        on_frame: the cycle's ``on_frame(leg, data, t)``.
        sync: the bus's SYNC clock.
        staleness: s after a SYNC during which a TPDO belongs to it.
    """

    def __init__(self, name: str, encoders: CanopenEncoders, on_frame: OnFrame, sync: SyncClock, staleness: float):
        self.name, self.encoders, self._on_frame, self.sync, self.staleness = (
            name,
            encoders,
            on_frame,
            sync,
            staleness,
        )
        n = len(encoders.node_ids)
        self.emergency = [0] * n  # the active EMCY error code per leg (0: none)
        self._beat = [-math.inf] * n
        self._operational = [False] * n
        self._late = LATE * encoders.heartbeat
        self._reported: set[int] = set()  # legs whose lost heartbeat was logged
        self._unsynced: set[int] = set()  # legs whose TPDO came too long after the SYNC (logged once)

    def routes(self, tpdo_ids: list[int]) -> list[Route]:
        """``(can id, handler, leg)`` of every frame the link reads: TPDOs, EMCYs, heartbeats."""
        out: list[Route] = [(can_id, self.on_pdo, k) for k, can_id in enumerate(tpdo_ids)]
        for k, node in enumerate(self.encoders.node_ids):
            out.append((self.encoders.emcy_base + node, self.on_emcy, k))
            out.append((0x700 + node, self.on_heartbeat, k))
        return out

    def alive(self, leg: int, t: float) -> bool:
        """Whether the leg's node is heard (heartbeat on time, operational) at ``t`` (s)."""
        if self._late <= 0.0:
            return True
        ok = self._operational[leg] and t - self._beat[leg] <= self._late
        if not ok and leg not in self._reported:
            self._reported.add(leg)
            log.warning("fixture %s: leg%d (node %d): heartbeat lost", self.name, leg + 1, self.encoders.node_ids[leg])
        return ok

    def on_pdo(self, leg: int, data: bytes | bytearray, t: float) -> PoseRecord | None:
        """A TPDO of leg ``leg``: to the cycle, SYNC-stamped, the EMCY status byte and the SYNC counter appended."""
        if not self.alive(leg, t):
            return None  # a node not heard is silent, whatever it still sends
        sync = self.sync
        since = t - sync.t
        if not 0.0 <= since <= self.staleness and sync.t > -math.inf:  # long after its SYNC: which instant?
            if leg not in self._unsynced:
                self._unsynced.add(leg)
                log.warning("fixture %s: leg%d: a TPDO %.3g s after the SYNC: not used", self.name, leg + 1, since)
            return None
        self._unsynced.discard(leg)
        stamp = sync.t if since <= self.staleness else t
        status = 1 if self.emergency[leg] else 0
        return self._on_frame(leg, bytes(data[: self.encoders.pdo_length]) + bytes((status, sync.counter)), stamp)

    def on_emcy(self, leg: int, data: bytes | bytearray, t: float) -> None:
        """An EMCY of leg ``leg``: its error code (bytes 0-1) is active until a code 0 resets it."""
        code = int.from_bytes(bytes(data[:2]).ljust(2, b"\0"), "little")
        if code != self.emergency[leg]:
            if code:
                log.error("fixture %s: leg%d: EMCY error code %#06x", self.name, leg + 1, code)
            else:
                log.warning("fixture %s: leg%d: EMCY error reset", self.name, leg + 1)
        self.emergency[leg] = code

    def on_heartbeat(self, leg: int, data: bytes | bytearray, t: float) -> None:
        """A heartbeat (or boot-up) of leg ``leg``'s node: its NMT state, heard at ``t``."""
        self._beat[leg] = t
        self._operational[leg] = bool(data) and (data[0] & 0x7F) == OPERATIONAL
        if leg in self._reported and self._operational[leg]:
            self._reported.discard(leg)
            log.warning("fixture %s: leg%d: heartbeat heard again", self.name, leg + 1)


def master_frames(
    encoders: CanopenEncoders, stamp: float | None, heartbeats: bool, sync_counter: int | None = None
) -> list[can.Message]:
    """What a CANopen bus carries besides the TPDOs of one instant, for a simulation.

    The SYNC that starts the instant (stamped ``stamp``, s, when given; with its counter byte
    ``sync_counter``, 1..240, when given) and, with ``heartbeats``, each node's heartbeat in the
    *operational* state.
    """
    data = b"" if sync_counter is None else bytes([sync_counter])
    out = [can.Message(arbitration_id=encoders.sync_id, is_extended_id=False, data=data)]
    if heartbeats:
        out += [
            can.Message(arbitration_id=0x700 + n, is_extended_id=False, data=bytes([OPERATIONAL]))
            for n in encoders.node_ids
        ]
    if stamp is not None:
        for m in out:
            m.timestamp = stamp
    return out

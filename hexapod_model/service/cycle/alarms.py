"""Latched faults: what six readings cannot explain holds every later record off ``ok`` until acknowledged.

With six readings and six degrees of freedom any reading set is some pose: a slipped brake and a
faulty encoder (a step, two swapped legs) look alike. The cycle therefore latches a
:class:`LatchedFault` when

* ``discontinuity``: the tracker had to re-anchor over readings that jumped away from the
  motion model and stayed there (a step on one leg, swapped legs), or
* ``moved_while_locked``: while the fixture is locked, one or two legs left the steady band and
  stayed out while the others stayed still (brake slip on one leg, or an encoder fault),

and every later record has the status ``unacknowledged_fault`` (or a failure of its own) with the
fault's flags, until someone acknowledges it (``POST /fixtures/NAME/acknowledge`` with the token,
or ``hexapod fixture acknowledge``). A lock stored meanwhile carries the fault in its ``status``,
and a restart recovers the fault with it.
"""

from __future__ import annotations

import logging
import re
import time
from dataclasses import dataclass

log = logging.getLogger(__name__)

KINDS = ("discontinuity", "moved_while_locked")
UNACKNOWLEDGED = "unacknowledged_fault"
_STORED = re.compile(r"^unacknowledged:(discontinuity|moved_while_locked):((?:leg[1-6],?)*)@(.+)$")


@dataclass(frozen=True)
class LatchedFault:
    """A fault waiting for an acknowledgement.

    Attributes:
        kind: one of :data:`KINDS`.
        legs: the legs it names (0-based).
        t: Unix time (s) of the set that raised it.
    """

    kind: str
    legs: tuple[int, ...]
    t: float

    def flags(self) -> list[str]:
        """The record's flags: ``KIND:legN`` per leg (``KIND`` alone when no leg could be named)."""
        return [f"{self.kind}:leg{k + 1}" for k in self.legs] or [self.kind]

    def describe(self) -> dict:
        """JSON-ready form (``/health``, the acknowledgement's answer)."""
        return {"kind": self.kind, "legs": [k + 1 for k in self.legs], "t": self.t}

    def stored_status(self) -> str:
        """The ``status`` of a lock stored while this fault waits: ``unacknowledged:KIND:legN,...@t``."""
        return f"unacknowledged:{self.kind}:{','.join(f'leg{k + 1}' for k in self.legs)}@{self.t!r}"

    @classmethod
    def from_stored(cls, status: str) -> LatchedFault | None:
        """The fault a stored lock's ``status`` carries (None for ``ok``)."""
        m = _STORED.match(status)
        if m is None:
            return None
        legs = tuple(int(x[3:]) - 1 for x in m.group(2).split(",") if x)
        return cls(m.group(1), legs, float(m.group(3)))


@dataclass(frozen=True)
class Acknowledgement:
    """Who acknowledged which fault, when and from where.

    Attributes:
        fixture: its name.
        by: the name the acknowledging person gave.
        client: ``host:port`` of the HTTP peer (``cli`` / ``local`` otherwise).
        t: Unix time (s) of the acknowledgement.
        fault: what was acknowledged.
        note: free text given with it.
    """

    fixture: str
    by: str
    client: str
    t: float
    fault: LatchedFault
    note: str = ""

    def describe(self) -> dict:
        """JSON-ready form."""
        return {
            "fixture": self.fixture,
            "by": self.by,
            "client": self.client,
            "t": self.t,
            "fault": self.fault.describe(),
            "note": self.note,
        }


def _who(ack: Acknowledgement) -> tuple[str, str, float]:
    return ack.by, ack.client, ack.t


class FaultLatch:
    """One fixture's latched fault and its acknowledgement (the cycle's thread latches and takes).

    Args:
        fixture: the fixture's name (for the log).
    """

    def __init__(self, fixture: str):
        self.fixture = fixture
        self.fault: LatchedFault | None = None
        self.acknowledged: Acknowledgement | None = None  # the last one taken
        self._request: Acknowledgement | None = None

    def latch(self, kind: str, legs: tuple[int, ...], t: float) -> None:
        """Latch a fault (a fault already waiting stays the one to acknowledge)."""
        if self.fault is None:
            self.fault = LatchedFault(kind, legs, t)
            log.warning(
                "fixture %s: %s: not ok until acknowledged (POST /fixtures/%s/acknowledge)",
                self.fixture,
                ", ".join(self.fault.flags()),
                self.fixture,
            )

    def request(self, by: str, client: str, note: str = "", now: float | None = None) -> Acknowledgement | None:
        """Ask to clear the waiting fault (None when none waits); :meth:`take` applies it."""
        fault = self.fault
        if fault is None:
            return None
        self._request = Acknowledgement(self.fixture, by, client, time.time() if now is None else now, fault, note)
        return self._request

    @property
    def requested(self) -> bool:
        """Whether an acknowledgement waits to be taken."""
        return self._request is not None

    def take(self) -> Acknowledgement | None:
        """Clear the fault the waiting acknowledgement names (None: none, or another fault now); logged."""
        ack, self._request = self._request, None
        if ack is None or ack.fault != self.fault:
            return None
        self.fault, self.acknowledged = None, ack
        note = f": {ack.note}" if ack.note else ""
        flags = ",".join(ack.fault.flags())
        log.warning(
            "fixture %s: fault %s acknowledged by %s (%s) at t=%r%s",
            self.fixture,
            flags,
            ack.by,
            ack.client,
            ack.t,
            note,
        )
        return ack

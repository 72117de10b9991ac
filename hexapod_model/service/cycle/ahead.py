"""Frames stamped ahead of their instant: a frame that would open a newer instant waits for the next one.

A leg whose stamps run ahead of the others' (a gateway or encoder clock of its own, set wrong)
would open a new instant with each frame, so every set would close ``incomplete`` naming the
five healthy legs, and its stamp would date the records ahead of the frames they are made of.
So a frame newer than every frame seen by more than the set's skew is held until a frame of
another instant arrives: when that one is of the held frame's instant (or newer), the held frame
opens it as before; when it is of an instant between the one being collected and the held
frame's, the held frame ran ahead of the bus: it is dropped and its leg named (``ahead:legN``).
Frames of the instant being collected that arrive meanwhile join it. After sets were lost
the next frame can be of the instant the ahead stamp names, so for :data:`MEMORY` seconds after
a leg was last found ahead its frames that would open an instant are dropped too: a set never
mixes that leg's old reading with the others' new ones. The cost is one frame's delay of an
instant's first frame; nothing is published later than before.
"""

from __future__ import annotations

import math

MEMORY = 1.0  # s (bus time): a leg found ahead opens no instant for this long after
Frame = tuple[int, "bytes | bytearray", float]  # leg (0-based), payload, stamp (s)


class AheadCheck:
    """Hold an instant's first frame until the next frame says whether its stamp ran ahead (one fixture)."""

    def __init__(self) -> None:
        #: the frame held (leg, payload, stamp), None when none is: while None, a frame that would not
        #: open a newer instant is taken at once (:meth:`offer` returns it alone)
        self.held: Frame | None = None
        self._found: dict[int, float] = {}  # leg -> stamp (s) of the frame that last showed it ahead
        #: legs whose frames ran ahead since the last record (the cycle names and clears them)
        self.legs: set[int] = set()
        #: frames dropped for running ahead, since the start
        self.frames = 0

    @property
    def held_stamp(self) -> float:
        """The stamp (s) of the frame held, -inf when none is."""
        return -math.inf if self.held is None else self.held[2]

    def repeats(self, leg: int, data: bytes | bytearray, t: float, window: float) -> bool:
        """Whether the frame repeats the held one (same leg and payload, the same stamp or within ``window`` s)."""
        held = self.held
        return held is not None and held[0] == leg and held[1] == data and (t == held[2] or abs(t - held[2]) <= window)

    def offer(
        self, leg: int, data: bytes | bytearray, t: float, skew: float, newest: float, current: float
    ) -> list[Frame]:
        """The frames to take now, in order, given a new frame and the newest stamp taken (s).

        Args:
            leg: the new frame's leg (0-based).
            data: its payload.
            t: its stamp (s).
            skew: the set's skew (s; NaN until the period is known: nothing is held then).
            newest: the newest stamp among the frames taken so far (s).
            current: the stamp of the instant being collected (s): its first frame's, else ``newest``.
        """
        out: list[Frame] = []
        held, self.held = self.held, None
        if held is not None and t < held[2] - skew and t <= current + skew:
            self.held = held  # a frame of the instant being collected, arriving after it: not yet known
            return [(leg, data, t)]
        if held is not None:
            if t < held[2] - skew:  # a newer instant than the collected one, older than it: its stamp ran ahead
                self._found[held[0]] = t
                self.legs.add(held[0])
                self.frames += 1
            elif t - self._found.get(held[0], -math.inf) <= MEMORY:  # ran ahead lately: it may again
                self.legs.add(held[0])
                self.frames += 1
            else:
                out.append(held)
                newest = max(newest, held[2])
        if t > newest + skew:  # it would open a newer instant: the next frame confirms it (False for NaN)
            self.held = (leg, data, t)
        else:
            out.append((leg, data, t))
        return out

    def clear(self) -> None:
        """Forget the held frame and the legs found ahead (the bus clock went back)."""
        self.held = None
        self._found.clear()

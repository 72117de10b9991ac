"""A gateway's bursts: frames of several instants delivered at once under one stamp, split back into instants.

USB and Ethernet CAN gateways deliver frames in bursts, often with one receive stamp for the
whole burst, so stamps cannot tell its instants apart. Once a stamp holds two frames of one leg
(different payloads; an exact repeat of the frame before is a gateway's repeat and dropped)
after a frame of every leg, the cycle buffers each burst here until a frame with another stamp
ends it, then judges it:

* **in order**: the burst is whole groups of six frames, each group every leg once, every group
  in the leg order of the burst's first (one frame per leg per instant, the bus's order kept).
  Group ``n`` of ``N`` is then instant ``n``: its set is leg k's n-th frame with the others'
  n-th, never two instants mixed;
* **timed**: the stamps of two bursts in a row are ``N`` instant periods apart (within half a
  period): no instant of the burst was lost, so the stamp (the gateway's, of the burst's last
  instant) dates every instant: ``stamp - (N - n) * period``.

The period is the encoders' ``sample_period`` of ``[fixtures.encoder]`` (their SYNC or sampling
period): an in-order, timed burst's sets are then solved and published as any set (``ok`` when
nothing else is wrong), one burst late. Without it the period is the median of the recent
in-order bursts' ``(stamp - previous stamp) / N``, which a gateway losing the same instant of
every burst would fool: those sets are published with their poses but ``flagged``,
``batched_stamps``. Any other burst (reordered, a frame lost, an instant lost, the first after
frames with stamps of their own) is published as one ``incomplete`` record flagged
``batched_stamps``, without a pose: its frames cannot be put into instants. A single frame
under a stamp of its own, or three bursts in a row of one instant at most, end burst mode.
"""

from __future__ import annotations

import math
import statistics

SAME_STAMP = 1e-6  # s: two frames stamped closer than this share one stamp
RATIOS = 16  # in-order bursts whose period estimates are kept
MIN_RATIOS = 3  # in-order bursts needed before a burst is timed
SMALL_BURSTS = 3  # bursts in a row of at most six frames that end burst mode
Frame = tuple[int, "bytes | bytearray", float, "str | None"]  # leg (0-based), payload, stamp (s), failed check


class Bursts:
    """One fixture's gateway bursts: the detection, the burst being received and its judgement.

    Args:
        period: the encoders' sampling period (s; 0: not known, estimated from the bursts).
        channels: frames of one instant (six legs, and a hexapod's redundant sensors').
    """

    def __init__(self, period: float = 0.0, channels: int = 6) -> None:
        self.period = period
        self.channels = channels
        #: whether frames are buffered into bursts
        self.engaged = False
        self.stamp = -math.inf  # s, the stamp of the run of frames (or the burst) being received
        self._run: dict[int, bytes | bytearray] = {}  # leg -> its last payload under `stamp` (detection)
        self.frames: list[Frame] = []  # the burst being received
        self._first = False  # the burst during which burst mode began: partly taken as single sets already
        self._previous = math.nan  # s, the stamp of the burst before
        self._ratios: list[float] = []
        #: bursts that could not be split into instants, since the start
        self.unsplit = 0
        #: bursts in a row of at most one instant (one frame per channel): stamps separate instants again
        self.small = 0

    def shares_instant(self, leg: int, data: bytes | bytearray, t: float) -> bool:
        """Whether a frame outside burst mode shows a stamp holding two instants (then burst mode begins with it)."""
        if abs(t - self.stamp) >= SAME_STAMP:  # the common case: a stamp of its own
            self.stamp = t
            self._run.clear()
            self._run[leg] = data
            return False
        last = self._run.get(leg)
        if last is None or last == data or len(self._run) < self.channels:  # not yet a second instant of the whole set
            self._run[leg] = data
            return False
        self.engaged, self._first, self.frames, self.small = True, True, [], 0
        return True

    def add(self, leg: int, data: bytes | bytearray, t: float, failed: str | None) -> bool:
        """Buffer a frame of the burst being received; False for an exact repeat of the frame before."""
        if self.frames and self.frames[-1][0] == leg and self.frames[-1][1] == data:
            return False
        self.frames.append((leg, data, t, failed))
        return True

    def close(self, next_stamp: float) -> tuple[list[Frame], list[float] | None, int, bool]:
        """End the burst being received: its frames, each group's time (s) or None, the instants it spans.

        ``next_stamp`` (s) is the stamp of the frame that ended it (it begins the next burst).
        The last item says whether the times come from the configured period (else estimated).
        """
        if not self.frames:  # judged already (the bus went quiet after it)
            self.stamp = next_stamp
            return [], None, 0, False
        frames, stamp, previous, first = self.frames, self.stamp, self._previous, self._first
        self.frames, self.stamp, self._previous, self._first = [], next_stamp, stamp, False
        c = self.channels
        self.small = self.small + 1 if len(frames) <= c else 0
        n = len(frames) // c
        groups = [tuple(f[0] for f in frames[c * j : c * j + c]) for j in range(n)]
        in_order = n > 0 and len(frames) == c * n and len(set(groups[0])) == c and groups.count(groups[0]) == n
        gap = stamp - previous
        if in_order and not first and gap > 0.0:
            self._ratios = [*self._ratios[-(RATIOS - 1) :], gap / n]
        period = self.period or (statistics.median(self._ratios) if len(self._ratios) >= MIN_RATIOS else math.nan)
        instants = max(n, 1) if not period > 0.0 or not gap > 0.0 else max(round(gap / period), 1)
        if not (in_order and not first and abs(gap - n * period) <= 0.5 * period):  # (False for NaN)
            self.unsplit += 1
            return frames, None, instants, False
        return frames, [stamp - (n - 1 - j) * period for j in range(n)], n, self.period > 0.0

    def disengage(self) -> None:
        """Leave burst mode (frames have stamps of their own again)."""
        self.engaged, self.frames, self._first = False, [], False
        self._run.clear()
        self.stamp = -math.inf

"""Each frame checked against its layout's integrity fields before it may join a set.

A fixture whose frame layout carries a rolling counter or a checksum byte
(:mod:`~hexapod_model.service.config.integrity`) has every frame that is neither late nor a
repeat checked here, the checksum first (a corrupted frame says nothing about the sequence):

* ``bad_crc``: the checksum byte does not match the other bytes (a frame corrupted after CAN's
  own CRC, a sender that does not compute it);
* ``counter_gap``: the counter is not one more than the leg's previous frame's. The previous
  frame is the last one *seen* on the id, accepted or not (a corrupted one counts as the next
  in the sequence), so one lost frame costs the frame after it, and a second sender on the id
  fails with its frames or makes the encoder's fail while it sends (one that copies the
  encoder's next counter passes, and the encoder's own frame then fails: either way the set
  has a failed frame and gives no pose).

A frame that fails takes its leg's place in its instant's set, as a short frame does, and its
reading is never used: the set is published ``bad_frame`` naming the check and the leg
(``bad_crc:leg3``), and the cycle's counters say how many frames failed (``/health``). A set
of a CANopen fixture whose legs' frames follow different SYNCs (the SYNC counter the link
appends) is ``sync_mismatch`` (:meth:`FrameChecks.sync_mismatch`).
"""

from __future__ import annotations

from collections import Counter

from ..config.integrity import FrameIntegrity

CHECKS = ("bad_crc", "counter_gap", "sync_mismatch")  # names of the checks, flags and counters


class FrameChecks:
    """The integrity checks of one fixture's frames (its legs' counters).

    Args:
        integrity: the layout's integrity fields.
        legs: the fixture's legs.
    """

    def __init__(self, integrity: FrameIntegrity, legs: int = 6):
        self.integrity = integrity
        self._crc = integrity.crc_byte is not None
        self._counter = integrity.counter_bit is not None
        self._modulus = 1 << integrity.counter_bits
        self._last: list[int | None] = [None] * legs  # each leg's last counter seen

    def check(self, leg: int, data: bytes | bytearray) -> str | None:
        """The name of the first check ``data`` (a frame of leg ``leg``, 0-based) fails, or None."""
        if self._crc and not self.integrity.crc_ok(data):
            last = self._last[leg]
            if last is not None:  # the corrupted frame had its place in the sequence: the next one follows it
                self._last[leg] = (last + 1) % self._modulus
            return "bad_crc"
        if self._counter:
            c = self.integrity.counter(data)
            last, self._last[leg] = self._last[leg], c
            if last is not None and c != (last + 1) % self._modulus:
                return "counter_gap"
        return None

    @staticmethod
    def sync_mismatch(tags: list[int]) -> list[int]:
        """Legs (0-based) of a set whose SYNC counter ``tags`` differ from the set's most common one."""
        common = Counter(tags).most_common(1)[0][0]
        return [k for k, tag in enumerate(tags) if tag != common]

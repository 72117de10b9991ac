"""The platform inclinometer's CAN frame <-> its two tilt readings (rad): ``[fixtures.inclinometer]``.

A fixture whose hexapod declares an inclinometer (:mod:`hexapod_model.description.sensors`)
receives its two angles, ``tilt_x`` and ``tilt_y``, in one frame on a CAN id of its own. The
layout has its own table because an inclinometer is not a leg encoder: two count fields of one
width and byte order, a scale in radians per count and a count at the level (home) attitude per
angle, and the same optional *error* and *warning* bits. **Our defaults** (no manufacturer's
layout is implied): two little-endian signed 24-bit counts, ``tilt_x`` in bytes 0-2 and
``tilt_y`` in bytes 3-5, the error bit at bit 48 and the warning bit at bit 49, 1 µrad per
count. A tilt reading (rad, as the solver takes it) is ``(count - zero_count) * radians_per_count``;
nothing is clamped or wrapped.
"""

from __future__ import annotations

from dataclasses import dataclass

import can

from ..errors import ConfigError
from .codec import MAX_PAYLOAD, FrameLayout, decode, encode
from .table import Table


@dataclass(frozen=True)
class TiltCodec:
    """The inclinometer's frame: its CAN id and the layout of its two angles.

    Attributes:
        can_id: arbitration id of its frames.
        x: layout of the ``tilt_x`` count (its ``metres_per_count`` is radians per count here).
        y: layout of the ``tilt_y`` count (same width, order, scale and status bits as ``x``).
        zero_counts: the counts of ``tilt_x`` and ``tilt_y`` at the level attitude (reading 0 rad).
        extended_id: 29-bit identifier.
    """

    can_id: int
    x: FrameLayout
    y: FrameLayout
    zero_counts: tuple[int, int] = (0, 0)
    extended_id: bool = False

    @property
    def length(self) -> int:
        """Bytes a frame needs: both count fields and every status bit."""
        return max(self.x.length, self.y.length)

    def readings(self, data: bytes | bytearray) -> tuple[float, float, bool, bool]:
        """``(tilt_x, tilt_y, error, warning)`` of a payload (rad); :class:`FrameError` when too short."""
        if len(data) < self.length:
            decode(self.x if self.x.length > self.y.length else self.y, data)  # raises, naming the length
        cx, err, warn = self.x.unpack(data)
        cy = self.y.unpack(data)[0]
        step = self.x.metres_per_count
        return (cx - self.zero_counts[0]) * step, (cy - self.zero_counts[1]) * step, err, warn

    def message(self, tilt_x: float, tilt_y: float, error: bool = False, warning: bool = False) -> can.Message:
        """The ``can.Message`` an inclinometer at ``tilt_x``, ``tilt_y`` (rad) sends.

        Raises:
            FrameError: an angle whose count does not fit its field.
        """
        step = self.x.metres_per_count
        cx = self.zero_counts[0] + round(tilt_x / step)
        cy = self.zero_counts[1] + round(tilt_y / step)
        data = bytearray(encode(self.x, cx, error, warning).ljust(self.length, b"\0"))
        field = encode(self.y, cy)
        data[self.y.offset : self.y.offset + self.y.width] = field[self.y.offset : self.y.offset + self.y.width]
        return can.Message(arbitration_id=self.can_id, is_extended_id=self.extended_id, data=bytes(data))


def tilt_codec(t: Table, id_max: int, extended: bool) -> TiltCodec:
    """Read a ``[fixtures.inclinometer]`` table (missing keys take our defaults, module doc).

    Raises:
        ConfigError: a missing ``can_id``, a field outside the payload, overlapping fields, a
            status bit inside a field, a zero count outside its field; one line naming the field.
    """

    def bit(key: str, default: int) -> int | None:  # -1: the inclinometer has no such bit
        v = t.integer(key, default, -1, 8 * MAX_PAYLOAD - 1)
        return None if v == -1 else v

    can_id = t.integer("can_id", lo=0, hi=id_max)
    order = t.text("byte_order", "little", ("little", "big"))
    width = t.integer("width", 3, 1, MAX_PAYLOAD)
    x_offset = t.integer("x_offset", 0, 0, MAX_PAYLOAD - 1)
    y_offset = t.integer("y_offset", width, 0, MAX_PAYLOAD - 1)
    signed = t.boolean("signed", True)
    step = t.number("radians_per_count", 1e-6, -1.0, 1.0)
    error_bit, warning_bit = bit("error_bit", 48), bit("warning_bit", 49)
    if x_offset < y_offset + width and y_offset < x_offset + width:
        raise t.error(
            "y_offset", y_offset, f"the tilt_y field overlaps tilt_x's (bytes {x_offset}..{x_offset + width - 1})"
        )
    layouts = []
    for name, offset in (("x_offset", x_offset), ("y_offset", y_offset)):
        try:
            layouts.append(FrameLayout(order, offset, width, signed, step, error_bit, warning_bit))
        except ConfigError as exc:
            key = {"metres_per_count": "radians_per_count", "offset": name}.get(exc.field, exc.field)
            raise t.error(key, exc.value, exc.reason) from None
    zeros = t.take("zero_counts", [0, 0])
    if not isinstance(zeros, list) or len(zeros) != 2:
        raise t.error("zero_counts", zeros, "expected two integers (tilt_x, tilt_y)")
    lo, hi = layouts[0].count_range
    sub = Table({f"zero_counts[{k}]": v for k, v in enumerate(zeros)}, t.where, t.source)
    zero = tuple(sub.integer(f"zero_counts[{k}]", lo=lo, hi=hi) for k in range(2))
    t.finish()
    return TiltCodec(can_id, layouts[0], layouts[1], (zero[0], zero[1]), extended)

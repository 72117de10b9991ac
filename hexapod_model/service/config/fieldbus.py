"""Encoder protocols of ``[fixtures.encoder]``: the hand-written layout, CANopen (an EDS/DCF) or a DBC.

``protocol`` chooses how the encoders' frames are described:

* ``"raw"`` (default): the layout written out field by field
  (:class:`~hexapod_model.service.config.codec.FrameLayout`).
* ``"dbc"``: a vendor layout from a DBC file (``dbc = "encoders.dbc"``, read with ``cantools``):
  the message ``message`` (default: the file's only message) is the layout every leg's frame
  follows, on that leg's id of ``can_ids``; its signal ``position`` (default ``"Position"``) is
  the count, its 1-bit signals ``error`` / ``warning`` (default ``"Error"`` / ``"Warning"``
  when the message has them) the status bits. The count's size is the signal's ``scale`` in its
  ``unit`` (``m``, ``mm``, ``um`` or ``nm``). ``counter`` names the message's rolling-counter
  signal (2..16 bits, unsigned, little-endian or within one byte; it may be the message's
  multiplexer: a multiplexed counter), ``crc`` its checksum signal (one whole byte) and
  ``crc_kind`` the checksum (:mod:`~hexapod_model.service.config.integrity`).
* ``"canopen"``: CiA 301/406 encoders described by their EDS or DCF (``eds = "encoder.eds"``,
  read with ``canopen``): ``can_ids`` are the legs' TPDO1 COB-IDs, the node id of each is its
  COB-ID less the EDS's TPDO1 base (``$NODEID+0x180``); the position object ``position_object``
  (default ``0x6004``, *Position value*) is found in the TPDO1 mapping (``0x1A00``), its step
  is ``0x6005`` sub 1 (nm) unless ``metres_per_count`` is given. At run time
  (:mod:`~hexapod_model.service.cycle.canopen_link`) the SYNC stamps the set, an EMCY makes the
  leg's readings ``encoder_error`` until its error-reset EMCY, and a leg whose heartbeat
  (``0x1017``, ms) is late by half a period more is ``silent_leg``; a set whose frames follow
  SYNCs with different counters is ``sync_mismatch``.

Each is turned into one :class:`FrameLayout` the cycle decodes (byte-aligned fields; a layout
the fast decoder cannot read is a :class:`ConfigError` naming the signal).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...extras import install_hint
from ..errors import ConfigError
from .codec import MAX_PAYLOAD, MAX_SAMPLE_PERIOD, FrameLayout
from .integrity import CHECKSUMS, COUNTER_BITS, FrameIntegrity
from .table import Table

PROTOCOLS = ("raw", "dbc", "canopen")
FIELDBUS_HINT = f"the CANopen and DBC encoder protocols need canopen and cantools: {install_hint('fieldbus')}"
UNITS = {"m": 1.0, "mm": 1e3, "um": 1e6, "µm": 1e6, "nm": 1e9}  # per metre
_SIGNED = {0x2, 0x3, 0x4, 0x10, 0x15}  # CANopen INTEGER8/16/32/24/64
TPDO1_BASE = 0x180


@dataclass(frozen=True)
class CanopenEncoders:
    """What the cycle's CANopen link needs of a fixture's encoders (from the EDS).

    Attributes:
        eds: the EDS or DCF file.
        node_ids: each leg's node id, leg order.
        sync_id: COB-ID of the SYNC (``0x1005``).
        emcy_base: EMCY COB-ID less the node id (``0x1014``, ``$NODEID+0x80``).
        heartbeat: the producer heartbeat time (s, ``0x1017``); 0: none is watched.
        pdo_length: bytes of the TPDO; the link appends a status byte and the SYNC counter after them.
    """

    eds: Path
    node_ids: tuple[int, ...]
    sync_id: int = 0x80
    emcy_base: int = 0x80
    heartbeat: float = 0.0
    pdo_length: int = 4

    def ids(self) -> list[int]:
        """The CAN ids besides the TPDOs: SYNC, each leg's EMCY and heartbeat (``0x700`` + node id)."""
        return [self.sync_id, *(self.emcy_base + n for n in self.node_ids), *(0x700 + n for n in self.node_ids)]


def _path(t: Table, key: str, folder: Path) -> Path:
    value = t.text(key)
    p = Path(value) if Path(value).is_absolute() else folder / value
    if not p.is_file():
        raise t.error(key, value, f"{p} is not a readable file")
    return p


def dbc_layout(t: Table, folder: Path) -> FrameLayout:
    """The :class:`FrameLayout` of a ``protocol = "dbc"`` table (``t.finish()`` is called)."""
    try:
        import cantools
    except ImportError:
        raise t.error("protocol", "dbc", FIELDBUS_HINT) from None
    path = _path(t, "dbc", folder)
    try:
        db = cantools.database.load_file(str(path), database_format="dbc")
    except Exception as exc:  # noqa: BLE001 - cantools raises many kinds: one line
        raise t.error("dbc", str(path), f"not a DBC file cantools reads: {exc}") from None
    if not isinstance(db, cantools.database.can.Database):
        raise t.error("dbc", str(path), "not a CAN database")
    names = [m.name for m in db.messages]
    name = t.text("message", names[0] if len(names) == 1 else None)
    if name not in names:
        raise t.error("message", name, f"no such message in {path.name} (it has {', '.join(names) or 'none'})")
    message = db.get_message_by_name(name)
    signals = {s.name: s for s in message.signals}

    def signal(key: str, default: str | None):
        if key not in t.data:  # the default signal when the message has it
            return signals.get(default) if default else None
        chosen = t.text(key)
        if chosen not in signals:
            raise t.error(key, chosen, f"message {name} has no such signal ({', '.join(signals)})")
        return signals.get(chosen)

    position = signal("position", "Position")
    if position is None:
        raise t.error("position", None, f"name the count's signal of message {name}")
    error, warning = signal("error", "Error"), signal("warning", "Warning")
    unit = (position.unit or "").strip()
    if unit not in UNITS:
        raise t.error("position", position.name, f"unit {unit!r} of the signal: expected one of {', '.join(UNITS)}")
    if position.offset:
        raise t.error("position", position.name, f"offset {position.offset} of the signal: counts start at 0")
    little = position.byte_order == "little_endian"
    aligned = position.length % 8 == 0 and position.start % 8 == (0 if little else 7)
    if not aligned or position.length > 8 * MAX_PAYLOAD:
        raise t.error("position", position.name, "not a whole number of bytes starting on a byte: use protocol = raw")
    bits = []
    for key, s in (("error", error), ("warning", warning)):
        if s is not None and s.length != 1:
            raise t.error(key, s.name, f"a {s.length}-bit signal: expected a 1-bit status")
        bits.append(None if s is None else s.start)
    integrity = _dbc_integrity(t, name, signal("counter", None), signal("crc", None))
    period = t.number("sample_period", 0.0, 0.0, MAX_SAMPLE_PERIOD)
    t.finish()
    try:
        return FrameLayout(
            byte_order="little" if little else "big",
            offset=position.start // 8,
            width=position.length // 8,
            signed=bool(position.is_signed),
            metres_per_count=float(position.scale) / UNITS[unit],
            error_bit=bits[0],
            warning_bit=bits[1],
            integrity=integrity,
            sample_period=period,
        )
    except ConfigError as exc:
        raise exc.within(t.where, t.source) from None


def _dbc_integrity(t: Table, message: str, counter: Any, crc: Any) -> FrameIntegrity:
    """The rolling counter and checksum signals of a DBC message as :class:`FrameIntegrity`."""
    lo, hi = COUNTER_BITS
    counter_bit = None
    if counter is not None:
        within_byte = counter.start // 8 == (counter.start + counter.length - 1) // 8
        if counter.is_signed or not lo <= counter.length <= hi:
            raise t.error("counter", counter.name, f"expected an unsigned counter of {lo}..{hi} bits")
        if counter.byte_order != "little_endian" and not within_byte:
            raise t.error("counter", counter.name, "a big-endian counter across bytes: use protocol = raw")
        if getattr(counter, "multiplexer_ids", None):
            raise t.error("counter", counter.name, f"present only for some multiplexer values of {message}")
        counter_bit = counter.start if counter.byte_order == "little_endian" else counter.start - counter.length + 1
    crc_byte = None
    if crc is not None:
        if crc.length != 8 or (crc.start % 8 != (0 if crc.byte_order == "little_endian" else 7)):
            raise t.error("crc", crc.name, "expected a checksum of one whole byte")
        crc_byte = crc.start // 8
    kind = t.text("crc_kind", "crc8-sae-j1850", CHECKSUMS) if crc is not None else "crc8-sae-j1850"
    try:
        return FrameIntegrity(counter_bit, counter.length if counter is not None else 4, crc_byte, kind)
    except ConfigError as exc:
        raise exc.within(t.where, t.source) from None


def canopen_layout(t: Table, folder: Path, can_ids: list[int]) -> tuple[FrameLayout, CanopenEncoders]:
    """The layout of a ``protocol = "canopen"`` table and what its link needs (``t.finish()`` is called)."""
    try:
        import canopen
    except ImportError:
        raise t.error("protocol", "canopen", FIELDBUS_HINT) from None
    path = _path(t, "eds", folder)
    position_object = t.integer("position_object", 0x6004, 0x1000, 0xFFFF)
    step = t.number("metres_per_count", 0.0, -1.0, 1.0) if "metres_per_count" in t.data else None
    period = t.number("sample_period", 0.0, 0.0, MAX_SAMPLE_PERIOD)
    try:
        od: Any = canopen.objectdictionary.import_od(str(path), 0)  # its entries' types vary by object
        cob = int(od[0x1800][1].default) & 0x7FF
        mapped = [int(od[0x1A00][k].default) for k in range(1, int(od[0x1A00][0].default) + 1)]
        sync_id = int(od[0x1005].default) & 0x7FF if 0x1005 in od else 0x80
        emcy = int(od[0x1014].default) & 0x7FF if 0x1014 in od else 0x80
        heartbeat = float(od[0x1017].default) / 1000.0 if 0x1017 in od else 0.0
        if position_object not in od:
            raise t.error("position_object", hex(position_object), f"no such object in {path.name}")
        entry: Any = od[position_object]
        if not hasattr(entry, "data_type"):
            entry = entry[0] if 0 in entry else entry[1]
        kind = int(entry.data_type)
        if step is None and 0x6005 in od:
            step = float(od[0x6005][1].default) / 1e9
    except (KeyError, ValueError, TypeError, AttributeError, OSError) as exc:
        why = f"no TPDO1 mapping of the position in it ({type(exc).__name__}: {exc})"
        raise t.error("eds", str(path), why) from None
    offset = 0
    for m in mapped:
        index, bits = m >> 16, m & 0xFF
        if index == position_object:
            break
        offset += bits
    else:
        raise t.error("position_object", hex(position_object), f"not mapped in TPDO1 of {path.name}")
    length = sum(m & 0xFF for m in mapped) // 8
    if offset % 8 or bits % 8 or length > MAX_PAYLOAD - 2:  # the link appends the status and SYNC counter bytes
        raise t.error("eds", str(path), "the position must be whole bytes of a TPDO of at most 6 bytes")
    if cob != TPDO1_BASE:
        raise t.error("eds", str(path), f"TPDO1's COB-ID is node id + {cob:#x}; expected node id + 0x180")
    nodes = tuple(i - cob for i in can_ids)
    bad = next((i for i, n in zip(can_ids, nodes) if not 1 <= n <= 127), None)
    if bad is not None:
        raise t.error("protocol", "canopen", f"CAN id {bad:#x} is not a TPDO1 COB-ID (node id 1..127 + 0x180)")
    t.finish()
    try:
        layout = FrameLayout(
            "little",
            offset // 8,
            bits // 8,
            kind in _SIGNED,
            step or 1e-6,
            error_bit=8 * length,
            warning_bit=None,
            integrity=FrameIntegrity(sync_byte=length + 1),
            sample_period=period,
        )
    except ConfigError as exc:
        raise exc.within(t.where, t.source) from None
    return layout, CanopenEncoders(path, nodes, sync_id, emcy, heartbeat, length)

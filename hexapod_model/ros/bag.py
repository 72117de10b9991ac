"""The store's history as a ROS 2 bag in MCAP: ``hexapod fixture history CONFIG --mcap out.mcap``.

Topics (the types and names the service publishes live, :mod:`hexapod_model.ros.convert`):

* ``/<namespace>/<fixture>/pose`` (``geometry_msgs/PoseStamped``), ``/tf`` and
  ``/<namespace>/<fixture>/joint_states`` (the six prismatic joints: the sample log keeps no
  passive joints) for every ``ok`` sample;
* ``/diagnostics`` (``diagnostic_msgs/DiagnosticArray``) for every sample: its status and flags;
* ``/<namespace>/<fixture>/lock_pose`` (``PoseStamped``) for every stored lock event.

Messages are stamped and logged at the sample's (or lock's) ``t``, in time order. Each message is
the CDR that :mod:`hexapod_model.ros.messages` serialises (the bytes the live topics carry); the
schemas are ROS 2's ``.msg`` definitions (``ros2msg``, from ``rosbags``), so ``ros2 bag``,
Foxglove and ``rosbags`` read the file.
"""

from __future__ import annotations

import io
import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ..files import atomic_write_bytes
from ..service.record.pose_record import PoseRecord
from ..service.store.fixture_store import SAMPLE_COLUMNS, LockEvent
from .names import FixtureNames

PROFILE = "ros2"


def sample_record(row: tuple) -> PoseRecord:
    """A sample-log row (``SAMPLE_COLUMNS`` order) as a record (``sigma``, margin, ``stored`` unknown)."""
    r = dict(zip(SAMPLE_COLUMNS, row))
    pose_keys = ("x", "y", "z", "qx", "qy", "qz", "qw")
    pose = None if r["x"] is None else {k: r[k] for k in pose_keys}
    readings = [r[f"l{i}"] for i in range(1, 7)]
    flags = json.loads(r["flags"])
    return PoseRecord(
        r["fixture"], r["t"], readings, pose, r["status"], flags, 0, r["state"], None, None, None, None, None
    )


def lock_record(e: LockEvent) -> PoseRecord:
    """A lock event as an ``ok`` record of its pose."""
    keys = ("x", "y", "z", "qx", "qy", "qz", "qw")
    pose = dict(zip(keys, [float(v) for v in (*e.position, *e.quaternion)]))
    readings: list[float | None] = [float(v) for v in e.readings]
    return PoseRecord(e.fixture, e.t, readings, pose, e.status, [], 0, "locked", True, None, None, None, None)


def messages(
    samples: Iterable[tuple], locks: Iterable[LockEvent], names: dict[str, FixtureNames]
) -> list[tuple[float, str, Any]]:
    """``(t, topic, message)`` of the history, time order (a fixture not in ``names`` is left out)."""
    from .convert import diagnostic, joint_state, pose_stamped, stamp, transform
    from .messages import DiagnosticArray, Header, TFMessage

    out: list[tuple[float, str, Any]] = []
    for row in samples:
        rec = sample_record(row)
        n = names.get(rec.fixture)
        if n is None:
            continue
        t = rec.t
        for topic, msg in (
            (n.topic("pose"), pose_stamped(rec, n)),
            (n.topic("joint_states"), joint_state(rec, n, None)),
        ):
            if msg is not None:
                out.append((t, topic, msg))
        tf = transform(rec, n)
        if tf is not None:
            out.append((t, "/tf", TFMessage([tf])))
        status = diagnostic(rec, n, f"{n.namespace}/{n.fixture}")
        out.append((t, "/diagnostics", DiagnosticArray(Header(stamp(t), ""), [status])))
    for e in locks:
        n = names.get(e.fixture)
        msg = None if n is None else pose_stamped(lock_record(e), n)
        if msg is not None and n is not None:
            out.append((e.t, n.topic("lock_pose"), msg))
    out.sort(key=lambda m: m[0])
    return out


def write_mcap(path: str | Path, items: list[tuple[float, str, Any]]) -> int:
    """Write ``(t, topic, message)`` items as a ROS 2 MCAP bag at ``path`` (atomically); returns the count."""
    from mcap.writer import CompressionType, Writer
    from rosbags.typesys import Stores, get_typestore

    from .convert import stamp
    from .messages import ROS_NAMES

    store = get_typestore(Stores.ROS2_JAZZY)
    buffer = io.BytesIO()
    writer = Writer(buffer, compression=CompressionType.ZSTD)
    writer.start(profile=PROFILE, library="hexapod_model")
    schemas: dict[type, int] = {}
    channels: dict[str, int] = {}
    for seq, (t, topic, msg) in enumerate(items):
        cls = type(msg)
        if cls not in schemas:
            text = store.generate_msgdef(ROS_NAMES[cls], ros_version=2)[0]
            schemas[cls] = writer.register_schema(ROS_NAMES[cls], "ros2msg", text.encode())
        if topic not in channels:
            channels[topic] = writer.register_channel(topic, "cdr", schemas[cls])
        time = stamp(t)
        ns = time.sec * 1_000_000_000 + time.nanosec
        writer.add_message(channels[topic], log_time=ns, data=msg.serialize(), publish_time=ns, sequence=seq)
    writer.finish()
    atomic_write_bytes(path, buffer.getvalue())
    return len(items)

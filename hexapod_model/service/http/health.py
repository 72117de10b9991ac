"""``/health``: what the pose service says about itself, every problem on one line."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .view import ServiceView

OVERLOADED = 0.25  # s: frames handled this long after their bus stamps: the service is behind, not the fixture


def health(service: ServiceView) -> dict:
    """Service state: ``ok`` or ``degraded``, with every problem as one line in ``problems``.

    Degraded: a store error, the cycle stopped, a fixture whose latest record is not ``ok``
    (its status and flags say why) or whose fault waits for an acknowledgement, or a section of
    ``service.health_sections`` (other parts' own state, by name) with an ``error``, or the
    service running behind the bus (``service_overloaded``: frames handled more than
    :data:`OVERLOADED` s after their stamps; the fixture is not at fault).
    """
    now = time.time()
    fixtures, problems = {}, []
    for name, c in service.cycles.items():
        rec = c.last
        fixtures[name] = {
            "status": rec.status,
            "flags": rec.flags,
            "state": rec.state,
            "stored": rec.stored,
            "age_s": now - rec.t,
            "recovery": c.recovery,
            "recovered_t": None if c.recovered is None else c.recovered.t,
            "fault": None if c.fault is None else c.fault.describe(),
            "acknowledged": None if c.acknowledged is None else c.acknowledged.describe(),
            "counters": dict(c.counters),
        }
        if rec.status != "ok":
            problems.append(f"{name}: {rec.status}" + (f" ({', '.join(rec.flags)})" if rec.flags else ""))
        if c.fault is not None and rec.status != "unacknowledged_fault":
            problems.append(f"{name}: {', '.join(c.fault.flags())} waits for an acknowledgement")
    store_error = None if service.writer is None else service.writer.error
    lost_samples = 0 if service.writer is None else service.writer.dropped  # sample-log rows, since the start
    if store_error is not None:
        problems.append(f"store: {store_error}")
    if not service.running:
        problems.append("the cycle thread is not running")
    if service.lag > OVERLOADED:
        problems.append(
            f"service_overloaded: frames handled {service.lag:.3g} s after their bus stamps (limit {OVERLOADED} s)"
        )
    extra = {name: section() for name, section in service.health_sections.items()}
    problems += [f"{name}: {section['error']}" for name, section in extra.items() if section.get("error") is not None]
    return {
        "status": "ok" if not problems else "degraded",
        "problems": problems,
        "uptime_s": now - service.started,
        "frames": service.frames,
        "unknown_frames": service.unknown_frames,
        "lag_s": service.lag,
        "store": {"file": service.config.store.path.name, "error": store_error, "lost_samples": lost_samples},
        "fixtures": fixtures,
        **extra,
    }

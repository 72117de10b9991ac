"""What the HTTP application and ``/health`` read of the service: :class:`ServiceView`.

:class:`~hexapod_model.service.service.FixtureService` is one; the application holds it as this
view, so the HTTP layer names every attribute it uses and never imports the service above it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from ..changeover.changeover import Changeover
from ..config.settings import ServiceConfig
from ..cycle.alarms import Acknowledgement
from ..cycle.fixture_cycle import FixtureCycle
from ..store.writer import StoreWriter


class ServiceView(Protocol):
    """The running service as HTTP endpoints and ``/health`` see it.

    Attributes:
        config: the service's configuration (HTTP token, store path).
        cycles: the fixtures' cycles by name (empty until the service is ready).
        writer: the store's writer thread (None until ready): its ``error`` and ``dropped`` rows.
        changeover: targets, recipes and guidance (None until ready).
        health_sections: more ``/health`` sections by name, each a callable returning a dict.
        frames: frames read from the bus for a fixture since the start.
        unknown_frames: frames read whose id no fixture uses (and error or remote frames).
        lag: seconds between a frame's bus stamp and its handling, at the last check.
    """

    config: ServiceConfig
    cycles: dict[str, FixtureCycle]
    writer: StoreWriter | None
    changeover: Changeover | None
    health_sections: dict[str, Callable[[], dict]]
    frames: int
    unknown_frames: int
    lag: float

    @property
    def ready(self) -> bool:
        """Whether the cycle runs."""
        ...

    @property
    def running(self) -> bool:
        """Whether the cycle thread runs."""
        ...

    @property
    def started(self) -> float:
        """Unix time (s) of the start."""
        ...

    def starting(self) -> dict:
        """What ``/health`` says before the service is ready."""
        ...

    def names(self) -> list[str]:
        """Fixture names, configuration order."""
        ...

    def record_json(self, name: str) -> str | None:
        """The latest record of fixture ``name`` as JSON text (None for an unknown name)."""
        ...

    def acknowledge(self, name: str, by: str, client: str = "local", note: str = "") -> Acknowledgement | None:
        """Acknowledge the fault latched on fixture ``name``."""
        ...

    def health(self) -> dict:
        """``/health``'s answer."""
        ...

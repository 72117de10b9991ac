"""The fixture pose service: encoder frames on CAN in, tracked poses out, persisted and recovered.

Bem, Ude, Nemec 2026 ("Experimental Validation of the Direct Kinematics of a Passive
Stewart-Gough Platform with Modified Cardan Joints Using Integrated Absolute Linear Encoders",
§2 and §5.5): absolute encoders on the six legs report on a CAN bus, an edge computer collects
the readings, the pose is computed, published to the robot cell and kept in non-volatile memory
for recovery after shutdown. Here: python-can for the bus, the stream tracker for the poses,
SQLite for the store, uvicorn + Starlette for HTTP clients. ``docs/service.md``.

Public API::

    from hexapod_model.service import FixtureService, load_config
    svc = FixtureService(load_config("fixture.toml")).start()
    svc.record("left")      # the latest record (a PoseRecord), also GET /fixtures/left/pose
    svc.changeover.set_target("left", {"pose": {...}, "tolerance": {...}}, by="anna")
    svc.changeover.guidance("left")   # deviation, per-leg changes; docs/changeover.md
    svc.stop()
"""

from .changeover.changeover import Changeover, UnknownError
from .changeover.plan_monitor import PlanMonitor
from .config.cell import Cell, Located, locate
from .config.codec import Decoded, FrameLayout, LegCodec, decode, encode
from .config.settings import (
    BusConfig,
    FixtureConfig,
    HttpConfig,
    ServiceConfig,
    StoreConfig,
    config_from_dict,
    geometry_hash,
    load_config,
)
from .cycle.bus import open_bus
from .cycle.fixture_cycle import FixtureCycle
from .cycle.solver import PoseSolver, SolveOutcome, Uncertainty
from .errors import ConfigError, FrameError, ServiceError
from .http.client import RequestError, ServiceClient
from .record.pose_record import RECORD_KEYS, PoseRecord
from .service import FixtureService
from .sim.config import Fault, SimConfig, SimFixture, load_simulation, simulation_from_dict
from .sim.plan_player import PlanPlay
from .sim.simulator import SentSet, Simulator
from .store.fixture_store import LockEvent, Store
from .targets.guidance import guidance
from .targets.target import Recipe, Target, TargetError, Tolerance

__all__ = [
    "BusConfig",
    "Cell",
    "Changeover",
    "ConfigError",
    "Decoded",
    "Fault",
    "FixtureConfig",
    "FixtureCycle",
    "FixtureService",
    "FrameError",
    "FrameLayout",
    "HttpConfig",
    "LegCodec",
    "Located",
    "LockEvent",
    "PlanMonitor",
    "PlanPlay",
    "PoseRecord",
    "PoseSolver",
    "RECORD_KEYS",
    "Recipe",
    "RequestError",
    "SentSet",
    "ServiceClient",
    "ServiceConfig",
    "ServiceError",
    "SimConfig",
    "SimFixture",
    "Simulator",
    "SolveOutcome",
    "Store",
    "StoreConfig",
    "Target",
    "TargetError",
    "Tolerance",
    "Uncertainty",
    "UnknownError",
    "config_from_dict",
    "decode",
    "encode",
    "geometry_hash",
    "guidance",
    "load_config",
    "load_simulation",
    "locate",
    "open_bus",
    "simulation_from_dict",
]

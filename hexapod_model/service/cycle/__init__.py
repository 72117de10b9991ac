"""One fixture's cycle: CAN frames in, reading sets judged (lock, stuck legs, steps, faults), solved, records out."""

from ...tracking.steps import StepDetector
from .alarms import Acknowledgement, FaultLatch, LatchedFault
from .bus import open_bus
from .fixture_cycle import FixtureCycle
from .lock import LockDetector
from .solver import PoseSolver, SolveOutcome, Uncertainty
from .stuck import StuckDetector

__all__ = [
    "Acknowledgement",
    "FaultLatch",
    "FixtureCycle",
    "LatchedFault",
    "LockDetector",
    "PoseSolver",
    "SolveOutcome",
    "StepDetector",
    "StuckDetector",
    "Uncertainty",
    "open_bus",
]

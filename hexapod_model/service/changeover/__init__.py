"""The changeover of a running service: targets and recipes set, stored and turned into guidance."""

from .changeover import Changeover, UnknownError

__all__ = ["Changeover", "UnknownError"]

"""Changeover targets and recipes, validated, and the guidance from a record to a target."""

from .guidance import deviation, guidance, within
from .target import Recipe, Target, TargetError, Tolerance

__all__ = ["Recipe", "Target", "TargetError", "Tolerance", "deviation", "guidance", "within"]

"""The error of a changeover that has no valid path: which constraint blocks it, and where."""

from __future__ import annotations

from ..exceptions import HexapodError


class Blocked(HexapodError, ValueError):
    """No valid path: one line naming the fixture, the fraction of the way and the constraint.

    Attributes:
        fixture: the fixture whose move is blocked.
        fraction: how far along the move (0: its start, 1: its end).
        reason: the constraint, with the leg or joint and its value.
    """

    def __init__(self, fixture: str, fraction: float, reason: str):
        self.fixture, self.fraction, self.reason = fixture, fraction, reason
        super().__init__(f"fixture '{fixture}', {fraction:.0%} of the way: {reason}")

"""Geometric direct kinematics of the 3-6 hexapod sensor: :mod:`hexapod_model.kinematics.three_six`.

The solver lives with the kinematics, whose direct kinematics uses it to account for every
assembly of a 3-6 hexapod (:mod:`hexapod_model.kinematics.assemblies`); this module keeps its
analysis-layer name.
"""

from __future__ import annotations

from ..kinematics.three_six import ACCEPT, MAX_ASSEMBLIES, ThreeSixFK, ThreeSixSolution

__all__ = ["ACCEPT", "MAX_ASSEMBLIES", "ThreeSixFK", "ThreeSixSolution"]

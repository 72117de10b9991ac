"""Robot-driven changeover planning: a UR10 carries each plate from its lock pose to its target.

* :mod:`.carry`: the plate's checked SE(3) path (stroke, Cardan limits, singularity margin);
* :mod:`.robot`: the UR10 of example-robot-data, its IK branch and singularities;
* :mod:`.clearance`: the arm against the hexapods' bounding cylinders (coal);
* :mod:`.timing`: the time parametrisation (trapezoids, the carry's jerk-limited S-curve);
* :mod:`.scurve`: the S-curve and the plate jerk the service's tracker tolerates;
* :mod:`.order`: the visiting order;
* :mod:`.model`: the :class:`Plan` and ``plan.json``; :mod:`.writers`: CSV and JSON files;
* :mod:`.visit`: one fixture's part (:class:`Move`, :class:`Settings`);
* :mod:`.solve`: :func:`plan_changeover`.

Needs the ``plan`` extra (example-robot-data, coal).
"""

from .blocked import Blocked
from .model import PHASES, FixtureCell, Margins, Plan
from .solve import plan_changeover
from .visit import Move, Settings

__all__ = ["PHASES", "Blocked", "FixtureCell", "Margins", "Move", "Plan", "Settings", "plan_changeover"]

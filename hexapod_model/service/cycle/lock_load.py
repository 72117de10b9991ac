"""The ``load`` of a locked fixture's records: the process wrench's leg forces and the brakes' margin.

Computed once per lock, at the lock configuration (docs/statics.md for the model): the brakes hold
the six axial forces while the fixture is locked; the margin is the brake capacity (the fixture's
``brake_capacity``, else its geometry file's) minus the largest of them.
"""

from __future__ import annotations

import logging

import numpy as np

from ...analysis.statics import loads_at
from ...exceptions import SingularityError
from ...kinematics.hexapod import Hexapod
from ..config.settings import FixtureConfig

log = logging.getLogger(__name__)


def lock_load(cfg: FixtureConfig, hexa: Hexapod, q: np.ndarray) -> dict | None:
    """The record's ``load`` at the lock configuration ``q``; None without a ``process_wrench``.

    Keys: ``leg_forces_N`` (six axial forces, positive in tension), ``largest_leg_force_N``,
    ``brake_capacity_N`` and ``margin_N`` (None without a capacity). At a singular lock pose the forces
    are unbounded: every number but the capacity is None.
    """
    if cfg.process_wrench is None:
        return None
    capacity = cfg.brake_capacity
    if capacity is None and hexa.geometry is not None:
        capacity = hexa.geometry.brake_capacity
    try:
        loads = loads_at(hexa, q, cfg.process_wrench, "platform", cfg.wrench_point)
    except SingularityError:
        log.warning("fixture %s: locked at a singular pose: no leg forces for the process wrench", cfg.name)
        return {"leg_forces_N": None, "largest_leg_force_N": None, "brake_capacity_N": capacity, "margin_N": None}
    return {
        "leg_forces_N": loads.axial_force.tolist(),
        "largest_leg_force_N": loads.largest_axial_force,
        "brake_capacity_N": capacity,
        "margin_N": None if capacity is None else loads.margin(capacity),
    }

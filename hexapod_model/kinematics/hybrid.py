"""Hybrid kinematics' held sets: the named joints' values into a configuration, and the rank check.

:meth:`.hexapod.Hexapod.solve` holds any joints of the URDF: a float (m or rad) for a one-dof
joint, a 4x4 pose for the platform's floating joint. A held set that leaves the closure system
rank-deficient (free directions of motion) is refused, naming the count; its rank is measured
once per held set at a generic configuration within the limits (seeded, so the answer is the
same on every run).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pinocchio as pin

from ..exceptions import InputError
from .engine import SolveEngine
from .input_checks import LIMIT_SLACK, check_held_set, check_vector, free_directions


def hold(engine: SolveEngine, held: Mapping[str, object], q: np.ndarray) -> tuple[int, ...]:
    """Write the held values into ``q``; return the held joint ids, sorted.

    Raises:
        InputError: not a mapping, an unknown joint, a bad value, or an under-determined set.
        LimitError: a value outside its joint's limits.
    """
    if not isinstance(held, Mapping) or not held:
        raise InputError("held", held, "expected a non-empty mapping of joint name -> value")
    clm = engine.closed_loop
    m = clm.model
    ids = []
    for name, value in held.items():
        if name not in engine.joint_names:
            raise InputError("held joint", name, f"not a joint of this URDF ({len(engine.joint_names)} joints)")
        j = m.getJointId(name)
        if j == clm.platform_joint:
            engine.set_pose(q, value)
        else:
            v = check_vector(name, [value], 1)[0]
            iq = m.joints[j].idx_q
            if not clm.lower[iq] - LIMIT_SLACK <= v <= clm.upper[iq] + LIMIT_SLACK:
                raise engine.limit_error(iq, v)
            q[iq] = v
        ids.append(j)
    held_ids = tuple(sorted(ids))
    check_held_set(sorted(held), *free_directions_of(engine, held_ids))
    return held_ids


def free_directions_of(engine: SolveEngine, held_ids: tuple[int, ...]) -> tuple[int, int]:
    """(free directions, rank) of the closure system with ``held_ids`` held, cached on ``engine``."""
    known = engine.free_directions.get(held_ids)
    if known is None:  # rank at a generic configuration within the limits
        rng = np.random.default_rng(12345)
        qg = engine.closed_loop.q_home.copy()
        qg[engine.limited] = rng.uniform(0.5 * engine.limited_lo, 0.5 * engine.limited_hi)
        i = engine.closed_loop.platform_q
        qg[i : i + 7] = pin.SE3ToXYZQUAT(pin.exp6(rng.uniform(-0.05, 0.05, 6)))
        known = engine.free_directions[held_ids] = free_directions(engine.solver(held_ids).evaluate(qg)[1])
    return known

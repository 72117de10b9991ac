"""The plate's carry path: the SE(3) geodesic from the lock pose to the target, checked along its whole length.

``T(s) = T0 exp(s xi)``, ``s`` in ``[0, 1]``, ``xi = log6(T0^-1 T1)`` (platform frame): the
platform's twist is constant along it, so the plate turns about one axis while it translates.

**Between the samples.** Each checked quantity ``f`` (a leg's stroke margin, a Cardan angle's
margin, the singularity margin) is sampled at ``s_0 .. s_n``, at most ``STEP`` apart (0.5 mm of
the platform's origin and 0.05 deg). On each interval its rate is bounded by
``L = SAFETY * max |f(s_k+1) - f(s_k)| / h`` over the path (the largest sampled rate, doubled),
and a Lipschitz function with constant ``L`` cannot drop below
``(f(a) + f(b) - L h) / 2`` on ``[a, b]``. That lower bound, not the sampled values, is what
must stay above zero (above the threshold for the singularity margin), and it is the margin the
plan reports. The bound holds when the true rates stay within a factor ``SAFETY`` of the
largest sampled one: they do not double between samples 0.5 mm apart away from singularities,
which the singularity threshold keeps the path from (checked against ten times denser samples).

The singularity margin is ``cond(J_home) / cond(J(s))`` of the 6x6 leg Jacobian
(:func:`hexapod_model.analysis.jacobian.leg_jacobian_local`), lengths in the base's
characteristic length: 1 at home, 0 at a singularity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..analysis.jacobian import evaluate_jacobian, leg_jacobian_local
from ..kinematics.hexapod import Hexapod
from ..tracking.types import characteristic_length
from .blocked import Blocked

STEP = (0.5e-3, math.radians(0.05))  # m, rad: largest pose step between two samples
SAFETY = 2.0  # the sampled rate's factor in the Lipschitz bound


@dataclass(frozen=True)
class CarryPath:
    """A checked carry of one plate.

    Attributes:
        s: (n,) path parameter, 0 at the lock pose, 1 at the target.
        poses: (n, 4, 4) platform poses (m, base frame).
        readings: (n, 6) the legs' readings (m).
        twist: (6,) ``xi``, the platform-frame twist of the whole path (m, rad).
        stroke_margin: smallest certified distance (m) of a leg to its stroke limit along the path.
        joint_margin: smallest certified distance (rad) of a Cardan angle to its limit.
        singularity_margin: smallest certified singularity margin (1 at home).
    """

    s: np.ndarray
    poses: np.ndarray
    readings: np.ndarray
    twist: np.ndarray
    stroke_margin: float
    joint_margin: float
    singularity_margin: float


def geodesic(start: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, int]:
    """``(xi, n)``: the platform-frame twist from ``start`` to ``target`` and the number of intervals (>= 2)."""
    xi = pin.log6(pin.SE3(np.linalg.inv(start) @ target)).vector
    n = max(2, math.ceil(max(np.linalg.norm(xi[:3]) / STEP[0], np.linalg.norm(xi[3:]) / STEP[1])))
    return xi, n


def lower_bound(values: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Per interval and column, the Lipschitz lower bound of ``values`` ((n, k) sampled at ``s``).

    Returns:
        (n - 1, k): ``(f(a) + f(b) - L h) / 2`` with ``L`` ``SAFETY`` times the largest sampled rate.
    """
    h = np.diff(s)[:, None]
    rate = SAFETY * np.max(np.abs(np.diff(values, axis=0)) / h, axis=0, initial=0.0)
    return (values[:-1] + values[1:] - rate * h) / 2.0


def carry_path(
    hexa: Hexapod,
    start: np.ndarray,
    target: np.ndarray,
    fixture: str,
    min_singularity_margin: float,
    s: np.ndarray | None = None,
) -> CarryPath:
    """Sample and check the carry from ``start`` to ``target`` (4x4 platform poses, m, base frame).

    Args:
        hexa: the hexapod.
        start: the platform's start pose (4x4, m, base frame).
        target: its target pose.
        fixture: the fixture's name (for the messages).
        min_singularity_margin: the singularity margin kept along the path (1 at home).
        s: the path parameters to sample (increasing from 0 to 1, at least as dense as the
            default; default: equal steps of at most ``STEP``).

    Raises:
        Blocked: a leg leaves its stroke, a Cardan angle its limit, or the singularity margin
            drops below ``min_singularity_margin``: names the fixture, the fraction of the way and
            the leg or joint.
    """
    xi, n = geodesic(start, target)
    if s is None:
        s = np.linspace(0.0, 1.0, n + 1)
    else:
        s = np.asarray(s, dtype=float)
        if s[0] != 0.0 or s[-1] != 1.0 or np.any(np.diff(s) <= 0.0) or np.diff(s).max() > 1.0 / n * (1 + 1e-9):
            raise ValueError("the carry's samples must rise from 0 to 1, at most a default step apart")
        n = len(s) - 1
    clm = hexa.closed_loop
    limited = clm.limited_q()
    lo, hi = clm.lower[limited], clm.upper[limited]
    length = characteristic_length(hexa)
    home_cond = evaluate_jacobian(leg_jacobian_local(hexa, hexa.q_home)[0], length).condition_number
    T0 = pin.SE3(start)
    poses, readings = np.empty((n + 1, 4, 4)), np.empty((n + 1, 6))
    margins, sing = np.empty((n + 1, limited.size)), np.empty((n + 1, 1))
    qs = np.empty((n + 1, clm.nq))
    q = hexa.q_home
    for k, sk in enumerate(s):
        pose = start.copy() if k == 0 else target.copy() if k == n else (T0 * pin.exp6(sk * xi)).homogeneous
        sol = hexa.inverse(pose, q, check=False)
        if sol.status != "converged" and sol.status != "out_of_limits":
            raise Blocked(fixture, float(sk), f"the hexapod's inverse kinematics: {sol.message}")
        q = qs[k] = sol.q
        poses[k], readings[k] = pose, sol.lengths
        margins[k] = np.minimum(q[limited] - lo, hi - q[limited])
        cond = evaluate_jacobian(leg_jacobian_local(hexa, q)[0], length).condition_number
        sing[k] = home_cond / cond if math.isfinite(cond) else 0.0
    for values, limit, kind in ((margins, 0.0, "limit"), (sing, min_singularity_margin, "singularity")):
        low = values.min(axis=1) < limit
        bound = lower_bound(values, s) if n >= 1 else values
        bad = np.flatnonzero(low[:-1] | low[1:] | (bound.min(axis=1) < limit))
        if bad.size:
            k = int(bad[0])
            at = k if low[k] else k + 1 if low[k + 1] else k
            if kind == "singularity":
                raise Blocked(
                    fixture,
                    float(s[at]),
                    f"singularity margin {float(values[at, 0]):.3f} below {min_singularity_margin}",
                )
            j = int(np.argmin(bound[k]))
            iq = int(limited[j])
            what = "stroke" if iq in clm.prismatic_q else "joint"
            raise Blocked(
                fixture,
                float(s[at]),
                f"{what} limit: {clm.joint_name_of_q(iq)} = {qs[at, iq]:.4f} "
                f"leaves [{clm.lower[iq]:.4f}, {clm.upper[iq]:.4f}]",
            )
    mb, sb = lower_bound(margins, s), lower_bound(sing, s)
    prism = np.isin(limited, clm.prismatic_q)
    return CarryPath(
        s,
        poses,
        readings,
        xi,
        float(mb[:, prism].min()),
        float(mb[:, ~prism].min()),
        float(sb.min()),
    )

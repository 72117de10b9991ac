"""Time-parametrising the arm's joint path under its velocity and acceleration limits.

* A free-space move (approach, retract) is a straight line in joint space, from rest to rest,
  with all joints synchronised on one trapezoidal velocity profile of the path parameter: the
  time-optimal profile of that line under per-joint velocity and acceleration boxes.
* A carry follows the sampled joint path of the plate's geodesic; toppra (time-optimal path
  parametrisation by reachability analysis) times it at the samples under the joints'
  velocity and acceleration limits and the plate's speed limits (translation of the platform
  origin, rotation), from rest to rest. The profile has constant path acceleration between
  samples; limits are applied at ``LIMIT_SCALE`` of their value so that the interpolation
  between samples stays within them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..extras import require

LIMIT_SCALE = 0.98  # the share of a limit the timing uses
SAMPLE_DT = 0.05  # s between the points of a free-space move


@dataclass(frozen=True)
class Timed:
    """A timed joint path.

    Attributes:
        t: (n,) time from the segment's start (s).
        q: (n, 6) joints (rad).
        qd: (n, 6) rad/s.
        qdd: (n, 6) rad/s^2.
        index: (n,) for a carry, the index of the path sample of each point; -1 for a free move.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    index: np.ndarray


def line_duration(qa: np.ndarray, qb: np.ndarray, vmax: np.ndarray, amax: np.ndarray) -> tuple[float, float, float]:
    """``(T, v, a)``: the duration (s) of the straight move and its path parameter's peak rate and acceleration."""
    dq = np.abs(np.asarray(qb, dtype=float) - np.asarray(qa, dtype=float))
    if not np.any(dq > 0.0):
        return 0.0, 0.0, 0.0
    moving = dq > 0.0
    v = float(np.min(LIMIT_SCALE * vmax[moving] / dq[moving]))
    a = float(np.min(LIMIT_SCALE * amax[moving] / dq[moving]))
    if v * v / a >= 1.0:  # triangular: the peak rate is not reached
        v = math.sqrt(a)
        return 2.0 * v / a, v, a
    return 1.0 / v + v / a, v, a


def line(qa: np.ndarray, qb: np.ndarray, vmax: np.ndarray, amax: np.ndarray) -> Timed:
    """The straight move ``qa -> qb`` from rest to rest, sampled every :data:`SAMPLE_DT` and at its ends."""
    qa, qb = np.asarray(qa, dtype=float), np.asarray(qb, dtype=float)
    T, v, a = line_duration(qa, qb, vmax, amax)
    if T == 0.0:
        z = np.zeros((1, 6))
        return Timed(np.zeros(1), qa[None].copy(), z, z.copy(), np.full(1, -1))
    t = np.unique(np.r_[np.arange(0.0, T, SAMPLE_DT), T])
    tb = v / a  # end of the acceleration
    sig = np.where(t < tb, 0.5 * a * t**2, np.where(t <= T - tb, v * t - 0.5 * v * tb, 1.0 - 0.5 * a * (T - t) ** 2))
    sd = np.where(t < tb, a * t, np.where(t <= T - tb, v, a * (T - t)))
    sdd = np.where(t < tb, a, np.where(t <= T - tb, 0.0, -a))
    sig[-1], sd[-1] = 1.0, 0.0
    dq = qb - qa
    q = qa + sig[:, None] * dq
    q[-1] = qb
    return Timed(t, q, sd[:, None] * dq, sdd[:, None] * dq, np.full(t.size, -1))


def carry_timing(qs: np.ndarray, plate_time: float, vmax: np.ndarray, amax: np.ndarray) -> Timed:
    """Time the carry's joint samples ``qs`` ((n, 6), n >= 3, equal steps of the geodesic) with toppra.

    Args:
        qs: the arm's joints at the path samples (rad).
        plate_time: the carry's shortest duration at the plate's speed limits (s): the path's
            parameter may not advance faster than ``1 / plate_time`` per second.
        vmax: joint velocity limits (rad/s).
        amax: joint acceleration limits (rad/s^2).
    """
    require("toppra", "plan", "the carry's time parametrisation")
    import toppra
    import toppra.algorithm
    import toppra.constraint

    toppra.setup_logging("WARNING")
    n = len(qs)
    ss = np.linspace(0.0, max(plate_time, 1e-6), n)
    way = np.hstack([qs, ss[:, None]])
    path = toppra.SplineInterpolator(ss, way)
    vel = np.r_[LIMIT_SCALE * vmax, 1.0]
    acc = np.r_[LIMIT_SCALE * amax, 1e6]
    constraints = [
        toppra.constraint.JointVelocityConstraint(np.vstack([-vel, vel]).T),
        toppra.constraint.JointAccelerationConstraint(np.vstack([-acc, acc]).T),
    ]
    algorithm = toppra.algorithm.TOPPRA(constraints, path, gridpoints=ss, parametrizer="ParametrizeConstAccel")
    sd = algorithm.compute_parameterization(0.0, 0.0)[1]
    if sd is None or not np.all(np.isfinite(sd)):
        raise ValueError("toppra found no parametrisation of the carry")
    ds = np.diff(ss)
    dt = 2.0 * ds / np.maximum(sd[:-1] + sd[1:], 1e-12)
    t = np.r_[0.0, np.cumsum(dt)]
    acc_s = np.r_[(sd[1:] ** 2 - sd[:-1] ** 2) / (2.0 * ds), 0.0]
    acc_s[-1] = acc_s[-2]
    d1, d2 = path(ss, 1)[:, :6], path(ss, 2)[:, :6]
    qd = d1 * sd[:, None]
    qdd = d1 * acc_s[:, None] + d2 * sd[:, None] ** 2
    return Timed(t, qs.copy(), qd, qdd, np.arange(n))

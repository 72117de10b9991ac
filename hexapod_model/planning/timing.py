"""Time-parametrising the arm's joint path under its velocity and acceleration limits.

* A free-space move (approach, retract) is a straight line in joint space, from rest to rest,
  with all joints synchronised on one trapezoidal velocity profile of the path parameter: the
  time-optimal profile of that line under per-joint velocity and acceleration boxes.
* A carry follows the sampled joint path of the plate's geodesic on a jerk-limited S-curve of
  its path parameter (:mod:`.scurve`), from rest to rest: the plate's acceleration ramps up
  and down, never steps (a step is what the service's tracker takes for a discontinuity).
  The rate, acceleration and jerk of the parameter are bounded by the joints' velocity and
  acceleration limits, the plate's speed limits (translation of the platform origin,
  rotation) and the plate's jerk limit; limits are applied at ``LIMIT_SCALE`` of their value
  so that the interpolation between samples stays within them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .scurve import SCurve

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


def carry_curve(
    qs: np.ndarray, plate_time: float, vmax: np.ndarray, amax: np.ndarray, plate: np.ndarray, jerk: float
) -> SCurve:
    """The S-curve of the carry's path parameter over its samples ``qs`` ((n, 6), n >= 3, equal steps).

    Its rate, acceleration and jerk bounds are the largest under which the joints keep their
    velocity and acceleration limits and every watched coordinate of the plate its jerk limit,
    each at :data:`LIMIT_SCALE` (the derivatives along the path are those of cubic splines
    through the samples).

    Args:
        qs: the arm's joints at the path samples (rad).
        plate_time: the carry's shortest duration at the plate's speed limits (s): the path's
            parameter may not advance faster than ``1 / plate_time`` per second.
        vmax: joint velocity limits (rad/s).
        amax: joint acceleration limits (rad/s^2).
        plate: (n, 9) the plate at the samples: its origin (m, base frame) and the six leg
            readings (m), whose jerk is limited (the origin's by the norm of its vector).
        jerk: the plate's jerk limit (m/s^3).
    """
    from scipy.interpolate import CubicSpline

    ss = np.linspace(0.0, 1.0, len(qs))
    path = CubicSpline(ss, qs)
    d1, d2 = np.abs(path(ss, 1)).max(axis=0), np.abs(path(ss, 2)).max(axis=0)
    curve = CubicSpline(ss, plate)

    def size(d: np.ndarray) -> float:
        return float(max(np.linalg.norm(d[:, :3], axis=1).max(), np.abs(d[:, 3:]).max()))

    p1, p2, p3 = (size(curve(ss, k)) for k in (1, 2, 3))
    vel, acc = LIMIT_SCALE * vmax, LIMIT_SCALE * amax
    v = 1.0 / max(plate_time, 1e-6)
    v = min(v, float(np.min(vel / np.maximum(d1, 1e-12))))
    v = min(v, float(np.min(np.sqrt(0.5 * acc / np.maximum(d2, 1e-12)))))  # half the budget for the curvature
    a = float(np.min((acc - d2 * v * v) / np.maximum(d1, 1e-12)))
    a = min(a, math.sqrt(0.5 * LIMIT_SCALE * jerk / max(3.0 * p2 * v, 1e-12)))  # 3 p2 v a within half the jerk
    budget = LIMIT_SCALE * jerk - 3.0 * p2 * v * a - p3 * v**3
    if budget <= 0.0:  # the plate's path curves too much for its jerk at this rate: slower
        v = min(v, (0.25 * LIMIT_SCALE * jerk / max(p3, 1e-12)) ** (1.0 / 3.0))
        budget = LIMIT_SCALE * jerk - 3.0 * p2 * v * a - p3 * v**3
    return SCurve(v, a, budget / max(p1, 1e-12))


def refine(curve: SCurve, s: np.ndarray, max_dt: float) -> np.ndarray:
    """The path parameters ``s`` and more, so that ``curve`` passes two neighbours at most ``max_dt`` (s) apart."""
    t = curve.times(s)
    extra = [np.linspace(t[k], t[k + 1], math.ceil((t[k + 1] - t[k]) / max_dt) + 1)[1:-1] for k in range(len(t) - 1)]
    more = curve(np.concatenate(extra) if extra else np.zeros(0))[0]
    return np.union1d(s, more[(more > 0.0) & (more < 1.0)])


def carry_timing(qs: np.ndarray, s: np.ndarray, curve: SCurve) -> Timed:
    """The carry's joint samples ``qs`` ((n, 6), at path parameters ``s``) timed on ``curve``.

    ``qd`` and ``qdd`` are the path's derivatives (a cubic spline through the samples) times
    the curve's rate and acceleration.
    """
    from scipy.interpolate import CubicSpline

    path = CubicSpline(s, qs)
    t = curve.times(s)
    _, sd, sdd, _ = curve(t)
    qd = path(s, 1) * sd[:, None]
    qdd = path(s, 1) * sdd[:, None] + path(s, 2) * sd[:, None] ** 2
    return Timed(t, qs.copy(), qd, qdd, np.arange(len(s)))

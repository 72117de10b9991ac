"""Compiled (numba) SE(3) maps on unit quaternions ``[x, y, z, w]``: the stream tracker's branch check.

The same maps as :mod:`hexapod_model.lie.compiled` with the rotation kept as a quaternion
(free-flyer coordinates ``[x, y, z, qx, qy, qz, qw]``, Pinocchio's order):

* :func:`quat_mul`: the Hamilton product; :func:`quat_rotate`: ``R(q) v`` or ``R(q)^T v``;
* :func:`log6_quat`: ``log6`` of ``(p, q)``; ``log3`` goes through ``2 atan2(|u|, s)`` of the
  quaternion (``s >= 0``), which is accurate at every angle;
* :func:`exp6_quat`: ``exp6`` of a twist as ``(p, q)``;
* :func:`relative_free_flyer`: ``Ma^-1 Mb`` of two free-flyer configurations.

The coefficients that cancel (``beta``, ``(t - sin t) / t^3``) are taken from their series
below 0.2 rad. The results agree with Pinocchio's to rounding (``tests/lie/test_lie.py``
checks 1e-12), not to the bit. The NumPy twins are :mod:`hexapod_model.lie.se3` and
:mod:`hexapod_model.lie.quaternion`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_SERIES = 0.2  # rad: below, the coefficients that cancel (beta, c2) by their series (next term < 1e-16)


@njit(cache=True)
def quat_mul(a, b, out):
    """``out = a b`` for quaternions stored ``[x, y, z, w]``."""
    ax, ay, az, aw = a[0], a[1], a[2], a[3]
    bx, by, bz, bw = b[0], b[1], b[2], b[3]
    out[0] = aw * bx + ax * bw + ay * bz - az * by
    out[1] = aw * by - ax * bz + ay * bw + az * bx
    out[2] = aw * bz + ax * by - ay * bx + az * bw
    out[3] = aw * bw - ax * bx - ay * by - az * bz


@njit(cache=True)
def quat_rotate(q, v, out, inverse):
    """``out = R(q) v`` (or ``R(q)^T v`` when ``inverse``), ``q = [x, y, z, w]`` of unit norm."""
    x, y, z, w = q[0], q[1], q[2], q[3]
    if inverse:
        x, y, z = -x, -y, -z
    # v + 2 w (u x v) + 2 u x (u x v), u the vector part
    cx = y * v[2] - z * v[1]
    cy = z * v[0] - x * v[2]
    cz = x * v[1] - y * v[0]
    out[0] = v[0] + 2.0 * (w * cx + y * cz - z * cy)
    out[1] = v[1] + 2.0 * (w * cy + z * cx - x * cz)
    out[2] = v[2] + 2.0 * (w * cz + x * cy - y * cx)


@njit(cache=True)
def log6_quat(p, q, out):
    """``out = [v; w] = log6(M)`` of ``M = (R(q), p)``: ``w = log3(R)``, ``v = V(w)^-1 p``.

    ``V^-1 p = alpha p - w x p / 2 + beta (w . p) w`` with ``alpha = t sin t / (2 (1 - cos t))``
    and ``beta = 1 / t^2 - sin t / (2 t (1 - cos t))`` (``t = |w|``), as Pinocchio's ``log6``.
    """
    x, y, z, s = q[0], q[1], q[2], q[3]
    if s < 0.0:  # the same rotation; s >= 0 gives the angle in [0, pi]
        x, y, z, s = -x, -y, -z, -s
    n = math.sqrt(x * x + y * y + z * z)
    t = 2.0 * math.atan2(n, s)
    k = t / n if n > 0.0 else 2.0 / s  # t / |u| -> 2 / s as t -> 0
    wx, wy, wz = k * x, k * y, k * z
    t2 = t * t
    # alpha = (t / 2) cot(t / 2) (1 - cos t = 2 sin^2(t / 2): no cancellation), beta = (1 - alpha) / t^2
    if t < _SERIES:
        beta = 1.0 / 12.0 + t2 * (1.0 / 720.0 + t2 * (1.0 / 30240.0 + t2 * (1.0 / 1209600.0 + t2 / 47900160.0)))
        alpha = 1.0 - t2 * beta
    else:
        alpha = 0.5 * t * math.cos(0.5 * t) / math.sin(0.5 * t)
        beta = (1.0 - alpha) / t2
    d = beta * (wx * p[0] + wy * p[1] + wz * p[2])
    out[0] = alpha * p[0] - 0.5 * (wy * p[2] - wz * p[1]) + d * wx
    out[1] = alpha * p[1] - 0.5 * (wz * p[0] - wx * p[2]) + d * wy
    out[2] = alpha * p[2] - 0.5 * (wx * p[1] - wy * p[0]) + d * wz
    out[3], out[4], out[5] = wx, wy, wz


@njit(cache=True)
def exp6_quat(xi, p, q):
    """``(p, q)`` of ``exp6(xi)``, ``xi = [v; w]``: ``R = exp3(w)``, ``p = V(w) v``.

    ``V v = v + c1 w x v + c2 w x (w x v)``, ``c1 = (1 - cos t) / t^2``, ``c2 = (t - sin t) / t^3``.
    """
    wx, wy, wz = xi[3], xi[4], xi[5]
    t2 = wx * wx + wy * wy + wz * wz
    t = math.sqrt(t2)
    # h = sin(t / 2) / t, c1 = 2 h^2 (1 - cos t = 2 sin^2(t / 2)); c2 cancels: its series below _SERIES
    if t < _SERIES:
        h = 0.5 - t2 * (1.0 / 48.0 - t2 * (1.0 / 3840.0 - t2 * (1.0 / 645120.0 - t2 / 185794560.0)))
        c2 = 1.0 / 6.0 - t2 * (1.0 / 120.0 - t2 * (1.0 / 5040.0 - t2 * (1.0 / 362880.0 - t2 / 39916800.0)))
    else:
        h = math.sin(0.5 * t) / t
        c2 = (t - math.sin(t)) / (t2 * t)
    c1 = 2.0 * h * h
    q[0], q[1], q[2], q[3] = h * wx, h * wy, h * wz, math.cos(0.5 * t)
    vx, vy, vz = xi[0], xi[1], xi[2]
    ax, ay, az = wy * vz - wz * vy, wz * vx - wx * vz, wx * vy - wy * vx  # w x v
    bx, by, bz = wy * az - wz * ay, wz * ax - wx * az, wx * ay - wy * ax  # w x (w x v)
    p[0] = vx + c1 * ax + c2 * bx
    p[1] = vy + c1 * ay + c2 * by
    p[2] = vz + c1 * az + c2 * bz


@njit(cache=True)
def relative_free_flyer(a, b, p, q):
    """``(p, q)`` of ``Ma^-1 Mb`` for free-flyer coordinates ``a``, ``b`` (``[x, y, z, qx, qy, qz, qw]``)."""
    d = np.empty(3)
    d[0], d[1], d[2] = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    quat_rotate(a[3:], d, p, True)
    conj = np.empty(4)
    conj[0], conj[1], conj[2], conj[3] = -a[3], -a[4], -a[5], a[6]
    quat_mul(conj, b[3:], q)

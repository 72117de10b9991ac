"""Compiled (numba) SO(3) / SE(3) maps on rotation matrices, written as Pinocchio computes them.

They are inlined into the compiled Newton kernels (``inline="always"``) and the standard
model's steps; their NumPy twins are :mod:`hexapod_model.lie.so3`, :mod:`.se3` and
:mod:`.quaternion`, the quaternion-based twins of the tracker :mod:`.compiled_quaternion`.

* :func:`exp3`: Rodrigues' ``exp([w])`` (the standard model's rotation update);
* :func:`quat_to_matrix`: rotation of a unit quaternion ``(x, y, z, w)`` (Eigen's
  ``toRotationMatrix``: ``R = I + 2 w [u] + 2 [u]^2`` with ``u = (x, y, z)``, no normalisation);
* :func:`matrix_to_quat`: Eigen's branch on the trace (Shepperd's method);
* :func:`exp6`: ``exp`` of a twist ``(v, w)`` (Murray-Li-Sastry eq. 2.36:
  ``R = I + sin t/t [w] + (1 - cos t)/t^2 [w]^2``, ``p = V v`` with
  ``V = I + (1 - cos t)/t^2 [w] + (t - sin t)/t^3 [w]^2``), Taylor-expanded for small ``t``
  with Pinocchio's threshold;
* :func:`integrate_free_flyer`: Pinocchio's ``integrate`` on a free flyer's ``(p, quat)``:
  ``M1 = M0 exp6(v)`` (body velocity), the quaternion kept on ``q0``'s side and normalised to
  first order (``q *= (3 - |q|^2) / 2``);
* :func:`log6`: the inverse of ``exp6`` away from a half turn (the readings path's substeps turn
  far less), as Pinocchio's ``log3`` and ``log6``: the angle ``t`` from the trace (here by
  ``atan2`` with the skew part, accurate near 0), ``w = t / (2 sin t) (R - R^T)^v``,
  ``v = alpha p - [w] p / 2 + beta (w . p) w`` with ``alpha = t sin t / (2 (1 - cos t))``
  written ``(t/2) cot(t/2)`` (no cancellation) and ``beta = (1 - alpha) / t^2``,
  Taylor-expanded for small ``t``;
* :func:`difference_free_flyer`: Pinocchio's ``difference``, ``log6(M0^-1 M1)``;
* :func:`pose_to_xyzquat` / :func:`xyzquat_to_pose`: a 4x4 pose <-> its free-flyer configuration
  ``(x, y, z, qx, qy, qz, qw)`` relative to the home placement (the solver's pose in and out;
  their NumPy twins are in :mod:`hexapod_model.lie.se3`).

Tests: ``tests/lie/test_lie.py`` against ``pin.exp3``, ``pin.exp6``, ``pin.log6`` and
``pin.Quaternion``, ``tests/kinematics/test_chains.py`` against ``pin.integrate`` and
``pin.difference``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

_EPS = np.finfo(np.float64).eps
_TAYLOR_T = _EPS ** (1.0 / 3.0)  # Pinocchio's TaylorSeriesExpansion<double>::precision<3>()


@njit(cache=True, inline="always")
def exp3(wx, wy, wz, E):
    """Write ``E`` (3x3) ``= exp([w])`` of the rotation vector ``w = (wx, wy, wz)`` (rad; Rodrigues)."""
    a = np.sqrt(wx * wx + wy * wy + wz * wz)
    if a < 1e-8:
        s, c = 1.0 - a * a / 6.0, 0.5 - a * a / 24.0
    else:
        s, c = np.sin(a) / a, (1.0 - np.cos(a)) / (a * a)
    E[0, 0] = 1.0 - c * (wy * wy + wz * wz)
    E[1, 1] = 1.0 - c * (wx * wx + wz * wz)
    E[2, 2] = 1.0 - c * (wx * wx + wy * wy)
    E[0, 1], E[1, 0] = -s * wz + c * wx * wy, s * wz + c * wx * wy
    E[0, 2], E[2, 0] = s * wy + c * wx * wz, -s * wy + c * wx * wz
    E[1, 2], E[2, 1] = -s * wx + c * wy * wz, s * wx + c * wy * wz


@njit(cache=True, inline="always")
def quat_to_matrix(x, y, z, w, R):
    """Write ``R`` (3x3) of the quaternion ``(x, y, z, w)`` (assumed unit, as Pinocchio does)."""
    tx, ty, tz = 2.0 * x, 2.0 * y, 2.0 * z
    twx, twy, twz = tx * w, ty * w, tz * w
    txx, txy, txz = tx * x, ty * x, tz * x
    tyy, tyz, tzz = ty * y, tz * y, tz * z
    R[0, 0], R[0, 1], R[0, 2] = 1.0 - (tyy + tzz), txy - twz, txz + twy
    R[1, 0], R[1, 1], R[1, 2] = txy + twz, 1.0 - (txx + tzz), tyz - twx
    R[2, 0], R[2, 1], R[2, 2] = txz - twy, tyz + twx, 1.0 - (txx + tyy)


@njit(cache=True, inline="always")
def matrix_to_quat(R, out):
    """Write the quaternion ``out = (x, y, z, w)`` of rotation ``R`` (Eigen's algorithm)."""
    t = R[0, 0] + R[1, 1] + R[2, 2]
    if t > 0.0:
        t = np.sqrt(t + 1.0)
        out[3] = 0.5 * t
        t = 0.5 / t
        out[0] = (R[2, 1] - R[1, 2]) * t
        out[1] = (R[0, 2] - R[2, 0]) * t
        out[2] = (R[1, 0] - R[0, 1]) * t
        return
    i = 0
    if R[1, 1] > R[0, 0]:
        i = 1
    if R[2, 2] > R[i, i]:
        i = 2
    j = (i + 1) % 3
    k = (j + 1) % 3
    t = np.sqrt(R[i, i] - R[j, j] - R[k, k] + 1.0)
    out[i] = 0.5 * t
    t = 0.5 / t
    out[3] = (R[k, j] - R[j, k]) * t
    out[j] = (R[j, i] + R[i, j]) * t
    out[k] = (R[k, i] + R[i, k]) * t


@njit(cache=True, inline="always")
def _exp6_terms(v):
    """``(a_wxv, a_v, diag, p0, p1, p2)`` of ``exp6(v)``.

    The rotation's ``(1 - cos t) / t^2``, ``sin t / t`` and ``cos t``, and the translation
    ``V v``; Taylor-expanded below Pinocchio's threshold, as Pinocchio's ``exp6``.
    """
    wx, wy, wz = v[3], v[4], v[5]
    t2 = wx * wx + wy * wy + wz * wz + _EPS * _EPS
    t = np.sqrt(t2)
    if t < _TAYLOR_T:
        a_wxv = 0.5 - t2 / 24.0  # (1 - cos t) / t^2
        a_v = 1.0 - t2 / 6.0  # sin t / t
        a_w = 1.0 / 6.0 - t2 / 120.0  # (t - sin t) / t^3
        diag = 1.0 - t2 / 2.0  # cos t
    else:
        st, ct = np.sin(t), np.cos(t)
        a_wxv = (1.0 - ct) / t2
        a_v = st / t
        a_w = (1.0 - a_v) / t2
        diag = ct
    vx, vy, vz = v[0], v[1], v[2]
    wv = wx * vx + wy * vy + wz * vz
    p0 = a_v * vx + a_w * wv * wx + a_wxv * (wy * vz - wz * vy)
    p1 = a_v * vy + a_w * wv * wy + a_wxv * (wz * vx - wx * vz)
    p2 = a_v * vz + a_w * wv * wz + a_wxv * (wx * vy - wy * vx)
    return a_wxv, a_v, diag, p0, p1, p2


@njit(cache=True, inline="always")
def exp6(v, R, p):
    """Write ``R`` (3x3) and ``p`` (3,) of ``exp6(v)``, ``v = (linear, angular)`` (Pinocchio's ``exp6``)."""
    wx, wy, wz = v[3], v[4], v[5]
    a_wxv, a_v, diag, p[0], p[1], p[2] = _exp6_terms(v)
    w = (wx, wy, wz)
    for a in range(3):
        for b in range(3):
            R[a, b] = a_wxv * w[a] * w[b]
        R[a, a] += diag
    R[0, 1] -= a_v * wz
    R[1, 0] += a_v * wz
    R[0, 2] += a_v * wy
    R[2, 0] -= a_v * wy
    R[1, 2] -= a_v * wx
    R[2, 1] += a_v * wx


@njit(cache=True)
def integrate_free_flyer(x, v):
    """``x <- x (+) v`` for a free flyer ``x = (p, quat)`` and body velocity ``v`` (6,), in place.

    :func:`quat_to_matrix` of ``x``'s quaternion ``R0``, :func:`exp6` of ``v`` ``(Re, pe)``, the
    product ``M1 = M0 exp6(v)`` and :func:`matrix_to_quat` of ``R1``, written out in scalars with
    the same operations in the same order (no array, and a quarter of the time; the same numbers:
    ``tests/lie/test_lie.py``), then the quaternion kept on ``x``'s side and normalised to first order.
    """
    qx, qy, qz, qw = x[3], x[4], x[5], x[6]
    tx, ty, tz = 2.0 * qx, 2.0 * qy, 2.0 * qz  # R0, as quat_to_matrix
    twx, twy, twz = tx * qw, ty * qw, tz * qw
    txx, txy, txz = tx * qx, ty * qx, tz * qx
    tyy, tyz, tzz = ty * qy, tz * qy, tz * qz
    a00, a01, a02 = 1.0 - (tyy + tzz), txy - twz, txz + twy
    a10, a11, a12 = txy + twz, 1.0 - (txx + tzz), tyz - twx
    a20, a21, a22 = txz - twy, tyz + twx, 1.0 - (txx + tyy)
    wx, wy, wz = v[3], v[4], v[5]  # (Re, pe), as exp6
    a_wxv, a_v, diag, p0, p1, p2 = _exp6_terms(v)
    cx, cy, cz = a_wxv * wx, a_wxv * wy, a_wxv * wz
    e00, e01, e02 = cx * wx + diag, cx * wy - a_v * wz, cx * wz + a_v * wy
    e10, e11, e12 = cy * wx + a_v * wz, cy * wy + diag, cy * wz - a_v * wx
    e20, e21, e22 = cz * wx - a_v * wy, cz * wy + a_v * wx, cz * wz + diag
    x[0] += a00 * p0 + a01 * p1 + a02 * p2  # M1 = M0 exp6(v): p1 = p0 + R0 pe, R1 = R0 Re
    x[1] += a10 * p0 + a11 * p1 + a12 * p2
    x[2] += a20 * p0 + a21 * p1 + a22 * p2
    r00, r01, r02 = (
        a00 * e00 + a01 * e10 + a02 * e20,
        a00 * e01 + a01 * e11 + a02 * e21,
        a00 * e02 + a01 * e12 + a02 * e22,
    )
    r10, r11, r12 = (
        a10 * e00 + a11 * e10 + a12 * e20,
        a10 * e01 + a11 * e11 + a12 * e21,
        a10 * e02 + a11 * e12 + a12 * e22,
    )
    r20, r21, r22 = (
        a20 * e00 + a21 * e10 + a22 * e20,
        a20 * e01 + a21 * e11 + a22 * e21,
        a20 * e02 + a21 * e12 + a22 * e22,
    )
    t = r00 + r11 + r22  # R1's quaternion, as matrix_to_quat (Eigen: Shepperd's branches)
    if t > 0.0:
        t = np.sqrt(t + 1.0)
        ow = 0.5 * t
        t = 0.5 / t
        ox, oy, oz = (r21 - r12) * t, (r02 - r20) * t, (r10 - r01) * t
    else:
        i = 0
        if r11 > r00:
            i = 1
        if r22 > (r11 if i == 1 else r00):
            i = 2
        if i == 0:
            t = np.sqrt(r00 - r11 - r22 + 1.0)
            ox = 0.5 * t
            t = 0.5 / t
            ow, oy, oz = (r21 - r12) * t, (r10 + r01) * t, (r20 + r02) * t
        elif i == 1:
            t = np.sqrt(r11 - r22 - r00 + 1.0)
            oy = 0.5 * t
            t = 0.5 / t
            ow, oz, ox = (r02 - r20) * t, (r21 + r12) * t, (r01 + r10) * t
        else:
            t = np.sqrt(r22 - r00 - r11 + 1.0)
            oz = 0.5 * t
            t = 0.5 / t
            ow, ox, oy = (r10 - r01) * t, (r02 + r20) * t, (r12 + r21) * t
    dot = ox * qx + oy * qy + oz * qz + ow * qw
    sign = -1.0 if dot < 0.0 else 1.0
    n2 = ox * ox + oy * oy + oz * oz + ow * ow
    alpha = sign * (3.0 - n2) / 2.0  # first-order normalisation
    x[3], x[4], x[5], x[6] = alpha * ox, alpha * oy, alpha * oz, alpha * ow


@njit(cache=True, inline="always")
def log6(R, p, out):
    """Write ``out = (v, w)`` (6,) of ``log6`` of the transform ``(R, p)`` (Pinocchio's ``log6``, no half turn)."""
    ax, ay, az = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]  # 2 sin t times the axis
    sin_t = 0.5 * np.sqrt(ax * ax + ay * ay + az * az)
    t = np.arctan2(sin_t, 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0))  # acos of the trace, well conditioned
    half = 0.5 * t / sin_t if t > _TAYLOR_T else 0.5  # t / (2 sin t)
    wx, wy, wz = half * ax, half * ay, half * az
    t2 = t * t
    if t < _TAYLOR_T:
        alpha = 1.0 - t2 / 12.0 - t2 * t2 / 720.0
        beta = 1.0 / 12.0 + t2 / 720.0
    else:
        alpha = 0.5 * t / np.tan(0.5 * t)  # t sin t / (2 (1 - cos t)), without the cancellation
        beta = (1.0 - alpha) / t2
    wp = beta * (wx * p[0] + wy * p[1] + wz * p[2])
    out[0] = alpha * p[0] - 0.5 * (wy * p[2] - wz * p[1]) + wp * wx
    out[1] = alpha * p[1] - 0.5 * (wz * p[0] - wx * p[2]) + wp * wy
    out[2] = alpha * p[2] - 0.5 * (wx * p[1] - wy * p[0]) + wp * wz
    out[3], out[4], out[5] = wx, wy, wz


@njit(cache=True)
def difference_free_flyer(x0, x1, out, R0, R1, Rd, pd):
    """``out = x1 (-) x0`` (6,), the body velocity from free flyer ``x0`` to ``x1``: ``log6(M0^-1 M1)``.

    ``R0``, ``R1``, ``Rd`` (3x3) and ``pd`` (3,) are scratch buffers.
    """
    quat_to_matrix(x0[3], x0[4], x0[5], x0[6], R0)
    quat_to_matrix(x1[3], x1[4], x1[5], x1[6], R1)
    for a in range(3):  # M0^-1 M1 = (R0^T R1, R0^T (p1 - p0))
        pd[a] = R0[0, a] * (x1[0] - x0[0]) + R0[1, a] * (x1[1] - x0[1]) + R0[2, a] * (x1[2] - x0[2])
        for b in range(3):
            Rd[a, b] = R0[0, a] * R1[0, b] + R0[1, a] * R1[1, b] + R0[2, a] * R1[2, b]
    log6(Rd, pd, out)


@njit(cache=True)
def pose_to_xyzquat(T, H, out):
    """Free-flyer configuration of a pose relative to home.

    Free-flyer configuration ``(x, y, z, qx, qy, qz, qw)`` of pose ``T`` relative to the
    home placement ``H`` (both 4x4): ``H^-1 T``. No array is allocated (a batch's rows call it).
    """
    for a in range(3):
        out[a] = H[0, a] * (T[0, 3] - H[0, 3]) + H[1, a] * (T[1, 3] - H[1, 3]) + H[2, a] * (T[2, 3] - H[2, 3])
    # M = H^T T, entry by entry
    m00 = H[0, 0] * T[0, 0] + H[1, 0] * T[1, 0] + H[2, 0] * T[2, 0]
    m01 = H[0, 0] * T[0, 1] + H[1, 0] * T[1, 1] + H[2, 0] * T[2, 1]
    m02 = H[0, 0] * T[0, 2] + H[1, 0] * T[1, 2] + H[2, 0] * T[2, 2]
    m10 = H[0, 1] * T[0, 0] + H[1, 1] * T[1, 0] + H[2, 1] * T[2, 0]
    m11 = H[0, 1] * T[0, 1] + H[1, 1] * T[1, 1] + H[2, 1] * T[2, 1]
    m12 = H[0, 1] * T[0, 2] + H[1, 1] * T[1, 2] + H[2, 1] * T[2, 2]
    m20 = H[0, 2] * T[0, 0] + H[1, 2] * T[1, 0] + H[2, 2] * T[2, 0]
    m21 = H[0, 2] * T[0, 1] + H[1, 2] * T[1, 1] + H[2, 2] * T[2, 1]
    m22 = H[0, 2] * T[0, 2] + H[1, 2] * T[1, 2] + H[2, 2] * T[2, 2]
    tr = m00 + m11 + m22
    if tr > 0.0:
        s = 2.0 * np.sqrt(1.0 + tr)
        qw, qx, qy, qz = 0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s
    elif m00 > m11 and m00 > m22:
        s = 2.0 * np.sqrt(1.0 + m00 - m11 - m22)
        qw, qx, qy, qz = (m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s
    elif m11 > m22:
        s = 2.0 * np.sqrt(1.0 + m11 - m00 - m22)
        qw, qx, qy, qz = (m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s
    else:
        s = 2.0 * np.sqrt(1.0 + m22 - m00 - m11)
        qw, qx, qy, qz = (m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s
    n = np.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    out[3], out[4], out[5], out[6] = qx / n, qy / n, qz / n, qw / n


@njit(cache=True)
def xyzquat_to_pose(x, H, T):
    """Pose ``T = H * X`` (4x4) of the free-flyer configuration ``x`` relative to ``H`` (no array allocated)."""
    qx, qy, qz, qw = x[3], x[4], x[5], x[6]
    n = np.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    qx, qy, qz, qw = qx / n, qy / n, qz / n, qw / n
    x00, x01, x02 = 1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)
    x10, x11, x12 = 2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)
    x20, x21, x22 = 2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)
    for a in range(3):
        h0, h1, h2 = H[a, 0], H[a, 1], H[a, 2]
        T[a, 0] = h0 * x00 + h1 * x10 + h2 * x20
        T[a, 1] = h0 * x01 + h1 * x11 + h2 * x21
        T[a, 2] = h0 * x02 + h1 * x12 + h2 * x22
        T[a, 3] = h0 * x[0] + h1 * x[1] + h2 * x[2] + H[a, 3]
        T[3, a] = 0.0
    T[3, 3] = 1.0

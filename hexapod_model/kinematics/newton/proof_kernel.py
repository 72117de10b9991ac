"""The compiled entry of the warm-step proof: from two configurations to the Krawczyk proof's bounds.

:func:`prove_configurations` reads the Krawczyk unknowns of the start and the result (the legs'
free joints and the platform's chart coordinates about the result's placement,
:mod:`.enclosure`), runs :func:`.krawczyk.prove_whole` on the readings path between them (and
:func:`.krawczyk.prove_path`, which subdivides it, when that fails) and
turns the proven radius into bounds of the platform's position and rotation, in one call.
:class:`.proof.StepProver` calls it through :func:`prove_packed`, which takes the model's tables
and the work arrays packed in two buffers (:func:`pack`): numba unboxes each array an entry is
handed (about 70 ns each), and the unpacked call takes some fifty. Everything between it and
the enclosure is inlined into it: one compiled unit (see :mod:`.krawczyk`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .kernels import copy_into
from .krawczyk import prove_in_region, prove_path, prove_region, prove_whole
from .views import view

#: the dimensions of :func:`.krawczyk.workspace`'s arrays (V, Jm, Jr, Y, H, the 16 of the per-leg
#: test's workspace, the 6 of the enclosure's)
WORK = (2, 2, 2, 2, 2) + (3, 3, 2, 3, 3, 2, 1, 2, 2, 2, 1, 1, 1, 3, 3, 3) + (3, 5, 4, 4, 3, 2)
#: the dimensions of the arrays :func:`pack` takes: the work, the path's ends, the model's tables
LAYOUT = WORK + (2, 2, 1, 1, 1, 1, 2, 1) + (4, 3, 3, 1, 2, 2, 2, 1)
INTEGER = (38, 40, 41, 42)  # the int64 arrays among them (the rest are float64)

REGION = 7e-4  # a region's readings box: half-width per reading, in the model's length (its anchor radius)
REGION_STEP = 0.35  # a region is built about a step (and after a motion) of at most this fraction of its half-width
MIN_SCALE = 1.0 / 64.0  # the narrowest region tried (its width halves after each failure)
COOLDOWN = 16  # steps without a region try after one at the narrowest width failed


@njit(cache=True)
def platform_placement(home, q, platform_q, T):
    """``T`` (4, 4) = world placement of the platform joint at ``q``: ``home * X(q)`` (as :mod:`.chains`)."""
    px, py, pz = q[platform_q], q[platform_q + 1], q[platform_q + 2]
    qx, qy, qz, qw = q[platform_q + 3], q[platform_q + 4], q[platform_q + 5], q[platform_q + 6]
    X = (
        (1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw), px),
        (2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw), py),
        (2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy), pz),
    )
    for a in range(4):
        for b in range(4):
            s = home[a, 3] if b == 3 else 0.0
            for k in range(3):
                s += home[a, k] * X[k][b]
            T[a, b] = s


@njit(cache=True, inline="always")
def _relative(T0, T, a, b):
    """``(R0^T R)[a, b]`` for the rotations of the placements ``T0`` and ``T``."""
    return T0[0, a] * T[0, b] + T0[1, a] * T[1, b] + T0[2, a] * T[2, b]


@njit(cache=True)
def chart_coordinates_into(T0, T, v):
    """``v`` (6,) with ``T = T0 * Trans(v[:3]) * Rx(v[3]) Ry(v[4]) Rz(v[5])`` (m along ``T0``'s axes, rad)."""
    v[4] = np.arcsin(min(1.0, max(-1.0, _relative(T0, T, 0, 2))))
    v[3] = np.arctan2(-_relative(T0, T, 1, 2), _relative(T0, T, 2, 2))
    v[5] = np.arctan2(-_relative(T0, T, 0, 1), _relative(T0, T, 0, 0))
    for a in range(3):
        s = 0.0
        for k in range(3):
            s += T0[k, a] * (T[k, 3] - T0[k, 3])
        v[a] = s


@njit(cache=True)
def unknowns_into(q, T0, T, home, platform_q, leg_q, free, x):
    """``x`` (nf,): the legs' free joints of ``q``, then its chart coordinates about ``T0`` (``T`` scratch)."""
    v = 0
    for i in range(6):
        for k in range(free.shape[1]):
            x[v] = q[leg_q[i, free[i, k]]]
            v += 1
    platform_placement(home, q, platform_q, T)
    chart_coordinates_into(T0, T, x[v:])


@njit(cache=True, inline="always")
def _in_region(tables, home, platform_q, leg_q, free, held_q, q0, q1, work, ends):
    """The proof of a step inside the thread's proven region (``ends``' state), or not proven (then no region)."""
    T0, T, x0, x1, l0, l1, Tc, state = ends
    V, H = work[0], work[4]
    if not _step_ends(home, platform_q, leg_q, free, held_q, q0, q1, Tc, ends):
        return False, 0, V[23]
    proven, _, radius, _ = prove_in_region(tables, Tc, x0, x1, l0, l1, H[5], H[6], work, V[22], V[23])
    return proven, 0, radius


@njit(cache=True)
def _step_ends(home, platform_q, leg_q, free, held_q, q0, q1, chart, ends):
    """Write the step's unknowns about ``chart`` and its readings into ``ends``; False when not finite."""
    _, T, x0, x1, l0, l1, _, _ = ends
    unknowns_into(q0, chart, T, home, platform_q, leg_q, free, x0)
    unknowns_into(q1, chart, T, home, platform_q, leg_q, free, x1)
    for i in range(6):
        l0[i], l1[i] = q0[held_q[i]], q1[held_q[i]]
    return _finite(x0, x1, l0, l1)


@njit(cache=True, inline="always")
def _finite(x0, x1, l0, l1):
    for a in range(x0.shape[0]):
        if not (np.isfinite(x0[a]) and np.isfinite(x1[a])):
            return False
    for i in range(6):
        if not np.isfinite(l0[i] + l1[i]):
            return False
    return True


@njit(cache=True, inline="always")
def _build_region(tables, T0, x0, x1, l0, l1, work, state, motion):
    """A region about the step (:func:`.krawczyk.prove_region`) and the step's end box in it; state updated.

    Tried when the step and ``motion`` (how far the readings moved since the last step proven on
    these arrays, m; 0 when unknown) are both at most :data:`REGION_STEP` of the region's
    half-width: only then can the next step's readings fall in it. A step from a prediction (a
    tracker's guess) is short while the readings move fast: its motion says the region would be
    left at once, and it would cost two tests at every step instead of one.

    The readings box is ``REGION * scale`` model lengths each way per reading, centred half that
    ahead of ``l1`` along the step (the readings' direction of travel); ``scale`` halves after a
    failure (down to :data:`MIN_SCALE`, then no try for :data:`COOLDOWN` steps) and doubles
    after a success.
    """
    V, H = work[0], work[4]
    hm, hr = H[5], H[6]
    nf = x0.shape[0]
    length = V[21][nf - 6]  # the chart translations' unit: the model's length
    step = 0.0
    for i in range(6):
        step = max(step, abs(l1[i] - l0[i]))
    half = REGION * state[1] * length
    if state[2] > 0.0 or max(step, motion) > REGION_STEP * half:
        state[2] = max(0.0, state[2] - 1.0)
        return False, V[23]
    for i in range(6):
        hr[i] = half
        hm[i] = l1[i] + (0.5 * half * (l1[i] - l0[i]) / step if step > 0.0 else 0.0)
    if prove_region(tables, T0, x0, x1, l0, l1, hm, hr, work, V[22], V[23]):
        proven, _, radius, _ = prove_in_region(tables, T0, x0, x1, l0, l1, hm, hr, work, V[22], V[23])
        if proven:
            state[0], state[1] = 1.0, min(1.0, 2.0 * state[1])
            return True, radius
    state[0] = 0.0
    if state[1] > MIN_SCALE:
        state[1] *= 0.5
    else:
        state[2] = COOLDOWN
    return False, V[23]


@njit(cache=True, inline="always")
def prove_configurations(tables, home, platform_q, leg_q, free, held_q, q0, q1, structured, subdivide, work, ends):
    """The Krawczyk proof of the readings path from ``q0`` to ``q1`` (:meth:`.proof.StepProver.prove`).

    The per-leg test (``structured``) first looks for a **region** proven by an earlier step
    (:func:`.krawczyk.prove_region`: one solution for every reading of a box, in one box of the
    unknowns): a step whose readings lie in it and whose start lies in its box needs only the
    box about its result. Else a short step of readings that move slowly (since the last step:
    ``l1`` holds its readings) builds a region about itself; a longer one, or one whose region
    fails, gets the test of its whole path (:func:`.krawczyk.prove_whole`), then the subdivided
    path (:func:`.krawczyk.prove_path`).

    Args:
        tables: ``(placements, motions, closure, held, rows)`` (:func:`.enclosure.enclose_into`).
        home: (4, 4) the platform joint's placement at home.
        platform_q: configuration index of the platform's free flyer.
        leg_q: (6, n) configuration index of each leg joint.
        free: (6, n - 1) positions of each leg's free joints in ``leg_q``.
        held_q: (6,) configuration indices of the held joints.
        q0: the start configuration (closed).
        q1: the result.
        structured: the per-leg Krawczyk test (else the dense reference, without regions).
        subdivide: when the test of the whole path fails, subdivide it (else not proven).
        work: :func:`.krawczyk.workspace`, overwritten (but a region's rows while it holds).
        ends: ``(T0, T, x0, x1, l0, l1, Tc, state)`` work arrays ((4, 4), (4, 4), (nf,), (nf,),
            (6,), (6,), (4, 4), (4,)): ``l1`` the last step's end readings on entry (NaN: none),
            this step's on return, ``Tc`` the region's chart origin, ``state`` (region held,
            its width's scale, steps before the next try, whether this step was proven in a
            region).

    Returns:
        ``(proven, tests, position, rotation, parts)``: ``position`` (m) and ``rotation`` (rad)
        bound the distance and the rotation angle between ``q1``'s platform and the exact one
        the path ends at (``inf`` when not proven).
    """
    T0, T, x0, x1, l0, l1, Tc, state = ends
    motion = 0.0  # how far the readings moved since the last step (l1 still holds its readings; NaN before any)
    for i in range(6):
        d = abs(q1[held_q[i]] - l1[i])
        if d > motion:
            motion = d
    state[3] = 0.0
    if not structured:  # the dense test overwrites the region's enclosure
        state[0] = 0.0
    proven, tests = False, 0
    radius = work[0][23]
    if structured and state[0] > 0.0:
        proven, tests, radius = _in_region(tables, home, platform_q, leg_q, free, held_q, q0, q1, work, ends)
        state[0] = 1.0 if proven else 0.0
    if not proven:
        platform_placement(home, q1, platform_q, T0)
        if not _step_ends(home, platform_q, leg_q, free, held_q, q0, q1, T0, ends):
            return False, 0, np.inf, np.inf, 0
        if structured:
            proven, radius = _build_region(tables, T0, x0, x1, l0, l1, work, state, motion)
            if proven:
                for row in range(4):
                    copy_into(Tc[row], T0[row])
                tests = 1
        if not proven:
            proven, more, radius, parts = prove_whole(tables, T0, x0, x1, l0, l1, structured, work)
            tests += more
            if not proven and subdivide:  # subdivide the path (its tests counted after the whole path's)
                proven, more, radius, parts = prove_path(tables, T0, x0, x1, l0, l1, structured, work)
                tests += more
            if not proven:
                return False, tests, np.inf, np.inf, 0
            position, rotation = _bounds(radius)
            return True, tests, position, rotation, parts
    state[3] = 1.0
    position, rotation = _bounds(radius)
    return True, tests, position, rotation, 1


@njit(cache=True, inline="always")
def _bounds(radius):
    """The platform's position (m) and rotation (rad) bounds from the unknowns' proven radius."""
    r = radius[-6:]
    slack = 1e-15  # the chart coordinates of q1 itself, computed in floating point
    position = np.sqrt(r[0] ** 2 + r[1] ** 2 + r[2] ** 2) * (1.0 + 1e-12) + slack
    rotation = (r[3] + r[4] + r[5]) * (1.0 + 1e-12) + slack
    return position, rotation


def pack(arrays: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[np.ndarray]]:
    """The arrays of :data:`LAYOUT` copied into one float64 and one int64 buffer.

    Returns ``(floats, ints, spec, views)``: ``spec`` (k, 6) holds each array's offset in its
    buffer and its shape, ``views`` the arrays as views of the buffers (what :func:`unpack`
    makes of them in compiled code), in the order given.
    """
    if tuple(a.ndim for a in arrays) != LAYOUT:
        raise ValueError("the arrays do not have the packed layout")
    sizes = [0, 0]
    spec = np.zeros((len(arrays), 6), dtype=np.int64)
    for k, a in enumerate(arrays):
        which = int(k in INTEGER)
        spec[k, 0] = sizes[which]
        spec[k, 1 : 1 + a.ndim] = a.shape
        sizes[which] += a.size
    buffers = (np.zeros(sizes[0]), np.zeros(sizes[1], dtype=np.int64))
    views = []
    for k, a in enumerate(arrays):
        v = view(buffers[int(k in INTEGER)], int(spec[k, 0]), a.shape)  # as the compiled unpack makes it
        v[...] = a
        views.append(v)
    return buffers[0], buffers[1], spec, views


@njit(cache=True, inline="always")
def _v1(b, s, k):
    return b[s[k, 0] : s[k, 0] + s[k, 1]]


@njit(cache=True, inline="always")
def _v2(b, s, k):
    o, a, c = s[k, 0], s[k, 1], s[k, 2]
    return view(b, o, (a, c))


@njit(cache=True, inline="always")
def _v3(b, s, k):
    o, a, c, d = s[k, 0], s[k, 1], s[k, 2], s[k, 3]
    return view(b, o, (a, c, d))


@njit(cache=True, inline="always")
def _v4(b, s, k):
    o, a, c, d, e = s[k, 0], s[k, 1], s[k, 2], s[k, 3], s[k, 4]
    return view(b, o, (a, c, d, e))


@njit(cache=True, inline="always")
def _v5(b, s, k):
    o, a, c, d, e, f = s[k, 0], s[k, 1], s[k, 2], s[k, 3], s[k, 4], s[k, 5]
    return view(b, o, (a, c, d, e, f))


@njit(cache=True)
def unpack(fb, ib, s):
    """The work arrays, the ends and the model's tables of :func:`pack`'s buffers, as views (see :data:`LAYOUT`)."""
    f, i = fb, ib
    blocks = (
        *(_v3(f, s, 5), _v3(f, s, 6), _v2(f, s, 7), _v3(f, s, 8), _v3(f, s, 9), _v2(f, s, 10), _v1(f, s, 11)),
        *(_v2(f, s, 12), _v2(f, s, 13), _v2(f, s, 14), _v1(f, s, 15), _v1(f, s, 16), _v1(f, s, 17)),
        *(_v3(f, s, 18), _v3(f, s, 19), _v3(f, s, 20)),
    )
    ew = (_v3(f, s, 21), _v5(f, s, 22), _v4(f, s, 23), _v4(f, s, 24), _v3(f, s, 25), _v2(f, s, 26))
    work = (_v2(f, s, 0), _v2(f, s, 1), _v2(f, s, 2), _v2(f, s, 3), _v2(f, s, 4), blocks, ew)
    ends = (
        *(_v2(f, s, 27), _v2(f, s, 28), _v1(f, s, 29), _v1(f, s, 30), _v1(f, s, 31), _v1(f, s, 32)),
        *(_v2(f, s, 33), _v1(f, s, 34)),
    )
    model = (
        *(_v4(f, s, 35), _v3(f, s, 36), _v3(f, s, 37), _v1(i, s, 38), _v2(f, s, 39)),
        *(_v2(i, s, 40), _v2(i, s, 41), _v1(i, s, 42)),
    )
    return work, ends, model


@njit(cache=True)
def prove_packed(fb, ib, spec, rows, platform_q, q0, q1, structured, subdivide):
    """:func:`prove_configurations` with the tables, work arrays and ends in :func:`pack`'s buffers.

    Args:
        fb: the float64 buffer.
        ib: the int64 buffer.
        spec: the arrays' offsets and shapes in them.
        rows: 6 (6-D closures) or 3 (point closures).
        platform_q: configuration index of the platform's free flyer.
        q0: the start configuration (closed).
        q1: the result.
        structured: as :func:`prove_configurations`.
        subdivide: as :func:`prove_configurations`.

    Returns:
        :func:`prove_configurations`'s ``(proven, tests, position, rotation, parts)``.
    """
    work, ends, model = unpack(fb, ib, spec)
    placements, motions, closure, held, home, leg_q, free, held_q = model
    tables = (placements, motions, closure, held, rows)
    return prove_configurations(
        tables, home, platform_q, leg_q, free, held_q, q0, q1, structured, subdivide, work, ends
    )

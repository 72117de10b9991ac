"""A compiled Krawczyk (interval Newton) proof that a readings path stays on one assembly.

For the closure residual ``F(x, s)`` of direct kinematics (:mod:`.enclosure`: the unknowns ``x``
are the legs' free joints and the platform's chart coordinates; the held prismatic joints move
with the readings path ``l(s) = l0 + s (l1 - l0)``), a box ``X = xc +- rho`` and a parameter
interval ``S = [s0, s1]``, the Krawczyk operator is

    K(X, S) = xc - Y F(xc, S) + (I - Y J(X, S)) (X - xc),   Y ~ J(xc, s_mid)^-1,

with ``F(xc, S)`` and ``J(X, S)`` the interval enclosures over the box and the parameter interval.
**Krawczyk's theorem** (Krawczyk 1969; Moore 1977; Neumaier, *Interval methods for systems of
equations*, 1990, thm. 5.1.8): if ``K(X, S)`` lies in the interior of ``X``, then for every ``s`` in
``S`` the system ``F(., s) = 0`` has exactly one solution in ``X`` (and ``J`` is regular on ``X``), so
the solutions for ``s`` in ``S`` form one continuous path inside ``X`` (the implicit function theorem).

:func:`prove_path` covers ``[0, 1]`` with such tests, halving a sub-interval whose test fails (at
most ``MAX_TESTS`` tests), and chains them: consecutive boxes must hold each other's ``K``
(then the path's point at the shared ``s`` is the unique solution of both boxes), the first box
the start ``x0``, and a last test at ``s = 1`` alone, on a box about the result ``x1`` inside the
last box (whose Jacobian enclosure, over a larger box and parameter interval, holds the
Jacobian over it: inclusion isotonicity), gives the box that holds the exact solution the path
ends at (the unique one of the last box at ``s = 1``).
Each test tries ``INFLATIONS`` boxes (epsilon-inflation: ``rho <- 1.5 |K - xc|``).

``Y`` is applied leg by leg (:mod:`.krawczyk_blocks`: each leg's block of the block-arrow
Jacobian, then the 6 x 6 Schur complement onto the platform's unknowns), or, as the reference
that the tests hold the structured test to, as a dense matrix (:mod:`.krawczyk_dense`): the
same theorem with the same enclosures, proving the same statements.

Every function here but the leaves is inlined into its caller (``inline="always"``): the proof
compiles as one unit, :func:`.proof_kernel.prove_packed`, that calls the enclosure
(:func:`.enclosure.enclose_into`), the per-leg algebra and the small leaves. numba links a
called compiled function into each caller's unit and optimises it there again, so each unit
between the entry and the enclosure cost a few seconds of the first compilation; an inlined
function is typed, lowered and optimised once per call site, so the leaves used at several sites
(:func:`_inside`, :func:`in_readings`, the dense reference's products) are called. The first
proven warm step took 107 s of CPU after installation with the fourteen functions above the
enclosure units of their own, 68 s so (``benchmarks/startup.py --cold``); the proofs are bit for
bit the same, and as fast.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .enclosure import JACOBIAN, enclose_into, enclosure_workspace
from .intervals import REL, up
from .kernels import copy_into
from .krawczyk_blocks import apply, krawczyk_blocks, setup, transform
from .krawczyk_blocks import workspace as workspace_blocks
from .krawczyk_dense import end_dense, krawczyk, precondition_dense, preconditioned_dense

MAX_TESTS = 32  # Krawczyk tests per path (each sub-interval that fails is halved)
V_ROWS = 26  # rows of the work's vectors: 0-20 scratch, 21 the unknowns' units, 22-23 a region's box, 24-25 HELD
HELD = 24  # the row whose first entry is 1 while the per-leg workspace holds a preconditioner (:func:`held_setup`)
HELD_AT = 25  # the row that holds the unknowns about which that preconditioner was built
# a held preconditioner is tried when every leg joint lies within this (rad, or model lengths) of where it was
# built: on trajectory A every one held within 0.01 proved, 4 % of those 0.03-0.1 away, and a test that fails
# costs a third of the proof (a thread that proves the steps of several fixtures of one hexapod, at their poses)
REUSE_WITHIN = 0.01
MIN_WIDTH = 1.0 / 64.0  # narrowest sub-interval of the readings path tried
INFLATIONS = 4  # boxes tried per test (epsilon-inflation)
FLOOR = 0.05  # a first box's radius per unknown, at least this fraction of the largest one (in units)
# the same for the whole path's first box (:func:`prove_whole`), sized by the start's distance alone: a
# start predicted from earlier samples (a tracker's guess) lies close to the result in unknowns that
# the readings path moves several times as far (at 0.05, a second box at most steps on trajectory A)
WHOLE_FLOOR = 0.35


@njit(cache=True)
def _path_term(Jm, Jr, dl, half, e, gm, gr):
    """The readings path's part of ``F(xc, S)``: ``J_held(xc, S) (dl (s - sm) + e)``, ``|s - sm| <= half``.

    Writes ``gm`` (nf,) = ``J_held``'s midpoint times ``dl`` (the path's tangent, to be taken over
    ``[-half, half]``) and ``gr`` (nf,) the radius of the rest; ``e`` the rounding of the held
    joints' midpoint ``hm``.
    """
    nf = gm.shape[0]
    for a in range(nf):
        gm[a], gr[a] = 0.0, 0.0
        for i in range(6):
            t = Jm[a, nf + i] * dl[i]
            gm[a] += t
            gr[a] += Jr[a, nf + i] * abs(dl[i]) * half + REL * abs(t) * half
            gr[a] += (abs(Jm[a, nf + i]) + Jr[a, nf + i]) * e[i]


@njit(cache=True)
def preconditioned_blocks(ws, rows, Fm, Fr, gm, gr, half, YFm, YFr, tm, tr):
    """``Y F(xc, S)`` as midpoint and radius, ``F in Fm +- (Fr + gr) + gm [-half, half]`` (:func:`_path_term`).

    ``tm``, ``tr`` (nf,) are scratch, and so is ``gr`` once read.
    """
    nf = Fm.shape[0]
    for a in range(nf):
        tr[a] = up(Fr[a] + gr[a])
    apply(ws, rows, Fm, tr, YFm, YFr)
    tr[:] = 0.0
    apply(ws, rows, gm, tr, tm, gr)
    for a in range(nf):
        YFr[a] = up(YFr[a] + up(abs(tm[a]) + gr[a]) * half)


@njit(cache=True, inline="always")
def held_setup(Jm, rows, work, xc):
    """:func:`.krawczyk_blocks.setup` into ``work``'s per-leg workspace, noting whether it now holds a preconditioner.

    Every preconditioner of the per-leg test is built here: a failed setup leaves the workspace
    partly written (its blocks no longer one matrix ``Y`` and the bound of ``|Y|``), and the note
    (``work``'s row :data:`HELD`) says so, so that :func:`prove_whole` never reuses it. ``xc``
    (nf,), the unknowns at the Jacobian's centre, is kept (row :data:`HELD_AT`).
    """
    ok = setup(Jm, rows, work[5])
    work[0][HELD][0] = 1.0 if ok else 0.0
    copy_into(work[0][HELD_AT], xc)
    return ok


@njit(cache=True, inline="always")
def _held_near(work, x):
    """Whether ``work`` holds a preconditioner built within :data:`REUSE_WITHIN` of ``x`` in every leg joint."""
    V = work[0]
    if not V[HELD][0] > 0.0:
        return False
    at, unit = V[HELD_AT], V[21]
    for a in range(x.shape[0] - 6):  # the chart's coordinates are about each test's own origin
        if not abs(x[a] - at[a]) <= REUSE_WITHIN * unit[a]:
            return False
    return True


def workspace(nf: int, rows: int) -> tuple:
    """The work arrays of :func:`prove_path` for ``nf`` unknowns and legs of ``rows`` closure rows."""
    return (
        # vectors: 21 scratch, the unknowns' units (StepProver), a region's centre and radius (prove_region)
        np.vstack((np.zeros((21, nf)), np.ones((1, nf)), np.zeros((V_ROWS - 22, nf)))),
        np.zeros((nf, nf + 6)),  # Jm: the Jacobian's enclosure (and the held joints' columns)
        np.zeros((nf, nf + 6)),  # Jr
        np.zeros((nf, nf)),  # Y: the dense test's preconditioner
        np.zeros((7, 6)),  # six-vectors (the last two: a region's readings box)
        workspace_blocks(rows),
        # legs of nf / 6 joints (6 (n - 1) + 6 unknowns); its Python function: the same arrays, without
        # compiling a function of a few np.zeros (1.5 s after installation) for a call from Python
        enclosure_workspace.py_func(nf // 6),
    )


@njit(cache=True, inline="always")
def _precondition_box(rows, structured, work, xc):
    """The preconditioner from the Jacobian midpoint in ``work`` (per leg, or dense) about ``xc``; False if singular."""
    V, Jm, Jr, Y, H, blocks, ew = work
    if structured:
        return held_setup(Jm, rows, work, xc)
    return precondition_dense(Y, Jm)


@njit(cache=True, inline="always")
def precondition(tables, T0, xc, hm, structured, work):
    """``F(xc, hm)`` (``work``'s first two rows) and the preconditioner from the Jacobian at ``xc``, ``hm``.

    The preconditioner is the inverse of the Jacobian's midpoint (the same at every box about
    ``xc``), applied leg by leg (``structured``, :mod:`.krawczyk_blocks`) or as a dense matrix;
    False when singular.
    """
    placements, motions, closure, held, rows = tables
    V, Jm, Jr, Y, H, blocks, ew = work
    zero, zero6 = V[4], H[1]
    zero[:] = 0.0
    zero6[:] = 0.0
    enclose_into(placements, motions, closure, held, rows, T0, xc, zero, hm, zero6, JACOBIAN[1], V[0], V[1], Jm, Jr, ew)
    return _precondition_box(rows, structured, work, xc)


@njit(cache=True, inline="always")
def _path_enclosure(tables, hm, dl, half, structured, work):
    """``Y F(xc, S)`` (``work``'s rows 7 and 8) with the Jacobian enclosure in ``work`` (see :func:`_path_term`)."""
    rows = tables[4]
    V, Jm, Jr, Y, H, blocks, ew = work
    Fm, Fr, gm, gr, YFm, YFr, tm, tr = V[0], V[1], V[5], V[6], V[7], V[8], V[9], V[10]
    e = H[0]
    for i in range(6):
        e[i] = REL * (abs(hm[i]) + abs(dl[i]))  # hm's rounding
    _path_term(Jm, Jr, dl, half, e, gm, gr)
    if structured:
        preconditioned_blocks(blocks, rows, Fm, Fr, gm, gr, half, YFm, YFr, tm, tr)
    else:
        ym, yr = preconditioned_dense(Y, Fm, Fr, gm, gr, half)
        copy_into(YFm, ym)
        copy_into(YFr, yr)


@njit(cache=True, inline="always")
def try_box(tables, T0, xc, rho, hm, hr, dl, half, structured, work, off, rad):
    """One Krawczyk test of the box ``xc +- rho`` over the held joints ``hm +- hr`` (after :func:`precondition`).

    The Jacobian over the box (whose held columns hold them over ``xc`` and the path) gives
    ``Y F(xc, S)`` and ``|I - Y J(X)| rho``; writes ``K = xc + off +- rad``; True when ``K``
    lies in the interior of the box.
    """
    placements, motions, closure, held, rows = tables
    V, Jm, Jr, Y, H, blocks, ew = work
    enclose_into(placements, motions, closure, held, rows, T0, xc, rho, hm, hr, JACOBIAN[1], V[2], V[3], Jm, Jr, ew)
    _path_enclosure(tables, hm, dl, half, structured, work)
    if structured:
        transform(Jm, rows, blocks)
        return krawczyk_blocks(V[7], V[8], Jr, rows, blocks, rho, off, rad)
    return krawczyk(V[7], V[8], Jm, Jr, rho, Y, off, rad)


@njit(cache=True, inline="always")
def prove_box(tables, T0, xc, spread, hm, hr, dl, half, off, rad, rho, structured, work):
    """Krawczyk with epsilon-inflation around ``xc``; ``spread`` (nf,) is a first radius to cover.

    The held joints run over ``hm +- hr``, the path ``l0 + s dl`` with ``|s - sm| <= half``.
    Writes the last box tried (``rho``), its ``K`` (``off``, ``rad``) and, in ``work``, the
    Jacobian's enclosure over it and the preconditioner; True when proven.
    """
    if not precondition(tables, T0, xc, hm, structured, work):
        return False
    V = work[0]
    YFm, YFr = V[7], V[8]
    nf = xc.shape[0]
    _path_enclosure(tables, hm, dl, half, structured, work)  # with J at xc and hm only: the first box's size
    unit = V[21]  # the unknowns' units: 1 for angles, the length scale for lengths
    big = 0.0
    for a in range(nf):  # room for the end box
        rho[a] = spread[a] + 4.0 * (abs(YFm[a]) + YFr[a]) + 1e-12 * (1.0 + abs(xc[a]))
        big = max(big, rho[a] / unit[a])
    for a in range(nf):  # room for the coupling |I - Y J(X)| rho of an unknown that hardly moves
        rho[a] = max(rho[a], FLOOR * big * unit[a])
    for _ in range(INFLATIONS):
        if try_box(tables, T0, xc, rho, hm, hr, dl, half, structured, work, off, rad):
            return True
        for a in range(nf):
            rho[a] = max(rho[a], 1.5 * (abs(off[a]) + rad[a]))
    return False


@njit(cache=True)
def _inside(c, off, rad, c2, rho2):
    """Whether the box ``c + off +- rad`` lies inside ``c2 +- rho2`` (rounding allowed for)."""
    for a in range(c.shape[0]):
        d = abs(c[a] - c2[a] + off[a])
        if not up(d + rad[a] + REL * (abs(c[a]) + abs(c2[a]) + abs(off[a]))) < rho2[a]:
            return False
    return True


@njit(cache=True, inline="always")
def prove_path(tables, T0, x0, x1, l0, l1, structured, work):
    """Prove that the readings path from ``x0`` (readings ``l0``) to ``x1`` (``l1``) stays on one assembly.

    Args:
        tables: ``(placements, motions, closure, held, rows)`` (:func:`.enclosure.enclose_into`).
        T0: (4, 4) the platform chart's origin.
        x0: (nf,) the start in the unknowns' coordinates.
        x1: (nf,) the result.
        l0: (6,) the held joints' values at the start (m).
        l1: (6,) the held joints' values at the result (m).
        structured: the per-leg test of :mod:`.krawczyk_blocks` (else the dense 36 x 36 one).
        work: :func:`workspace` ``(nf, rows)``, overwritten.

    Returns:
        ``(proven, tests, radius, parts)`` (``tests``: the path's): ``radius`` (nf,) bounds ``|x - x1|`` for the unique
        exact solution ``x`` the path ends at (rad for the joints and the chart's rotations, m for
        its translations); ``tests`` the Krawczyk tests run; ``parts`` the sub-intervals of the
        proven path. ``radius`` is a row of ``work``.
    """
    nf = x0.shape[0]
    V, H = work[0], work[4]
    zero = V[4]
    off, rad, rho, prev_c, prev_off, prev_rad, prev_rho = V[11], V[12], V[13], V[14], V[15], V[16], V[17]
    xc, spread = V[18], V[19]
    hm, hr, dl = H[2], H[3], H[4]
    for i in range(6):
        dl[i] = l1[i] - l0[i]
    tests, parts, s0, width = 0, 0, 0.0, 1.0
    while s0 < 1.0:
        s1 = min(1.0, s0 + width)
        sm, half = 0.5 * (s0 + s1), 0.5 * (s1 - s0)
        for i in range(6):
            hm[i] = l0[i] + sm * dl[i]
            hr[i] = up(half * abs(dl[i]) + REL * (abs(l0[i]) + abs(dl[i])))
        for a in range(nf):
            d = x1[a] - x0[a]
            xc[a] = x0[a] + sm * d
            spread[a] = half * abs(d)
        tests += 1
        ok = prove_box(tables, T0, xc, spread, hm, hr, dl, half, off, rad, rho, structured, work)
        zero[:] = 0.0
        if ok and s0 == 0.0:  # the start must lie in the first box
            ok = _inside(x0, zero, zero, xc, rho)
        if ok and s0 > 0.0:  # chained to the box before
            ok = _inside(prev_c, prev_off, prev_rad, xc, rho) or _inside(xc, off, rad, prev_c, prev_rho)
        if ok:
            copy_into(prev_c, xc)
            copy_into(prev_off, off)
            copy_into(prev_rad, rad)
            copy_into(prev_rho, rho)
            s0 = s1
            parts += 1
            width = min(1.0 - s0, 2.0 * width) if s0 < 1.0 else width
        else:
            if width <= MIN_WIDTH or tests >= MAX_TESTS:
                return False, tests, rho, 0
            width *= 0.5
        if tests >= MAX_TESTS and s0 < 1.0:
            return False, tests, rho, 0
    proven, _, radius, _ = _prove_end(tables, T0, x1, l1, prev_c, prev_rho, True, structured, work)
    return proven, tests, radius, parts if proven else 0


@njit(cache=True, inline="always")
def _prove_end(tables, T0, x1, l1, c, rho, fresh, structured, work):
    """The box about the result ``x1`` at ``s = 1`` alone, inside the last proven box ``c +- rho``.

    That box's Jacobian enclosure (over a larger box and parameter interval) and preconditioner
    are in ``work``; ``fresh``: enclose ``F(x1, l1)`` here (else ``work``'s first two rows hold
    it). Returns :func:`prove_path`'s ``(proven, 0, radius, parts)`` with ``parts`` 1.
    """
    nf = x1.shape[0]
    V, Jm, Jr, Y, H, blocks, ew = work
    Fm, Fr, zero, YFm, YFr = V[0], V[1], V[4], V[7], V[8]
    off, rad, box = V[11], V[12], V[20]
    placements, motions, closure, held, rows = tables
    zero[:] = 0.0
    if fresh:
        H[1][:] = 0.0
        enclose_into(placements, motions, closure, held, rows, T0, x1, zero, l1, H[1], JACOBIAN[0], Fm, Fr, Jm, Jr, ew)
    if structured:
        apply(blocks, rows, Fm, Fr, YFm, YFr)
    else:
        end_dense(Y, Fm, Fr, YFm, YFr)
    for a in range(nf):
        YFr[a] = up(YFr[a] + REL * abs(YFm[a]))
        box[a] = 2.0 * (abs(YFm[a]) + YFr[a]) + 1e-15 * (1.0 + abs(x1[a]))
    for _ in range(INFLATIONS):
        if not _inside(x1, zero, box, c, rho):
            break
        if structured:
            ok = krawczyk_blocks(YFm, YFr, Jr, rows, blocks, box, off, rad)
        else:
            ok = krawczyk(YFm, YFr, Jm, Jr, box, Y, off, rad)
        if ok:
            for a in range(nf):
                rad[a] = up(abs(off[a]) + rad[a])
            return True, 0, rad, 1
        for a in range(nf):
            box[a] = max(box[a], 1.5 * (abs(off[a]) + rad[a]))
    return False, 0, box, 0


@njit(cache=True, inline="always")
def _whole_test(rows, dl, e, structured, work, rho, off, rad):
    """:func:`prove_whole`'s test of the box ``x1 +- rho`` (its Jacobian enclosure and a preconditioner in ``work``).

    ``work``'s first two rows hold ``F(x1, l1)``; True when ``K`` lies in the interior of the box.
    """
    V, Jm, Jr, Y, H, blocks, ew = work
    Fm, Fr = V[0], V[1]
    gm, gr, YFm, YFr, tm, tr = V[5], V[6], V[7], V[8], V[9], V[10]
    Sm, Sr = V[14], V[15]
    _path_term(Jm, Jr, dl, 1.0, e, gm, gr)  # |s - 1| <= 1 for the Jacobian's radius
    for a in range(Fm.shape[0]):  # the midpoint moved to s = 1/2: F(x1, l1) - gm / 2, then gm (s - 1/2)
        Sm[a] = Fm[a] - 0.5 * gm[a]
        Sr[a] = up(Fr[a] + REL * (abs(Fm[a]) + abs(gm[a])))
    if structured:
        preconditioned_blocks(blocks, rows, Sm, Sr, gm, gr, 0.5, YFm, YFr, tm, tr)
        transform(Jm, rows, blocks)
        return krawczyk_blocks(YFm, YFr, Jr, rows, blocks, rho, off, rad)
    ym, yr = preconditioned_dense(Y, Sm, Sr, gm, gr, 0.5)
    copy_into(YFm, ym)
    copy_into(YFr, yr)
    return krawczyk(YFm, YFr, Jm, Jr, rho, Y, off, rad)


@njit(cache=True, inline="always")
def prove_whole(tables, T0, x0, x1, l0, l1, structured, work):
    """One Krawczyk test of the whole readings path on a box about the result ``x1``, then the end box.

    The path is taken from its end: ``l(s) = l1 + (s - 1) dl``, ``dl = l1 - l0`` (``l(0)`` is ``l0``
    up to the rounding of ``dl``, which the held joints' radius covers), and

        F(x1, l(s)) in F(x1, l1) + J_held(x1, S) dl (s - 1),   s - 1 in -1/2 +- 1/2,

    so that one enclosure of the residual at the result, ``F(x1, l1)``, serves the path's test
    and the end box's. The box ``x1 +- rho`` must hold the start ``x0``. Costs one enclosure of
    the residual and one of the Jacobian per box instead of :func:`prove_path`'s three; a step it
    does not prove is left to :func:`prove_path`.

    **The preconditioner** (any real matrix proves: :mod:`.krawczyk_blocks`). The per-leg test
    first tries the one ``work`` holds when it was built within :data:`REUSE_WITHIN` of ``x1``
    (:func:`held_setup`: the last test's, on a thread that proves step after step, built from a
    Jacobian a step away); only when the first box fails with it is it built afresh from the
    Jacobian's midpoint over that box, and the box tried again. The dense test builds its own
    every time.

    Returns:
        :func:`prove_path`'s ``(proven, tests, radius, parts)``.
    """
    nf = x0.shape[0]
    placements, motions, closure, held, rows = tables
    V, Jm, Jr, Y, H, blocks, ew = work
    Fm, Fr, zero = V[0], V[1], V[4]
    off, rad, rho = V[11], V[12], V[13]
    e, zero6, hm, hr, dl = H[0], H[1], H[2], H[3], H[4]
    zero[:] = 0.0
    zero6[:] = 0.0
    for i in range(6):
        dl[i] = l1[i] - l0[i]
        hm[i] = l1[i] - 0.5 * dl[i]
        hr[i] = up(0.5 * abs(dl[i]) + REL * (abs(l1[i]) + abs(dl[i])))
        e[i] = REL * (abs(l1[i]) + abs(dl[i]))  # l0 + dl against l1
    enclose_into(placements, motions, closure, held, rows, T0, x1, zero, l1, zero6, JACOBIAN[0], Fm, Fr, Jm, Jr, ew)
    unit = V[21]  # the unknowns' units: 1 for angles, the length scale for lengths
    big = 0.0
    for a in range(nf):
        rho[a] = 1.5 * abs(x1[a] - x0[a]) + 1e-12 * (1.0 + abs(x1[a]))
        big = max(big, rho[a] / unit[a])
    for a in range(nf):  # room for the coupling |I - Y J(X)| rho of an unknown that hardly moves
        rho[a] = max(rho[a], WHOLE_FLOOR * big * unit[a])
    for k in range(INFLATIONS):
        enclose_into(placements, motions, closure, held, rows, T0, x1, rho, hm, hr, JACOBIAN[1], V[2], V[3], Jm, Jr, ew)
        reused = k == 0 and structured and _held_near(work, x1)
        if k == 0 and not reused and not _precondition_box(rows, structured, work, x1):
            return False, 1, rho, 0
        ok = _whole_test(rows, dl, e, structured, work, rho, off, rad)
        if reused and not ok:  # the held preconditioner did not prove: build it from this box, try again
            if not _precondition_box(rows, structured, work, x1):
                return False, 1, rho, 0
            ok = _whole_test(rows, dl, e, structured, work, rho, off, rad)
        if ok and _inside(x0, zero, zero, x1, rho):
            proven, _, radius, parts = _prove_end(tables, T0, x1, l1, x1, rho, False, structured, work)
            return proven, 1, radius, parts
        for a in range(nf):
            rho[a] = max(rho[a], 1.5 * (abs(off[a]) + rad[a]))
    return False, 1, rho, 0


@njit(cache=True)
def in_readings(l, hm, hr):
    """Whether the readings ``l`` (6,) lie in the box ``hm +- hr`` (the rounding of ``l - hm`` allowed for)."""
    for i in range(6):
        d = abs(l[i] - hm[i])
        if not up(d + REL * d) <= hr[i]:
            return False
    return True


@njit(cache=True, inline="always")
def prove_region(tables, T0, x0, x1, l0, l1, hm, hr, work, c, rho):
    """One Krawczyk test over a box of readings ``P = hm +- hr`` (6,) on a box ``X = x1 +- rho`` (per-leg test).

    With the readings as interval parameters,

        K(X, P) = c - Y F(c, P) + (I - Y J(X, P)) (X - c),   F(c, P) in F(c, hm) + J_held(X, P) (P - hm),

    (the mean value theorem in the readings, ``c = x1``); ``K(X, P)`` inside ``X`` proves, for
    **every** reading ``l`` in ``P``, exactly one solution ``x(l)`` in ``X`` with the Jacobian
    regular there, so that ``x(l)`` is continuous on ``P`` (the implicit function theorem): any
    straight readings path within ``P`` (a convex box) from a start in ``X`` stays on that start's
    assembly. ``Y J_held`` is formed column by column (the solution's sensitivity to each
    reading), which keeps ``K`` as narrow as a path's test of the same width. Each try widens
    ``X`` (epsilon-inflation, :data:`INFLATIONS` boxes).

    Args:
        tables: as :func:`prove_path`.
        T0: (4, 4) the platform chart's origin.
        x0: (nf,) the step's start (must lie in ``X``).
        x1: (nf,) the step's result, the box's centre.
        l0: (6,) the step's start readings (m), in ``P``.
        l1: (6,) its end readings (m), in ``P``.
        hm: (6,) the readings box's midpoint (m).
        hr: (6,) its radius (m).
        work: :func:`workspace` ``(nf, rows)``: on success it holds the Jacobian's enclosure over
            ``X`` and ``P`` and its preconditioner (per leg), for :func:`_prove_end` at any
            reading in ``P`` and any box in ``X``.
        c: (nf,) written: the box's centre.
        rho: (nf,) written: its radius.

    Returns:
        True when proven.
    """
    nf = x1.shape[0]
    placements, motions, closure, held, rows = tables
    V, Jm, Jr, Y, H, blocks, ew = work
    Fm, Fr, zero, YFm, YFr = V[0], V[1], V[4], V[7], V[8]
    col, t, cm, cr, acc, tot, off, rad = V[5], V[6], V[9], V[10], V[14], V[15], V[11], V[12]
    zero6 = H[1]
    zero[:] = 0.0
    zero6[:] = 0.0
    if not (in_readings(l0, hm, hr) and in_readings(l1, hm, hr)):
        return False
    copy_into(c, x1)
    enclose_into(placements, motions, closure, held, rows, T0, c, zero, hm, zero6, JACOBIAN[1], Fm, Fr, Jm, Jr, ew)
    if not held_setup(Jm, rows, work, c):
        return False
    apply(blocks, rows, Fm, Fr, YFm, YFr)  # Y F(c, hm): the same at every box
    unit = V[21]
    for k in range(INFLATIONS + 1):
        # Y J_held(X, P) (P - hm): each reading's column through Y, then |Y| (rad J_held) hr
        acc[:] = 0.0
        for i in range(6):
            for a in range(nf):
                col[a] = Jm[a, nf + i]
            apply(blocks, rows, col, zero, cm, cr)
            for a in range(nf):
                acc[a] += (abs(cm[a]) + cr[a]) * hr[i]
        for a in range(nf):
            s = 0.0
            for i in range(6):
                s += Jr[a, nf + i] * hr[i]
            t[a] = up(s)
        apply(blocks, rows, zero, t, cm, cr)
        for a in range(nf):
            tot[a] = up(up(YFr[a] + up(acc[a] + REL * acc[a])) + cr[a])
        if k == 0:  # the first box (from the Jacobian at c): room for the readings box and the step
            big = 0.0
            for a in range(nf):
                rho[a] = 2.0 * (abs(YFm[a]) + tot[a]) + 1.5 * abs(x1[a] - x0[a]) + 1e-12 * (1.0 + abs(x1[a]))
                big = max(big, rho[a] / unit[a])
            for a in range(nf):
                rho[a] = max(rho[a], FLOOR * big * unit[a])
        else:
            transform(Jm, rows, blocks)
            if krawczyk_blocks(YFm, tot, Jr, rows, blocks, rho, off, rad) and _inside(x0, zero, zero, c, rho):
                return True
            for a in range(nf):
                rho[a] = max(rho[a], 1.5 * (abs(off[a]) + rad[a]))
        enclose_into(placements, motions, closure, held, rows, T0, c, rho, hm, hr, JACOBIAN[1], V[2], V[3], Jm, Jr, ew)
    return False


@njit(cache=True, inline="always")
def prove_in_region(tables, T0, x0, x1, l0, l1, hm, hr, work, c, rho):
    """The end box of a step whose readings lie in a proven region (:func:`prove_region`) and starts in its box.

    ``work`` holds that region's Jacobian enclosure and preconditioner: no path test is run.
    Returns :func:`prove_path`'s ``(proven, tests, radius, parts)`` (``tests`` 0).
    """
    zero = work[0][4]
    zero[:] = 0.0
    if not (in_readings(l0, hm, hr) and in_readings(l1, hm, hr) and _inside(x0, zero, zero, c, rho)):
        return False, 0, rho, 0
    return _prove_end(tables, T0, x1, l1, c, rho, True, True, work)

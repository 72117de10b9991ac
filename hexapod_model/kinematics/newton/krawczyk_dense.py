"""The dense Krawczyk test: the reference for the per-leg test of :mod:`.krawczyk_blocks`.

The preconditioner ``Y`` is the inverse of the whole Jacobian's midpoint (36 x 36 for 6-D
closures) and ``I - Y J(X)`` is formed as a dense interval matrix (:func:`krawczyk`); the
rounding is bounded as in :mod:`.intervals`. :func:`.krawczyk.prove_path` runs it when asked
for the dense test.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .intervals import REL, up
from .kernels import copy_into
from .linalg import lu_factor_in_place, lu_solve_in_place


@njit(cache=True)
def krawczyk(YFm, YFr, Jm, Jr, rho, Y, off, rad):
    """One Krawczyk test of the box ``xc +- rho``.

    ``YFm +- YFr`` encloses ``Y F(xc, S)``, ``Jm +- Jr`` (its first nf columns) ``J(X, S)``; ``Y``
    is the preconditioner (an approximate inverse of the Jacobian at ``xc``). Writes
    ``K = xc + off +- rad`` and returns True when ``K`` lies in the interior of the box.
    """
    nf = YFm.shape[0]
    aY = np.abs(Y)
    Jf = np.ascontiguousarray(Jm[:, :nf])
    YJ = Y @ Jf
    Cr = aY @ (Jr[:, :nf] + REL * np.abs(Jf))  # J's radius and the product's rounding
    ok = True
    for a in range(nf):
        s = 0.0
        for b in range(nf):
            c = (1.0 if a == b else 0.0) - YJ[a, b]
            s += (abs(c) + up(Cr[a, b] + REL * (abs(YJ[a, b]) + 1.0))) * rho[b]
        off[a] = -YFm[a]
        rad[a] = up(up(s) + YFr[a])
        if not up(abs(off[a]) + rad[a]) < rho[a]:
            ok = False
    return ok


@njit(cache=True)
def preconditioned_dense(Y, Fm, Fr, gm, gr, half):
    """``Y F(xc, S)`` as midpoint and radius, by the mean-value form along the readings path.

    ``F(xc, l(s)) in F(xc, hm) + J_held(xc, S) (dl (s - sm) + e)`` (:mod:`.krawczyk`): ``Y J_held
    dl`` is about the path's tangent, so the readings' change is not spread over every unknown
    as ``|Y| |F|`` would.
    """
    nf = Fm.shape[0]
    aY = np.abs(Y)
    YFm = Y @ Fm
    YFr = aY @ (Fr + REL * np.abs(Fm))
    Yg = Y @ gm
    YFr += aY @ gr + (np.abs(Yg) + REL * (aY @ np.abs(gm))) * half
    for a in range(nf):
        YFr[a] = up(YFr[a] + REL * abs(YFm[a]))
    return YFm, YFr


@njit(cache=True)
def inverse_into(J, Y):
    """``Y = J^-1`` by the pivoted LU of :mod:`.linalg` (NaN when singular; any matrix serves as ``Y``).

    Written element by element, not by a slice assignment ``Y[:, :] = ...``: that brings numba's
    broadcast check and its error message's string formatting into the proof's compiled unit
    (:func:`.kernels.copy_into`).
    """
    nf = J.shape[0]
    LU = J.copy()
    piv = np.empty(nf, dtype=np.int64)
    if lu_factor_in_place(LU, piv, nf) == 0.0:
        Y.fill(np.nan)
        return
    e = np.empty(nf)
    for b in range(nf):
        for a in range(nf):
            e[a] = 1.0 if a == b else 0.0
        lu_solve_in_place(LU, piv, e, nf)  # column b of J^-1
        for a in range(nf):
            Y[a, b] = e[a]


@njit(cache=True)
def precondition_dense(Y, Jm):
    """``Y = Jm[:, :nf]^-1`` (:func:`inverse_into`) in place; False when singular.

    A called function: the proof inlines its callers at several sites, and numba would type,
    lower and optimise the inverse's NumPy expressions once per site.
    """
    nf = Y.shape[0]
    inverse_into(Jm[:, :nf], Y)
    return np.all(np.isfinite(Y))


@njit(cache=True)
def end_dense(Y, Fm, Fr, YFm, YFr):
    """``Y F(x1, l1)`` in place: midpoint ``YFm``, radius ``YFr`` (before the product's rounding).

    A called function, as :func:`precondition_dense` is.
    """
    copy_into(YFm, Y @ Fm)
    copy_into(YFr, np.abs(Y) @ (Fr + REL * np.abs(Fm)))

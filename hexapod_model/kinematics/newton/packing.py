"""The fast path's tables and work buffers, packed in four flat arrays, and its per-call settings.

A compiled call pays for every argument it unboxes (tens of nanoseconds each, an array in a
tuple included); the Newton iteration needs about forty arrays and a dozen values. The constants
of one solver (the chains, the held joints, the prismatic joints, the joint limits, home) and its
buffers travel as four flat arrays (integer tables, float tables, float and integer work buffers)
that the unpack functions cut into views again inside the compiled code, with no copy
(:func:`unpack_constants`: what a solve reads beside the iteration). The same functions build
the views that :class:`Packed` fills from Python, so the layout is written once.
What changes from call to call travels in one small float array, ``settings`` (:data:`SETTINGS`
entries), owned by the solver and filled in place.

Layout (``n`` joints per leg, ``nv`` velocities, ``nf`` free velocities, ``nl`` limited joints,
all C order):

* ``ints``: header ``(n, nv, nf, platform_q, schur, nl, oc, fc)`` (``oc``, ``fc``: where
  ``prismatic_q`` starts in ``ints`` and ``lower`` in ``floats``), ``leg_q`` (6, n), ``leg_v`` (6, n),
  ``platform_v`` (6,), ``held_pos`` (6,), ``colmap`` (nv,), ``free_v`` (nf,), ``kinds`` (6, n)
  (:attr:`.legs.ChainTables.kinds`), then ``prismatic_q`` (6,) (configuration index of each leg's
  prismatic joint) and ``limited`` (nl,) (the configuration indices the limit check reads);
* ``floats``: the solver's constants ``(max_step, singular_ratio, theta_max, theta_floor,
  one_step, length_scale)`` (:data:`LENGTH_SCALE`: the geometry's, :func:`.solver.size_of`),
  the free velocities' ``step_weights`` (nf,) (:func:`.solver.velocity_weights`: the step's
  entries in metres count divided by the length scale), then ``placements`` (6, n, 4, 4),
  ``motions`` (6, n, 6), ``closure`` (12, 4, 4), ``home`` (4, 4) (:class:`.chains.ChainTables`),
  then ``lower`` (nl,), ``upper`` (nl,) of the limited joints and the limit check's ``slack`` (1,);
* ``work``: ``J`` (6, nv), ``R`` (12, 3, 3), ``p`` (12, 3),
  ``E`` (6, 3, 3), ``r`` (6n,), ``x`` (nf,), ``dv`` (nv,), ``G`` (6n, nf), ``LB`` (6, n, n),
  ``A`` (6, n, 6), ``M`` (6, 6), ``nb``, ``wb`` (6,), ``state`` (2,): the determinant sign and
  condition bound of the last Schur step (``NewtonSolver.sign``, ``kappa``);
* ``iwork``: ``PB`` (6, n), ``pm`` (6,);
* ``settings`` (float): ``(tol, max_iter, sign, scale, certify, finish, given)`` then the six
  prismatic joint values to hold when ``given`` is 1 (:data:`SETTINGS` in all; flags as 0 or 1).
  ``given`` 2: the values to hold are the entry's ``offset`` argument (six readings, no homotopy),
  checked first against the stroke that follows in ``settings``: its lower (6,) and upper (6,)
  bounds and their slack (1,) (:data:`STROKE` entries more).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .legs import ChainTables
from .views import view

HEADER = 8
FHEADER = 6
LENGTH_SCALE = 5  # index of the geometry's length scale in ``floats`` (after the five step constants)
#: entries of the per-call ``settings`` array: seven values, then six joint values
SETTINGS = 13
#: entries after :data:`SETTINGS` of a solve that checks its readings against the stroke (``given`` 2)
STROKE = 13
WORK_NAMES = tuple("J R p E r x dv G LB A M nb wb state".split())
#: positions in :func:`unpack_work`'s views (module constants: numba reads them as compile-time indices)
WORK_R, WORK_STATE = WORK_NAMES.index("r"), WORK_NAMES.index("state")


# Each view is ``buf[o : o + size]`` with its shape (:func:`.views.view`), ``o`` advancing: written out
# rather than through a shared function so that Packed can run the same functions as plain Python
# (``.py_func``) to fill the tables, without compiling them.
@njit(cache=True, inline="always")
def unpack_ints(ints):
    """Views ``(leg_q, leg_v, platform_v, held_pos, colmap, free_v, kinds)`` of the integer tables, and their end."""
    n, nv, nf = ints[0], ints[1], ints[2]
    o = HEADER
    leg_q = view(ints, o, (6, n))
    o += 6 * n
    leg_v = view(ints, o, (6, n))
    o += 6 * n
    platform_v, held_pos = ints[o : o + 6], ints[o + 6 : o + 12]
    o += 12
    colmap = ints[o : o + nv]
    o += nv
    free_v = ints[o : o + nf]
    o += nf
    kinds = view(ints, o, (6, n))
    return (leg_q, leg_v, platform_v, held_pos, colmap, free_v, kinds), o + 6 * n


@njit(cache=True, inline="always")
def unpack_floats(ints, floats):
    """Views ``(placements, motions, closure, home)`` of the float tables, and their end."""
    n = ints[0]
    o = FHEADER + ints[2]  # after the step weights
    placements = view(floats, o, (6, n, 4, 4))
    o += 96 * n
    motions = view(floats, o, (6, n, 6))
    o += 36 * n
    closure = view(floats, o, (12, 4, 4))
    home = view(floats, o + 192, (4, 4))
    return (placements, motions, closure, home), o + 208


@njit(cache=True)  # called, not inlined: numba's inlining costs compile time at every call site
def unpack_constants(ints, floats):
    """Views ``(prismatic_q, limited, lower, upper)``, the value ``slack`` and ``home`` (4, 4), and the tables' ends.

    What a solve reads beside the iteration: the joints a reading sets, the limit check, the
    platform's home placement (the view of :func:`unpack_floats`).
    """
    nl, o, f = ints[5], ints[6], ints[7]  # after the tables of unpack_ints and unpack_floats
    prismatic_q, limited = ints[o : o + 6], ints[o + 6 : o + 6 + nl]
    lower, upper = floats[f : f + nl], floats[f + nl : f + 2 * nl]
    home = view(floats, f - 16, (4, 4))
    return (prismatic_q, limited, lower, upper, floats[f + 2 * nl], home), (o + 6 + nl, f + 2 * nl + 1)


@njit(cache=True, inline="always")
def unpack_work(ints, work):
    """Views of the float work buffers (see the module docstring), and their end."""
    n, nv, nf = ints[0], ints[1], ints[2]
    J = view(work, 0, (6, nv))
    o = 6 * nv
    R = view(work, o, (12, 3, 3))
    p = view(work, o + 108, (12, 3))
    E = view(work, o + 144, (6, 3, 3))
    o += 198
    r = work[o : o + 6 * n]
    o += 6 * n
    x = work[o : o + nf]
    o += nf
    dv = work[o : o + nv]
    o += nv
    G = view(work, o, (6 * n, nf))
    o += 6 * n * nf
    LB = view(work, o, (6, n, n))
    o += 6 * n * n
    A = view(work, o, (6, n, 6))
    o += 36 * n
    M = view(work, o, (6, 6))
    nb, wb = work[o + 36 : o + 42], work[o + 42 : o + 48]
    state = work[o + 48 : o + 50]
    return (J, R, p, E, r, x, dv, G, LB, A, M, nb, wb, state), o + 50


@njit(cache=True, inline="always")
def unpack_iwork(ints, iwork):
    """Views ``(PB, pm)`` of the integer work buffers, and their end."""
    n = ints[0]
    return (view(iwork, 0, (6, n)), iwork[6 * n : 6 * n + 6]), 6 * n + 6


@njit(cache=True, inline="always")
def unpack(ints, floats, work, iwork):
    """The views of all four arrays, ``(tables, frames, buffers, pivots)``: those of the four functions above.

    For a compiled loop that runs the iteration again and again (:func:`.iteration.iterate_schur`
    per row of a batch, per substep of the readings path): made once and passed to each call.
    An entry called from Python makes its own: 32 views (:func:`.views.view`: a pointer, a shape
    and strides each, and the buffer's reference count), a small part of a warm solve.
    """
    return (
        unpack_ints(ints)[0],
        unpack_floats(ints, floats)[0],
        unpack_work(ints, work)[0],
        unpack_iwork(ints, iwork)[0],
    )


class Packed:
    """The four arrays of one solver (one thread, one set of held joints).

    Args:
        tables: the leg chains read from the Pinocchio model.
        constants: ``(max_step, singular_ratio, theta_max, theta_floor, one_step, length_scale)`` of the solver.
        step_weights: (nf,) weight of each free velocity in the step's size (:func:`.solver.velocity_weights`).
        schur: direct kinematics (Schur elimination); else inverse kinematics (blocks).
        held_pos: held joint of each leg (direct kinematics) or None.
        colmap: column of each velocity in the reduced Jacobian (-1 when held).
        free_v: the free velocities.
        nv: velocity dimension of the model.
        prismatic_q: configuration index of each leg's prismatic joint.
        limits: ``(limited q indices, lower, upper, slack)`` of the joint-limit check.
    """

    def __init__(
        self,
        tables: ChainTables,
        constants: tuple,
        step_weights: np.ndarray,
        schur: bool,
        held_pos: np.ndarray | None,
        colmap: np.ndarray,
        free_v: np.ndarray,
        nv: int,
        prismatic_q: np.ndarray,
        limits: tuple,
    ):
        n, nf, nl = tables.placements.shape[1], free_v.size, len(limits[0])
        self.ints = np.zeros(HEADER + 18 * n + 12 + nv + nf + 6 + nl, dtype=np.int64)
        self.ints[:6] = (n, nv, nf, tables.platform_q, int(schur), nl)
        self.floats = np.zeros(FHEADER + nf + 6 * n * 22 + 12 * 16 + 16 + 2 * nl + 1)
        self.floats[:FHEADER] = constants
        self.floats[FHEADER : FHEADER + nf] = step_weights
        self.work = np.zeros(6 * n * (1 + nf + n + 6) + 6 * nv + 108 + 36 + 54 + nf + nv + 36 + 12 + 2)
        self.iwork = np.zeros(6 * n + 6, dtype=np.int64)
        # the compiled functions' Python source: the same layout, nothing compiled here
        (leg_q, leg_v, platform_v, held, cmap, free, kinds), self.ints[6] = unpack_ints.py_func(self.ints)
        (placements, motions, closure, home), self.ints[7] = unpack_floats.py_func(self.ints, self.floats)
        (prismatic, limited, lower, upper, _, _), (end_i, end_f) = unpack_constants.py_func(self.ints, self.floats)
        views, end_w = unpack_work.py_func(self.ints, self.work)
        (PB, pm), end_iw = unpack_iwork.py_func(self.ints, self.iwork)
        ends = (end_i, end_f, end_w, end_iw)
        if ends != (self.ints.size, self.floats.size, self.work.size, self.iwork.size):
            raise RuntimeError(f"packing layout mismatch: {ends}")  # a bug, never bad input
        leg_q[:], leg_v[:], platform_v[:], kinds[:] = tables.leg_q, tables.leg_v, tables.platform_v, tables.kinds
        held[:] = -1 if held_pos is None else held_pos
        cmap[:], free[:] = colmap, free_v
        placements[:], motions[:], closure[:], home[:] = tables.placements, tables.motions, tables.closure, tables.home
        prismatic[:], limited[:], lower[:], upper[:], self.floats[-1] = prismatic_q, *limits
        #: ``(ints, floats, work, iwork)``: the arguments of the compiled functions
        self.arrays = (self.ints, self.floats, self.work, self.iwork)
        #: the work buffers by name (views on ``work`` and ``iwork``)
        self.views = dict(zip(WORK_NAMES, views)) | {"PB": PB, "pm": pm}

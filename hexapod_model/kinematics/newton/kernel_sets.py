"""Which kernels a solver runs: numba-compiled (:mod:`.kernels`, :mod:`.linalg`) or NumPy (:mod:`.numpy_kernels`).

The compiled kernels are the fast path (a warm direct-kinematics solve in tens of microseconds)
but numba costs about a second and 130 MB to import and initialise in every process, and the
first run after installation compiles them (tens of seconds). The NumPy kernels run the same
equations with no compilation, several times slower per solve: the right choice for a short job.
Only :func:`kernel_set` ``(compiled=True)`` imports numba.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import NamedTuple


class KernelSet(NamedTuple):
    """The kernels of the Newton step, the limit checks and the free-flyer conversions (same signatures)."""

    compiled: bool
    closure_residual: Callable
    jacobian: Callable
    scatter_step: Callable
    shift_residual: Callable
    schur_solve: Callable
    block_solve: Callable
    lu_factor: Callable
    lu_apply: Callable
    first_outside: Callable
    first_outside_at: Callable
    rigid_error: Callable
    pose_to_xyzquat: Callable
    xyzquat_to_pose: Callable
    copied: Callable


_LINALG = ("block_solve", "lu_factor", "lu_apply")  # from .linalg, schur_solve from .structured


@functools.cache
def kernel_set(compiled: bool = True) -> KernelSet:
    """The numba kernels (``compiled``, imports numba) or their NumPy twins."""
    import importlib

    if compiled:  # the kernels compile on their first call
        from .first_compile import collect_less

        collect_less()
    k = importlib.import_module(".kernels" if compiled else ".numpy_kernels", __package__)
    la = importlib.import_module(".linalg" if compiled else ".numpy_kernels", __package__)
    st = importlib.import_module(".structured" if compiled else ".numpy_kernels", __package__)
    lie = importlib.import_module("hexapod_model.lie.compiled" if compiled else "hexapod_model.lie.se3")
    home = {f: la for f in _LINALG} | {"schur_solve": st, "pose_to_xyzquat": lie, "xyzquat_to_pose": lie}
    return KernelSet(compiled, *(getattr(home.get(f, k), f) for f in KernelSet._fields[1:]))

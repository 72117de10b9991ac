"""Shared fixtures: one loaded Hexapod per preset for the whole session; the chromium and cell markers."""

from __future__ import annotations

import functools
import importlib.metadata
import re
import shutil

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.kinematics.batch import PROOF_STEP
from hexapod_model.viz.render import CHROMIUM_NAMES

#: the presets solved from six readings (those with redundant sensors: tests/kinematics/test_redundant.py)
PRESET_NAMES = [n for n in hm.PRESETS if not hm.get_preset(n).redundant]
HAVE_CHROMIUM = any(shutil.which(name) for name in CHROMIUM_NAMES)


def _have_cell() -> bool:
    try:
        importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return False
    return True


#: the UR10 of the robot cell (example-robot-data, ~400 MB; the `cell` extra, in `test`)
HAVE_CELL = _have_cell()
CELL_HINT = "needs example-robot-data (the UR10, ~400 MB): pip install -e '.[cell]'"


@functools.cache
def hexapod(name: str) -> hm.Hexapod:
    """Cached Hexapod of preset ``name`` (solver buffers are reused across tests)."""
    return hm.Hexapod.from_preset(name)


@functools.cache
def limits_only(name: str) -> hm.Hexapod:
    """Cached Hexapod of preset ``name`` without the body check: the stroke and joint limits alone decide."""
    return hm.Hexapod.from_preset(name, check_body=False)


_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?|\b(?:nan|inf)\b")
PATH_TOL = 1e-12  # m and rad: two code paths of one solve (compiled, NumPy, one call, batch) agree to this


def assert_same_message(a: str, b: str, numbers: bool = True) -> None:
    """The same words; the numbers (printed to 2-3 digits) to 1e-2 relative when ``numbers``."""
    assert _NUMBER.sub("#", a) == _NUMBER.sub("#", b)
    if numbers:
        x, y = ([float(v) for v in _NUMBER.findall(m)] for m in (a, b))
        np.testing.assert_allclose(x, y, rtol=1e-2, atol=0)


def assert_same_solution(a: hm.Solution, b: hm.Solution, tol: float = PATH_TOL) -> None:
    """``a`` and ``b``, one problem solved by two code paths: the same answer to rounding.

    Status, iterations, flags, determinant sign, candidate count and the message's words exactly;
    poses, configurations, readings and candidates to ``tol`` (m, rad), the residual to ``tol``,
    the Jacobian to ``1e3 tol`` (its entries are lever arms, up to ~1 m), the message's numbers to
    1e-2 relative (printed to 2-3 digits). The last iterate of a diverging Newton
    (``max_iterations`` after several steps) magnifies the paths' rounding: its numbers are not
    compared.
    """
    assert (a.status, a.iterations, a.flags, a.det_sign, len(a.candidates)) == (
        b.status,
        b.iterations,
        b.flags,
        b.det_sign,
        len(b.candidates),
    )
    diverged = a.status == "max_iterations" and a.iterations > 1
    assert_same_message(a.message, b.message, numbers=not diverged)
    if diverged:
        return
    for x, y in zip((a.pose, a.q, a.lengths, *a.candidates), (b.pose, b.q, b.lengths, *b.candidates)):
        np.testing.assert_allclose(x, y, rtol=0, atol=tol)
    np.testing.assert_allclose(a.residual, b.residual, rtol=0, atol=tol)
    assert (a.jacobian is None) == (b.jacobian is None)
    if a.jacobian is not None:
        np.testing.assert_allclose(a.jacobian, b.jacobian, rtol=0, atol=1e3 * tol)


@pytest.fixture(params=PRESET_NAMES)
def preset_hexapod(request) -> hm.Hexapod:
    return hexapod(request.param)


def pytest_collection_modifyitems(config, items):
    """Tests marked ``chromium`` (``cell``) are skipped, with the reason, without the browser (the UR10's data)."""
    chromium = pytest.mark.skip(reason="needs headless Chromium: apt-get install chromium (.ci/run installs it)")
    cell = pytest.mark.skip(reason=CELL_HINT)
    for item in items:
        if "chromium" in item.keywords and not HAVE_CHROMIUM:
            item.add_marker(chromium)
        if "cell" in item.keywords and not HAVE_CELL:
            item.add_marker(cell)


def batch_rule_forward(hexa: hm.Hexapod, prove: bool = True):
    """``forward`` as a batch row is solved (``forward(check=False)`` signature): with ``prove``
    (the batches' default) ``forward`` itself, a warm row with its Krawczyk proof; without, the
    certificate's checks and the proof of a warm row near a singularity only (docs/solver.md).
    A row's step longer than ``PROOF_STEP`` keeps the certificate's checks in both."""

    def solve(lengths, guess=None, check=False):
        if prove and guess is not None:  # a step within PROOF_STEP with its proof, a longer one as without prove
            start, held = np.asarray(getattr(guess, "q", guess), dtype=float), hexa.closed_loop.prismatic_q
            if np.abs(hexa.joints_of(np.asarray(lengths, dtype=float)) - start[held]).max() <= PROOF_STEP:
                return hexa.forward(lengths, guess=guess, check=check)
        sol = hexa.forward(lengths, guess=guess, check=check, prove=False)
        return hexa.prove_step(guess, sol) if guess is not None and "near_singular" in sol.flags else sol

    return solve

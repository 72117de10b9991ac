"""Identifiability on Jacobians whose answer is known: unseen, weak and gauge-pinned parameters are held."""

from __future__ import annotations

import numpy as np
import pytest

from hexapod_model.calibration.identifiability import analyse, frame_free, free_basis

NAMES = tuple(f"p{k}" for k in range(8))


def _jacobians(seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(60, 8) geometry rows, well determined (singular values > 10), and (60, 12) frame rows."""
    rng = np.random.default_rng(seed)
    frames = rng.normal(size=(60, 12))
    J = frame_free(rng.normal(size=(60, 8)), frames)  # the frames' span out: the analysis sees J as is
    return 10 * J / np.linalg.svd(J, compute_uv=False)[-1], frames


def test_frame_free_removes_the_frames_span():
    J, frames = _jacobians()
    out = frame_free(J + frames @ np.random.default_rng(1).normal(size=(12, 8)), frames)
    np.testing.assert_allclose(frames.T @ out, 0.0, atol=1e-10)
    np.testing.assert_allclose(out, J, atol=1e-10)  # what the frames cannot explain is kept


def test_free_basis_is_orthonormal_meets_the_constraints_and_the_holds():
    C = np.random.default_rng(2).normal(size=(3, 8))
    N = free_basis(C, (1, 6), 8)
    assert N.shape == (8, 3)
    np.testing.assert_allclose(N.T @ N, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(C @ N, 0.0, atol=1e-12)
    np.testing.assert_allclose(N[[1, 6]], 0.0, atol=1e-14)


def test_well_determined_data_hold_nothing():
    J, frames = _jacobians()
    ana = analyse(J, frames, np.zeros((0, 8)), NAMES)
    assert ana.held == () and ana.combinations == ()
    np.testing.assert_allclose(ana.spectrum, np.linalg.svd(J, compute_uv=False), rtol=1e-10)


def test_unseen_weak_and_pinned_parameters_are_held_and_named():
    J, frames = _jacobians()
    J[:, 2] = 0.0  # p2: the data do not see it
    J[:, 5] *= 0.05 / np.linalg.norm(J[:, 5])  # p5: seen, 1-sigma about 20 of its expected magnitudes
    C = np.eye(8)[[7]] + 0.0  # p7: fixed by the convention alone
    ana = analyse(J, frames, C, NAMES, max_sigma=1.0, held=(0,))
    assert set(ana.held) == {0, 2, 5, 7}
    by_name = {c.held: c for c in ana.combinations}
    assert set(by_name) == {"p2", "p5", "p7"}  # p0 was asked for: no combination of its own
    assert not np.isfinite(by_name["p2"].sigma) and "not seen by the data" in by_name["p2"].describe()
    assert by_name["p5"].sigma > 1.0 and "p5 held at nominal" in by_name["p5"].describe()
    assert by_name["p7"].sigma == 0.0 and "frame convention" in by_name["p7"].describe()
    free = [k for k in range(8) if k not in ana.held]
    np.testing.assert_allclose(ana.basis[list(ana.held)], 0.0, atol=1e-12)
    assert np.linalg.matrix_rank(ana.basis[free]) == len(free) == ana.basis.shape[1]
    # what is left is determined: every combination's 1-sigma within max_sigma
    assert np.all(1.0 / np.linalg.svd(J @ ana.basis, compute_uv=False) <= 1.0)


def test_of_two_parameters_that_move_together_one_is_held_with_the_other_named():
    J, frames = _jacobians(3)
    J[:, 4] = J[:, 3]  # p3 and p4 have the same effect: only p3 + p4 is seen
    ana = analyse(J, frames, np.zeros((0, 8)), NAMES)
    assert len(ana.held) == 1 and ana.held[0] in (3, 4)
    (combo,) = ana.combinations
    other = "p4" if combo.held == "p3" else "p3"
    terms = dict(combo.terms)
    assert terms[combo.held] == 1.0 and terms[other] == pytest.approx(-1.0, abs=1e-9)
    assert not np.isfinite(combo.sigma)

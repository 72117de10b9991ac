"""Pose planning and k-fold validation: their bad input, the folds, the verdict's decision."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.calibration.planning import plan_poses
from hexapod_model.calibration.validation import IMPROVEMENT_SIGMAS, Validation, folds_of, verdict


def test_a_plan_too_small_or_from_too_few_candidates_is_refused():
    nominal = hm.get_preset("reference")
    with pytest.raises(hm.InputError, match=r"--plan.*\b25\b.*78 unknowns need at least 26 poses"):
        plan_poses(nominal, 25, candidates=100)
    with pytest.raises(hm.InputError, match=r"candidates.*\b30\b.*at least as many candidates as poses \(40\)"):
        plan_poses(nominal, 40, candidates=30)


def test_a_plan_outside_the_workspace_says_how_many_candidates_are_reachable():
    with pytest.raises(hm.InputError, match=r"only \d+ of 30 candidate poses are reachable"):
        plan_poses(hm.get_preset("reference"), 26, candidates=30, translation=0.6, angle_deg=80.0)


@pytest.mark.parametrize("n, k", [(10, 3), (41, 5), (7, 7)])
def test_folds_are_a_seeded_split_of_nearly_equal_sizes(n, k):
    fold = folds_of(n, k, seed=4)
    sizes = np.bincount(fold, minlength=k)
    assert fold.shape == (n,) and sizes.sum() == n and sizes.max() - sizes.min() <= 1 and len(sizes) == k
    np.testing.assert_array_equal(fold, folds_of(n, k, seed=4))
    assert any(not np.array_equal(folds_of(n, k, seed=s), fold) for s in range(5, 10))


@pytest.mark.parametrize("n, k", [(10, 1), (5, 6), (10, 0)])
def test_folds_out_of_range_are_named(n, k):
    with pytest.raises(hm.InputError, match=rf"folds.*\b{k}\b.*2 <= folds <= poses \({n}\)"):
        folds_of(n, k)


def _validation(before_mm, after_mm, before_deg, after_deg) -> Validation:
    arrays = [np.asarray(a, dtype=float) for a in (before_mm, after_mm, before_deg, after_deg)]
    return Validation(2, np.arange(arrays[0].size) % 2, (arrays[0], arrays[2]), (arrays[1], arrays[3]))


def test_the_verdict_needs_a_drop_beyond_its_uncertainty():
    rng = np.random.default_rng(11)
    before = rng.uniform(0.4, 0.6, 30)
    rot = rng.uniform(0.01, 0.02, 30)
    after = before - 0.3 + rng.normal(0, 0.01, 30)
    clear = verdict(_validation(before, after, rot, rot))
    assert clear.better and clear.before_mm == pytest.approx(before.mean()) and "better beyond" in clear.describe()
    assert clear.after_mm == pytest.approx(after.mean())
    d = before - after  # the paired differences' standard error, as many times as the verdict states
    assert clear.uncertainty_mm == pytest.approx(IMPROVEMENT_SIGMAS * np.std(d, ddof=1) / np.sqrt(30), rel=1e-12)
    noise = rng.normal(0, 0.05, 30)
    unclear = verdict(_validation(before, before + noise - noise.mean(), rot, rot))  # same mean: no gain
    assert not unclear.better and "not better" in unclear.describe()
    worse_rotation = verdict(_validation(before, before - 0.3, rot, rot + 0.01 + rng.normal(0, 1e-4, 30)))
    assert not worse_rotation.better  # the position improved, the rotation got worse beyond its uncertainty
    single = verdict(_validation([0.5], [0.1], [0.01], [0.01]))
    assert not single.better and single.uncertainty_mm == float("inf")  # one pose: no uncertainty, no claim

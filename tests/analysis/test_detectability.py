"""The minimal detectable bias over a workspace section and ``hexapod evaluate --detectability``."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2, ncx2

import hexapod_model as hm
from hexapod_model.analysis.detectability import detectability_map
from hexapod_model.cli.main import main
from hexapod_model.kinematics.consistency import noncentrality, parity_diagonal, threshold


def test_minimal_detectable_bias_has_its_power():
    """A bias of the reported size shifts the statistic to the non-centrality detected with the stated power."""
    hexa = hm.Hexapod.from_preset("reference7")
    A = hexa.redundancy.whitened_jacobian(hexa.home_pose)
    sig = hexa.redundancy.sigmas
    dmap = detectability_map(hexa, half_width=0.01, grid=3)
    mdb = dmap.mdb[1, 1]
    lam = (mdb / sig) ** 2 * parity_diagonal(A)
    np.testing.assert_allclose(lam, noncentrality(1e-3, 0.8, 1), rtol=1e-6)
    np.testing.assert_allclose(ncx2.sf(threshold(1e-3, 1), 1, lam), 0.8, rtol=1e-6)
    assert np.all(np.isfinite(dmap.mdb)) and np.all(dmap.mdb > 0)


def test_a_bias_of_twice_the_detectable_size_is_detected():
    hexa = hm.Hexapod.from_preset("reference_tilt")
    dmap = detectability_map(hexa, half_width=0.02, grid=2)
    ref = hm.Hexapod.from_preset("reference")
    T = hexa.home_pose.copy()
    T[0, 3], T[1, 3] = dmap.xs[0], dmap.ys[0]
    z = np.concatenate([ref.inverse(T).lengths, hexa.redundancy.extra_readings(T)])
    for j in range(len(z)):
        bad = z.copy()
        bad[j] += 2 * dmap.mdb[0, 0, j]
        assert hexa.forward(bad, check=False).status == "inconsistent_readings"


def test_needs_redundant_sensors():
    with pytest.raises(hm.InputError, match="declares no redundant sensors"):
        detectability_map(hm.Hexapod.from_preset("reference"))


def test_cli_hook_prints_the_table_and_writes_the_figure(tmp_path, capsys):
    pytest.importorskip("matplotlib", reason="the figure needs the plots extra: pip install -e '.[plots]'")
    png = tmp_path / "mdb.png"
    assert main(["evaluate", "reference_tilt", "--detectability", str(png)]) == 0
    out = capsys.readouterr().out
    assert png.stat().st_size > 0 and "tilt_y" in out and "leg6" in out
    assert main(["evaluate", "reference", "--detectability", str(png)]) == 2


def test_the_consistency_bound_is_scipy_stats_chi2_isf():
    """``threshold`` takes scipy.special's ``chdtri`` (no scipy.stats import): the same numbers as ``chi2.isf``."""
    for alpha in (1e-9, 1e-6, 1e-3, 0.05):
        for dof in (1, 2, 3, 6, 12, 40):
            threshold.cache_clear()
            assert threshold(alpha, dof) == float(chi2.isf(alpha, dof))
    assert threshold(1e-3, 0) == 0.0

"""A warm 3-6 solve from a near-singular stored pose: a workspace verdict only when every assembly agrees."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from hexapod_model.exceptions import WorkspaceError
from hexapod_model.lie import pose_distance

from ..conftest import (
    limits_only as hexapod,
)  # the stored poses lie beyond the 45 deg cones: the limits alone decide here

# (stored pose, pose that made the readings) as SE(3) logs (m, rad) in the base frame: found among
# random poses whose warm solve from their own readings is near_singular, moved a few mm and degrees
CASES = [
    (
        [
            0.08482151189557367,
            0.0300014962178081,
            0.12141017572517104,
            -0.41003017952616627,
            -0.3413032808214151,
            -0.6365579604716242,
        ],
        [
            0.08740444591585442,
            0.02869007448277236,
            0.11991513551817037,
            -0.3918540541391503,
            -0.28966385690844726,
            -0.6030072011973766,
        ],
    ),
    (
        [
            0.014509891912067302,
            -0.08523571563814367,
            0.1369040897661219,
            -0.14018562375620955,
            0.612943915958898,
            -0.544286798972196,
        ],
        [
            0.025033363911346578,
            -0.08171507328686346,
            0.13835403131502896,
            -0.1846635773875167,
            0.5379995084967287,
            -0.5238197858973909,
        ],
    ),
]


@pytest.mark.parametrize("stored_log, true_log", CASES)
def test_warm_failure_near_a_singularity_falls_back_to_every_assembly(stored_log, true_log):
    hexa = hexapod("3-6")
    length = hexa.engine.finder.length
    T_stored, T_true = (pin.exp6(np.array(x)).homogeneous for x in (stored_log, true_log))
    start = hexa.inverse(T_stored)
    stored = hexa.forward(start.lengths, guess=start, check=False)
    assert stored.converged and "near_singular" in stored.flags  # the stored pose is near a singularity
    lengths = hexa.inverse(T_true).lengths
    cold = hexa.forward(lengths, check=False)
    assert cold.converged and pose_distance(cold.pose, T_true, length) < 1e-8  # the only valid assembly
    for guess in (stored, stored.q):
        warm = hexa.forward(lengths, guess=guess, check=False)
        assert warm.status == "converged", warm.message  # was out_of_limits
        assert pose_distance(warm.pose, T_true, length) < 1e-8
        assert pose_distance(hexa.forward(lengths, guess=guess).pose, T_true, length) < 1e-8  # check=True: no error


def test_a_warm_verdict_every_assembly_confirms_stays():
    """Readings of a pose past a joint limit, no assembly within the limits: warm, still ``out_of_limits``."""
    hexa = hexapod("3-6")
    log = [
        -0.12581070379611867,
        -0.14011111031081072,
        0.14525114920498722,
        -0.09933950925416463,
        -0.3658433894567889,
        0.24025387372228477,
    ]
    T = pin.exp6(np.array(log)).homogeneous  # a random pose of a wide box past the joint limits
    outside = hexa.inverse(T, check=False)
    assert outside.status == "out_of_limits"
    found = hexa.assemblies(outside.lengths)
    assert found.complete and not found.solutions and found.outside > 0
    warm = hexa.forward(outside.lengths, guess=outside.q, check=False)
    assert warm.status == "out_of_limits" and "all" in warm.message  # every assembly's verdict
    with pytest.raises(WorkspaceError):
        hexa.forward(outside.lengths, guess=outside.q)

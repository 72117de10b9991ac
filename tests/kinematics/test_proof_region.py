"""A region's proof (:func:`hexapod_model.kinematics.newton.krawczyk.prove_region`) and the steps it proves.

A region is a box of readings ``P`` and a box of unknowns ``X``: proven, every reading in ``P``
has exactly one solution in ``X``. Checked here against solves that know nothing of the proof:
Newton's solutions of readings drawn in ``P`` (its corners too) lie in ``X``; steps at rest are
proven in one region with end bounds that hold the exact pose; a start on another assembly,
or readings outside the box, are never proven by it.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from hexapod_model.kinematics.newton.krawczyk import prove_region
from hexapod_model.kinematics.newton.proof import StepProver

from ..conftest import limits_only as hexapod


def _pose(hexa):
    T = hexa.home_pose.copy()
    T[:3, 3] += [0.01, 0.0, 0.02]
    return hexa.inverse(T)


def _region(prover: StepProver, q, half: float):
    """A region about ``q`` whose readings box is ``half`` m wide each way: ``(T0, c, rho, hm, hr)`` or None."""
    T0 = prover.platform(q)
    x = prover.unknowns(q, T0)
    l = q[prover.held_q].copy()
    hm, hr = l.copy(), np.full(6, half)
    work = prover.work()[0]
    c, rho = np.empty(prover.nf), np.empty(prover.nf)
    if not prove_region(prover.tables, T0, x, x, l, l, hm, hr, work, c, rho):
        return None
    return T0, c, rho, hm, hr


def test_every_reading_of_a_proven_region_has_its_solution_in_the_region_box():
    hexa = hexapod("reference")
    prover = StepProver.of(hexa.closed_loop)
    start = _pose(hexa)
    proven = [h for h in (2e-4, 1e-4, 5e-5, 2e-5) if _region(prover, start.q, h) is not None]
    assert proven, "no region proven about a pose 22 mm from home"
    half = proven[0]  # the widest: where a bound too narrow would show first
    T0, c, rho, hm, hr = _region(prover, start.q, half)
    rng = np.random.default_rng(3)
    corners = [hm + hr * np.array(s) * (1 - 1e-9) for s in itertools.product((-1.0, 1.0), repeat=6)]
    inside = [hm + hr * rng.uniform(-1, 1, 6) for _ in range(32)]
    widest = 0.0
    for readings in corners + inside:
        sol = hexa.forward(readings, guess=start, check=False, prove=False)
        assert sol.converged
        x = prover.unknowns(sol.q, T0)
        assert np.all(np.abs(x - c) < rho), (np.max(np.abs(x - c) / rho), half)
        widest = max(widest, float(np.max(np.abs(x - c) / rho)))
    assert widest > 0.05  # the box is no wider than the solutions need by much


def test_steps_at_rest_are_proven_in_one_region_with_bounds_that_hold_the_exact_pose():
    hexa = hexapod("reference")
    prover = StepProver.of(hexa.closed_loop)
    start = _pose(hexa)
    rng = np.random.default_rng(4)
    q0, proofs = start.q, []
    for _ in range(40):  # 1 um of noise on each reading, at rest
        truth = start.lengths + rng.normal(scale=1e-6, size=6)
        sol = hexa.forward(truth, guess=q0, check=False, prove=False)
        proof = prover.prove(q0, sol.q)
        assert proof.proven
        proofs.append(proof)
        T0 = prover.platform(sol.q)
        exact = hexa.forward(truth, guess=sol, check=False, tol=1e-14, prove=False)
        assert np.linalg.norm(exact.pose[:3, 3] - sol.pose[:3, 3]) <= proof.position_m + 1e-15
        assert np.allclose(prover.unknowns(exact.q, T0)[-3:], prover.unknowns(sol.q, T0)[-3:], atol=proof.rotation_rad)
        q0 = sol.q
    assert proofs[0].in_region and proofs[0].tests == 1  # the first step built the region
    assert all(p.in_region and p.tests == 0 for p in proofs[1:])  # the others only tested their end box
    assert max(p.position_m for p in proofs) < 1e-9


def test_a_start_on_another_assembly_is_not_proven_by_a_region():
    hexa = hexapod("spherical")  # two assemblies within the limits here
    prover = StepProver.of(hexa.closed_loop)
    start = _pose(hexa)
    found = hexa.assemblies(start.lengths)
    other = [s for s in found.solutions if np.linalg.norm(s.pose[:3, 3] - start.pose[:3, 3]) > 1e-3]
    assert other, "the readings have one assembly only"
    moved = hexa.forward(start.lengths + 1e-6, guess=start, check=False, prove=False)
    assert prover.prove(start.q, moved.q).in_region  # the region about the pose holds
    proof = prover.prove(other[0].q, moved.q)  # same readings, the start on another assembly
    assert not proof.proven and not proof.in_region


def test_readings_outside_the_region_are_proven_by_a_test_of_their_own():
    hexa = hexapod("reference")
    prover = StepProver.of(hexa.closed_loop)
    start = _pose(hexa)
    near = hexa.forward(start.lengths + 1e-6, guess=start, check=False, prove=False)
    assert prover.prove(start.q, near.q).in_region
    far = hexa.forward(near.lengths + 2e-4, guess=near, check=False, prove=False)  # 0.2 mm: out of the box
    proof = prover.prove(near.q, far.q)
    assert proof.proven and not proof.in_region and proof.tests >= 1


def test_a_test_run_on_the_work_arrays_meanwhile_drops_the_region():
    # the dense test and a caller of StepProver.work() overwrite the region's enclosure: the next step builds anew
    hexa = hexapod("reference")
    prover = StepProver.of(hexa.closed_loop)
    start = _pose(hexa)
    steps = [hexa.forward(start.lengths + k * 1e-6, guess=start, check=False, prove=False) for k in range(1, 6)]
    assert prover.prove(start.q, steps[0].q).in_region
    assert prover.prove(steps[0].q, steps[1].q).tests == 0  # in the region
    far = hexa.forward(start.lengths + 3e-3, guess=start, check=False, prove=False)
    assert prover.prove(start.q, far.q, structured=False).proven  # the dense test, on another box
    # 3 mm from the dense test's readings: a test of its own, and a region only at the next step
    assert prover.prove(steps[1].q, steps[2].q).tests == 1
    again = prover.prove(steps[2].q, steps[3].q)
    assert again.proven and again.in_region and again.tests == 1  # built anew, not the stale region
    prover.work()
    assert prover.prove(steps[3].q, steps[4].q).tests == 1


def test_a_short_step_of_fast_moving_readings_builds_no_region():
    # a tracker's step: from a closed prediction 2 um from the result, while the readings move
    # 0.1 mm a sample; a region (+-0.1 mm) about the step would be left at the next sample
    hexa = hexapod("reference")
    prover = StepProver.of(hexa.closed_loop)
    previous = _pose(hexa)
    direction = np.array([1.0, -0.5, 0.8, 0.3, -1.0, 0.6])
    for k in range(1, 9):
        readings = previous.lengths + 1e-4 * direction
        sol = hexa.forward(readings, guess=previous, check=False, prove=False)
        guess = hexa.forward(readings + 2e-6, guess=sol, check=False, prove=False)  # the prediction
        proof = prover.prove(guess.q, sol.q)
        assert proof.proven and proof.tests == 1, (k, proof)
        assert k == 1 or not proof.in_region, (k, proof)  # the first: no motion known yet
        previous = sol
    # the same steps at rest (readings moving 1 um a sample) are proven in a region
    for k in range(1, 5):
        readings = previous.lengths + 1e-6 * direction
        sol = hexa.forward(readings, guess=previous, check=False, prove=False)
        guess = hexa.forward(readings + 2e-6, guess=sol, check=False, prove=False)
        proof = prover.prove(guess.q, sol.q)
        assert proof.proven and proof.in_region and proof.tests == int(k == 1), (k, proof)
        previous = sol


def test_streams_stepped_in_turn_keep_their_regions_in_states_of_their_own():
    # two fixtures at rest at poses of their own, proven in turn on one thread (the service's cycle)
    hexa = hexapod("reference")
    prover = StepProver.of(hexa.closed_loop)
    first = _pose(hexa)
    T = first.pose.copy()
    T[:3, 3] += [-0.02, 0.015, -0.01]
    second = hexa.inverse(T)
    rng = np.random.default_rng(7)

    def steps(states: list | None):
        q0, proofs = [first.q, second.q], []
        for _ in range(12):
            for i, start in enumerate((first, second)):
                sol = hexa.forward(
                    start.lengths + rng.normal(scale=1e-6, size=6), guess=q0[i], check=False, prove=False
                )
                if states is None:  # the thread's own state
                    proofs.append(prover.prove(q0[i], sol.q))
                else:
                    previous = prover.use(states[i])
                    proofs.append(prover.prove(q0[i], sol.q))
                    assert prover.use(previous) is states[i]
                q0[i] = sol.q
        return proofs

    own = steps([prover.new_state(), prover.new_state()])
    assert all(p.proven for p in own)
    assert all(p.in_region and p.tests == 0 for p in own[2:])  # each stream's steps in its own region
    shared = steps(None)  # the thread's one state: each step finds the other pose's region
    assert all(p.proven for p in shared)
    assert not any(p.in_region for p in shared[2:])


def test_a_proof_state_serves_the_prover_that_made_it():
    prover = StepProver.of(hexapod("reference").closed_loop)
    other = StepProver.of(hexapod("spherical").closed_loop)
    with pytest.raises(ValueError, match="another model"):
        prover.use(other.new_state())

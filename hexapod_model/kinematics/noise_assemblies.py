"""Assemblies of a 3-6 hexapod that a reading change within the noise creates: the near-fold test.

Near a fold of the readings map (a double root of the resultant of :mod:`.three_six`), readings
a few noise sigmas away have two more real roots than the measured ones: a complex root pair
``z``, ``1 / conj(z)`` of the resultant closes onto the unit circle there and splits into two
assemblies. The platform is in one of those when the noise happened to move its readings off
the fold, so a result is unique only if no such pair is within reach.

**The reach** is the encoder's noise: every set of readings whose every reading lies within
``NOISE_SIGMAS`` (``k`` = 6) standard deviations ``sigma`` of the measured one (a box about the
measured readings; ``sigma`` is the geometry's ``encoder_sigma``, m). One Gaussian reading error
exceeds 6 sigma with probability 2e-9, one of six with 1.2e-8: readings outside that box are not
ones the platform gives. A hexapod whose readings are less certain than its encoders' noise (an
uncalibrated layout, thermal growth) declares a larger ``encoder_sigma``.

:func:`noise_assemblies` finds them: for every complex pair, the gap ``g = |log |z||`` (the
imaginary part of ``psi_0``) and its gradient in the six readings, from the derivative of the
resultant's coefficients (central differences, ``STEP`` base radii) through the root's
sensitivity ``dz = -(dP) (z) / P'(z)``. Within the box the gap falls fastest towards the corner
``-reach * sign(grad g)``, at the rate ``G = sum_i reach_i |grad_i g|``; near a fold the gap grows
as the square root of the distance to it, so the linear estimate ``g / G`` (in fractions of the
box) is twice that distance: a pair whose estimate is at most 2 is taken, the readings moved
towards that corner by ``1.1, 1.5, 2`` times half the estimate (at most the corner itself), and
the assemblies there with ``psi_0`` within ``ANGLE`` of the pair's are returned when they are more
than the measured readings' own within ``ANGLE`` of it (those move with the readings: a pair next
to one of them finds it there too, and only more of them means that some appeared).
"""

from __future__ import annotations

import numpy as np

from ..exceptions import WorkspaceError
from .three_six import ThreeSixFK, ThreeSixSolution

NOISE_SIGMAS = 6.0  # k: readings within k sigma of the measured ones count (Gaussian tail 2e-9 a reading)
STEP = 5e-7  # base radii, central-difference step of the coefficients' derivative
ANGLE = 0.3  # rad, how near the pair's psi_0 a new assembly must appear
_CIRCLE = 1e-4  # |log |z|| of a real root (as .three_six)


def noise_reach(sigma: float) -> float:
    """How far (m) each reading may lie from the measured one: ``NOISE_SIGMAS`` times ``sigma`` (m)."""
    return NOISE_SIGMAS * float(sigma)


def _gaps(fk: ThreeSixFK, lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roots inside the unit circle (one of each complex pair) and the gradient (n, 6) of their gap."""
    h = STEP * fk.length
    P = fk.polynomial(lengths)
    z = np.roots(P)
    z = z[np.log(np.abs(z)) < -_CIRCLE]
    dP = np.polyval(np.polyder(P), z)
    grad = np.empty((z.size, 6))
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        dPj = (fk.polynomial(lengths + e) - fk.polynomial(lengths - e)) / (2 * h)
        dz = -np.polyval(dPj, z) / dP
        grad[:, j] = -np.real(dz / z)  # g = -log|z| inside the circle
    return z, grad


def noise_assemblies(fk: ThreeSixFK, lengths, reach) -> list[ThreeSixSolution]:
    """The assemblies of readings within ``reach`` of ``lengths`` that these lack.

    Args:
        fk: the 3-6 resultant of the hexapod.
        lengths: the six prismatic joint values (m) of the measured readings.
        reach: how far each joint value may move (m; a number, or six: the box
            ``|dl_i| <= reach_i``), :func:`noise_reach` of the encoder's sigma.

    Returns:
        Each a :class:`~.three_six.ThreeSixSolution` of moved joint values within the box (its
        pose closes those, not ``lengths``); none when no complex root pair of the resultant is
        that close to real.
    """
    lengths = np.asarray(lengths, dtype=float)
    box = np.broadcast_to(np.asarray(reach, dtype=float), (6,))
    try:
        z, grad = _gaps(fk, lengths)
    except WorkspaceError:
        return []
    found: list[ThreeSixSolution] = []
    own: list[float] | None = None  # psi_0 of the measured readings' own assemblies, at the first pair taken
    for k in range(z.size):
        corner = -box * np.sign(grad[k])  # the corner of the box towards which the gap falls fastest
        g, rate = -np.log(np.abs(z[k])), float(np.abs(grad[k]) @ box)
        if not (rate > 0.0 and g / rate <= 2.0):
            continue
        for factor in (1.1, 1.5, 2.0):
            s = min(1.0, factor * 0.5 * g / rate)
            try:
                sols = fk.solve_all(lengths + s * corner)
            except WorkspaceError:
                continue
            near = [a for a in sols if _apart(a.psi[0], z[k]) < ANGLE]
            if own is None:
                own = _own_angles(fk, lengths)
            # more assemblies there than the measured readings have about that angle: some appeared (their
            # own assemblies moved with the readings also lie there: a pair next to one of them is not new)
            if len(near) > sum(_apart(psi0, z[k]) < ANGLE for psi0 in own):
                found.extend(near)
                break
    return found


def _apart(psi0: float, z: complex) -> float:
    """The angle (rad) between the circle angle ``psi0`` and the root ``z``'s."""
    return float(abs(np.angle(np.exp(1j * psi0) / z * abs(z))))


def _own_angles(fk: ThreeSixFK, lengths: np.ndarray) -> list[float]:
    """``psi_0`` of each assembly of ``lengths`` itself (none when two legs of a pair cannot meet)."""
    try:
        return [float(a.psi[0]) for a in fk.solve_all(lengths)]
    except WorkspaceError:
        return []

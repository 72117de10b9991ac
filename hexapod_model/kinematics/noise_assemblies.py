"""Assemblies of a 3-6 hexapod that a reading change within the noise creates: the near-fold test.

Near a fold of the readings map (a double root of the resultant of :mod:`.three_six`), readings
a few noise sigmas away have two more real roots than the measured ones: a complex root pair
``z``, ``1 / conj(z)`` of the resultant closes onto the unit circle there and splits into two
assemblies. The platform is in one of those when the noise happened to move its readings off
the fold, so a result is unique only if no such pair is within reach.

:func:`noise_assemblies` finds them: for every complex pair, the gap ``g = |log |z||`` (the
imaginary part of ``psi_0``) and its gradient in the six readings, from the derivative of the
resultant's coefficients (central differences, ``STEP`` m) through the root's sensitivity
``dz = -(dP) (z) / P'(z)``. Near a fold the gap grows as the square root of the distance to it,
so the linear estimate ``g / |grad g|`` is twice that distance: a pair whose estimate is at most
twice ``reach`` is taken, the readings moved along ``-grad g`` by up to ``reach`` (1.1, 1.5, 2
times half the estimate, capped at ``reach``), and the assemblies that appear there with
``psi_0`` within ``ANGLE`` of the pair's are returned. ``reach`` (m, Euclidean over the six
readings) is by default ``REACH`` base radii: ``NOISE_SIGMAS`` times ``READING_NOISE`` at the
presets' 0.2 m base radius (0.3 mm), relative so that a scaled hexapod gets the same answers.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import WorkspaceError
from .three_six import ThreeSixFK, ThreeSixSolution

#: m, standard deviation of one reading on the presets: the order of the LinACE encoders'
#: accuracy (Bem et al. (2026) section 2), as the tracker's default
READING_NOISE = 10e-6
NOISE_SIGMAS = 30.0  # a reading change within this many sigmas counts
REACH = NOISE_SIGMAS * READING_NOISE / 0.2  # base radii: 0.3 mm at the presets' 0.2 m
STEP = 5e-7  # base radii, central-difference step of the coefficients' derivative
ANGLE = 0.3  # rad, how near the pair's psi_0 a new assembly must appear
_CIRCLE = 1e-4  # |log |z|| of a real root (as .three_six)


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


def noise_assemblies(fk: ThreeSixFK, lengths, reach: float | None = None) -> list[ThreeSixSolution]:
    """The assemblies of readings within ``reach`` (m; default ``REACH`` base radii) of ``lengths`` that these lack.

    Each is a :class:`~.three_six.ThreeSixSolution` of the moved readings (its pose closes those,
    not ``lengths``); none when no complex root pair of the resultant is that close to real.
    """
    lengths = np.asarray(lengths, dtype=float)
    reach = REACH * fk.length if reach is None else reach
    try:
        z, grad = _gaps(fk, lengths)
    except WorkspaceError:
        return []
    found: list[ThreeSixSolution] = []
    for k in range(z.size):
        g, norm = -np.log(np.abs(z[k])), np.linalg.norm(grad[k])
        if not (norm > 0.0 and g / norm <= 2.0 * reach):
            continue
        direction = -grad[k] / norm
        for factor in (1.1, 1.5, 2.0):
            t = min(reach, factor * 0.5 * g / norm)
            try:
                sols = fk.solve_all(lengths + t * direction)
            except WorkspaceError:
                continue
            near = [s for s in sols if abs(np.angle(np.exp(1j * s.psi[0]) / z[k] * abs(z[k]))) < ANGLE]
            if near:
                found.extend(near)
                break
    return found

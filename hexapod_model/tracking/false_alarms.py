"""The tracker's false alarms: the quantisation model and each flag's expected rate per hour.

A reading is the encoder count ``round((l + e) / resolution) * resolution`` of the true leg
value ``l`` plus Gaussian noise ``e`` of standard deviation ``noise`` (``resolution = 0``: no
counts). Two consequences for the checks of :mod:`.reading_tests`:

* **innovation spread.** The count adds a rounding error of standard deviation
  ``resolution / sqrt(12)`` (uniform over a count): the reading's standard deviation is
  ``reading_sigma = sqrt(noise^2 + resolution^2 / 12)``; the motion model's own error
  (``motion_error``, m: the third derivative of the motion over the window, speed-dependent)
  adds in quadrature to the innovation: ``sigma_nu = hypot(reading_sigma * spread, motion_error)``.
* **repeated counts.** A working encoder shows the same count twice in a row with probability
  ``p_repeat`` (:func:`repeat_probability`; at rest, the true value uniform within a count):
  about ``resolution / (2 sqrt(pi) noise)`` when the noise spans several counts, 1 when it is
  far below one count (an encoder at rest then shows one value: no test can tell it from a
  stuck one). A leg is called ``stuck`` only after a frozen run a working encoder shows with
  probability below ``STUCK_ALPHA`` per run (:func:`stuck_run`).

Expected false alarms per hour (:func:`false_alarm_rates`), ``f`` the sample rate (Hz), six
legs, ``Q`` the Gaussian upper tail:

* ``jump``: ``3600 f (1 - (1 - 2 Q(jump_sigmas))^6)``: 12.2 an hour at 1 kHz for 5 sigmas,
  whatever the noise and resolution, as long as ``motion_error`` is stated (a model error
  left out of the spread raises it);
* ``stuck``: at most ``3600 f * 6 * p_repeat^n`` with ``n`` the required frozen run
  (``stuck_run``): a working leg must repeat its count ``n`` times in a row (the bound takes
  the motion evidence as certain); 0 without counts (``resolution = 0``: a continuous
  reading never repeats).

These are the rates of the model (Gaussian noise, independent samples);
``benchmarks/tracker_faults.py --hour`` measures them over an hour of simulated samples.
"""

from __future__ import annotations

import math

import numpy as np

STUCK_ALPHA = 1e-9  # largest probability that a working leg repeats its count for the required run


def reading_sigma(noise: float, resolution: float) -> float:
    """Standard deviation (m) of a reading: Gaussian ``noise`` plus rounding to ``resolution`` counts."""
    return math.sqrt(noise * noise + resolution * resolution / 12.0)


def repeat_probability(noise: float, resolution: float) -> float:
    """Probability that two readings of a leg at rest show the same count (0 without counts).

    The true value uniform within a count, independent Gaussian ``noise`` on each reading:
    ``E_u [sum_k P_k(u)^2]``, ``P_k`` the probability of count ``k``; by quadrature over 64 offsets.
    """
    if resolution <= 0.0:
        return 0.0
    if noise <= 0.0:
        return 1.0
    from scipy.special import ndtr

    u = (np.arange(64) + 0.5) / 64.0  # true value's offset within its count (counts)
    k = np.arange(-int(8 * noise / resolution) - 2, int(8 * noise / resolution) + 3)
    edges = (k[None, :] + 0.5 - u[:, None]) * resolution / noise
    p = np.diff(ndtr(np.concatenate([edges[:, :1] - resolution / noise, edges], axis=1)), axis=1)
    return float(min(1.0, np.mean(np.sum(p * p, axis=1))))


def stuck_run(noise: float, resolution: float, samples: int, alpha: float = STUCK_ALPHA) -> int:
    """Frozen samples before ``stuck``: ``samples``, or more where counts repeat by chance.

    The smallest ``n >= samples`` with ``p_repeat^n <= alpha`` (a huge number when counts
    always repeat: ``stuck`` then never fires on an unchanged count alone).
    """
    p = repeat_probability(noise, resolution)
    if p <= 0.0:
        return samples
    if p >= 1.0 - 1e-12:
        return 2**31 - 1
    return max(samples, math.ceil(math.log(alpha) / math.log(p)))


def gaussian_tail(k: float) -> float:
    """``P(N(0, 1) > k)``."""
    return 0.5 * math.erfc(k / math.sqrt(2.0))


def false_alarm_rates(
    rate_hz: float, noise: float, resolution: float, jump_sigmas: float = 5.0, stuck_samples: int = 3
) -> dict[str, float]:
    """Expected false ``jump`` and (an upper bound of) ``stuck`` alarms per hour (see the module doc)."""
    per_sample_jump = 1.0 - (1.0 - 2.0 * gaussian_tail(jump_sigmas)) ** 6
    n = stuck_run(noise, resolution, stuck_samples)
    p = repeat_probability(noise, resolution)
    stuck = 3600.0 * rate_hz * 6.0 * p ** max(n, 1) if n < 2**31 - 1 else 0.0
    return {"jump": 3600.0 * rate_hz * per_sample_jump, "stuck": stuck, "stuck_run": float(n), "p_repeat": p}

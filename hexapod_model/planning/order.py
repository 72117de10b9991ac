"""The order in which the arm visits the fixtures: the one of least total time.

Each fixture's own time (couple, carry, decouple) does not depend on the order; what does is
the free-space moves between them: from the arm's start to the first plate, from each plate's
target to the next plate's start, and from the last plate back to the start configuration.
With up to :data:`EXACT_UP_TO` fixtures every order is tried (exact); beyond, the nearest
next fixture is taken each time (greedy, not guaranteed optimal; the plan's summary says which).
"""

from __future__ import annotations

import itertools

import numpy as np

EXACT_UP_TO = 7


def best_order(start: np.ndarray, between: np.ndarray, back: np.ndarray) -> tuple[tuple[int, ...], str]:
    """The visiting order of least move time, and ``"exact"`` or ``"greedy"``.

    Args:
        start: (n,) time (s) from the arm's start to fixture ``j``'s coupling.
        between: (n, n) time (s) from fixture ``i``'s target to fixture ``j``'s start.
        back: (n,) time (s) from fixture ``i``'s target back to the arm's start.
    """
    n = len(start)

    def cost(order: tuple[int, ...]) -> float:
        c = start[order[0]] + back[order[-1]]
        return float(c + sum(between[a, b] for a, b in itertools.pairwise(order)))

    if n <= EXACT_UP_TO:
        return min(itertools.permutations(range(n)), key=cost), "exact"
    order, left = [int(np.argmin(start))], set(range(n))
    left.discard(order[0])
    while left:
        order.append(min(left, key=lambda j: between[order[-1], j]))
        left.discard(order[-1])
    return tuple(order), "greedy"

"""Shared timing helper of the benchmark scripts."""

import time

import numpy as np


def best_of(fn, n, repeat=5):
    """Best mean time of ``n`` calls over ``repeat`` repetitions (s): the least disturbed by other load."""
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        best = min(best, (time.perf_counter() - t0) / n)
    return best

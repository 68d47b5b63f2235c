"""Timing helper shared by the benchmark scripts."""

import time


def best_of(fn, repeat):
    """Minimum wall time of ``repeat`` calls of ``fn`` after one warm-up call."""
    fn()  # warm-up
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)

"""A run's wall time as the peers study and benchmarks/peers.py measure it (SciMLBenchmarks style): a warm-up run
over a fraction of the interval (the units' libraries loaded, the caches warm), then up to ``repeat`` timed runs
of the whole interval, fewer once ``budget`` seconds are spent; the minimum counts (what the run costs when
nothing else gets in its way).
"""

from __future__ import annotations

import math
import time

from .runners import quiet

__all__ = ["measure"]


def measure(run, t_end: float, repeat: int, budget: float, H: float | None = None, warmup: float = 0.1):
    """``(the last run's outcome, the minimum wall time, the number of timed runs)`` of ``run(t)``; the warm-up
    over ``warmup * t_end``, rounded up to whole macro steps of ``H`` where given."""
    with quiet():
        run(warmup * t_end if H is None else math.ceil(warmup * t_end / H - 1e-9) * H)
        walls, outcome = [], None
        for _ in range(repeat):
            clock = time.perf_counter()
            outcome = run(t_end)
            walls.append(time.perf_counter() - clock)
            if sum(walls) > budget:
                break
    return outcome, min(walls), len(walls)

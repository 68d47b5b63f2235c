"""Benchmark of the convergence part: cost of one curve and of the co-simulation stepping.

Prints (no assertions):
* seconds per macro step of icosim.macrostep.simulate vs the amplification-matrix path, and
  the speed-up, for a few schemes;
* seconds for one full convergence curve (16 step sizes, 1e-5 ... 1e-2 s, T = 1 s) with the
  matrix path, and the estimate for the same curve with simulate;
* a check that CPU time per simulated second extrapolated from a few timed steps (what the
  work-precision job does) matches a fully timed run.

    /work/venv/bin/python benchmarks/convergence.py
"""

import time

import numpy as np

from icosim.convergence.experiment import Setup, dimensional_method, step_counts
from icosim.convergence.study import Study
from icosim.convergence.work_precision import time_macro_steps

SCHEMES = [
    ("baumgarte", {"index": 1, "mu": 5e-3}, "ff", 2),
    ("weighted", {"index": 1, "a": 1.0, "b": 1.0}, "fd", 1),
    ("projection", {}, "dd", 2),
]


def main():
    setup = Setup()
    H, N = 1e-4, 10000
    study = Study(setup, [N // 10, N])
    print(f"{'scheme':45s} {'simulate us/step':>17s} {'matrix us/step':>15s} {'speed-up':>9s}")
    for method, params, dec, k in SCHEMES:
        m = dimensional_method(method, H, **params)
        t = time_macro_steps(setup, H, method, params, dec, k, steps=200, repeats=3, warmup_steps=10)
        best = np.inf
        for _ in range(3):
            t0 = time.process_time()
            study._states(m, dec, k, H, N, "matrix")
            best = min(best, time.process_time() - t0)
        sim, mat = t["seconds_per_step"] * 1e6, best / N * 1e6
        print(f"{method + ' ' + str(params) + ' ' + dec + ' k=' + str(k):45s} {sim:17.1f} {mat:15.2f} {sim / mat:9.0f}")

    n = step_counts(1.0, 1e-5, 1e-2, 16)
    full = Study(setup, n)
    full.reference(0)  # warm-up of imports / caches
    t0 = time.perf_counter()
    full.run("baumgarte", {"index": 1, "mu": 5e-3}, "ff", 2)
    curve = time.perf_counter() - t0
    per_step = time_macro_steps(setup, 1e-3, "baumgarte", {"index": 1, "mu": 5e-3}, "ff", 2)["seconds_per_step"]
    print(
        f"one curve (16 sizes, {n.sum()} macro steps in total): {curve:.2f} s with the matrix path; "
        f"simulate would need about {n.sum() * per_step:.0f} s"
    )

    # extrapolation check: CPU time per simulated second from 20 timed steps vs a fully timed run
    H, T = 1e-3, 0.5
    est = time_macro_steps(setup, H, "projection", {}, "ff", 1, steps=20, repeats=3)["seconds_per_simulated_second"]
    s = Setup(end_time=T)
    st = Study(s, [int(T / H) // 2, int(T / H)])
    m = dimensional_method("projection", H)
    best = np.inf
    for _ in range(3):
        t0 = time.process_time()
        st._states(m, "ff", 1, H, int(T / H), "simulate")
        best = min(best, time.process_time() - t0)
    print(
        f"CPU s per simulated second, projection ff k=1, H = 1e-3: extrapolated {est:.3f}, "
        f"full run {best / T:.3f} (ratio {best / T / est:.2f}; the full run includes the set-up)"
    )


if __name__ == "__main__":
    main()

"""Benchmark: a certified recheck (ball arithmetic) against the 128-digit mpmath recheck, per point, in one run.

The pipeline rechecks the points float64 cannot decide.  Before the certified
rechecks that recheck was mpmath at 128 digits (a value, no bound); now it is a proven
enclosure in ball arithmetic (python-flint Arb).  For each scheme (every method
and decomposition, k = 0, 1, 2) this takes the points of a grid over the
paper's plane that the pipeline would recheck (float64 not trusted, or within
the band of 1: mostly the undamped axis lr1 = 0 and the stability boundary)
plus random points of the plane, and times on the *same* points, in turn:

* ``certify_spectral_radius`` (the adaptive ball recheck, its verdict),
* ``spectral_radius_mp`` at 128 digits (the recheck it replaces).

It prints per scheme the median time per point of each and their ratio, and the
ratio over all points (sum of times); the goal is a ratio mp : ball >= 5.

    python benchmarks/certify.py [--n 21] [--random 3] [--json FILE]
"""

import os

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from icosim import TestModel, make_method  # noqa: E402
from icosim.engine.decompositions import DECOMPOSITIONS  # noqa: E402
from icosim.problems.linear.spectral import certify_spectral_radius, spectral_radius_float64, spectral_radius_mp  # noqa: E402

GOAL = 5.0
METHODS = [("baumgarte", {"mu": 1.0, "index": 1}), ("weighted", {"a": 1.0, "b": 1.0}), ("projection", {})]


def recheck_points(method, dec, k, n, n_random, rng, band=1e-6):
    """Grid points the pipeline would recheck (at most 6, spread over the list) and ``n_random`` random ones."""
    lr, li = np.meshgrid(np.linspace(-2, 0, n), np.linspace(0, 2, n), indexing="ij")
    grid = TestModel(lr, li, 2.0, 2.0, 2.0)
    rho, err = spectral_radius_float64(grid, method, dec, k)
    todo = ~(np.isfinite(rho) & (np.abs(rho - 1) > err)) | (np.abs(rho - 1) < band)
    idx = np.flatnonzero(todo)
    idx = idx[np.linspace(0, idx.size - 1, min(6, idx.size)).astype(int)] if idx.size else idx
    points = [TestModel(float(lr.flat[i]), float(li.flat[i]), 2.0, 2.0, 2.0) for i in idx]
    points += [TestModel(-2 * rng.random(), 2 * rng.random(), 2.0, 2.0, 2.0) for _ in range(n_random)]
    return points, int(todo.sum())


def timed(f, *args):
    t0 = time.perf_counter()
    out = f(*args)
    return time.perf_counter() - t0, out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=21, help="grid points per axis for choosing the recheck points")
    ap.add_argument("--random", type=int, default=3, help="random points per scheme besides the recheck points")
    ap.add_argument("--digits", type=int, default=128)
    ap.add_argument("--json", help="write the results to this file")
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    rows, total_ball, total_mp = [], 0.0, 0.0
    print(f"{'scheme':34s} {'points':>6s} {'ball/pt [ms]':>12s} {'mp/pt [ms]':>11s} {'mp : ball':>9s}  verdicts")
    for name, params in METHODS:
        method = make_method(name, **params)
        for dec in DECOMPOSITIONS:
            try:
                method.check_decomposition(DECOMPOSITIONS[dec])
            except ValueError:  # e.g. dd needs a position-level method
                continue
            for k in (0, 1, 2):
                points, n_todo = recheck_points(method, dec, k, args.n, args.random, rng)
                certify_spectral_radius(points[0], method, dec, k)  # warm-up (imports, caches)
                t_ball, t_mp, verdicts = [], [], {}
                for p in points:
                    tb, c = timed(certify_spectral_radius, p, method, dec, k)
                    tm, _ = timed(spectral_radius_mp, p, method, dec, k, args.digits)
                    t_ball.append(tb)
                    t_mp.append(tm)
                    verdicts[c.verdict] = verdicts.get(c.verdict, 0) + 1
                total_ball += sum(t_ball)
                total_mp += sum(t_mp)
                row = dict(
                    method=name,
                    decomposition=dec,
                    k=k,
                    points=len(points),
                    recheck_points_on_grid=n_todo,
                    ball_ms_median=1e3 * statistics.median(t_ball),
                    mp_ms_median=1e3 * statistics.median(t_mp),
                    ratio=statistics.median(t_mp) / statistics.median(t_ball),
                    verdicts=verdicts,
                )
                rows.append(row)
                label = f"{name} {dec} k={k}"
                print(
                    f"{label:34s} {len(points):6d} {row['ball_ms_median']:12.2f} {row['mp_ms_median']:11.2f} "
                    f"{row['ratio']:9.1f}  {verdicts}"
                )
    ratio = total_mp / total_ball
    print(
        f"all points: ball {total_ball:.2f} s, mpmath {args.digits} digits {total_mp:.2f} s; "
        f"mp : ball = {ratio:.1f} (goal >= {GOAL:.0f}: {'met' if ratio >= GOAL else 'NOT met'})"
    )
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"rows": rows, "total_ball_s": total_ball, "total_mp_s": total_mp, "ratio": ratio}, f, indent=1)


if __name__ == "__main__":
    main()

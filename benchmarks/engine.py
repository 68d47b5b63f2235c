"""Engine benchmark: float64 grid sweeps and 128-digit points, measured in one run.

Reports, for several schemes at k = 2:
* the time of a 101 x 101 float64 grid (plain, and with the precision policy's
  error estimate), minimum of ``--repeat`` runs after a warm-up, on one core;
* the median time of one point at 128 digits (``--mp-points`` points);
* the per-point speed ratio float64 : 128 digits.

Run: ``python benchmarks/engine.py`` (``--json FILE`` to keep the numbers).
Set OMP_NUM_THREADS=1 etc. for a strict one-core figure; the script sets them.
"""

import os

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from _timing import best_of  # noqa: E402  (benchmarks/ is on sys.path when run as a script)

from icosim import (  # noqa: E402
    TestModel,
    baumgarte,
    projection,
    spectral_radius_float64,
    spectral_radius_mp,
    weighted_multiplier,  # noqa: E402
)

SCHEMES = [
    ("baumgarte mu=1 index 1", baumgarte(mu=1, index=1), "ff"),
    ("weighted a=b=1", weighted_multiplier(1, 1), "ff"),
    ("projection", projection(), "ff"),
    ("baumgarte mu=1 index 1", baumgarte(mu=1, index=1), "fd"),
    ("projection", projection(), "fd"),
    ("projection", projection(), "dd"),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=101, help="grid points per axis")
    ap.add_argument("--k", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--mp-points", type=int, default=5)
    ap.add_argument("--digits", type=int, default=128)
    ap.add_argument("--json", help="write the results to this file")
    args = ap.parse_args()

    lr, li = np.meshgrid(np.linspace(-2, 0, args.n), np.linspace(0, 2, args.n), indexing="ij")
    grid = TestModel(lr, li, 2.0, 2.0, 2.0)
    rng = np.random.default_rng(0)
    points = [TestModel(-2 * rng.random(), 2 * rng.random(), 2.0, 2.0, 2.0) for _ in range(args.mp_points)]
    rows = []
    print(
        f"{'scheme':28s} {'dec':3s} {'f64 grid [s]':>12s} {'+estimate [s]':>13s} "
        f"{'mp/point [s]':>12s} {'f64/point [us]':>14s} {'ratio mp:f64':>12s}"
    )
    for label, method, dec in SCHEMES:
        t_plain = best_of(
            lambda m=method, d=dec: spectral_radius_float64(grid, m, d, args.k, error_estimate=False), args.repeat
        )
        t_est = best_of(lambda m=method, d=dec: spectral_radius_float64(grid, m, d, args.k), args.repeat)
        spectral_radius_mp(points[0], method, dec, args.k, args.digits)  # warm-up
        mp_times = []
        for p in points:
            t0 = time.perf_counter()
            spectral_radius_mp(p, method, dec, args.k, args.digits)
            mp_times.append(time.perf_counter() - t0)
        t_mp = statistics.median(mp_times)
        per_point = t_est / args.n**2
        row = dict(
            scheme=label,
            decomposition=dec,
            k=args.k,
            grid=f"{args.n}x{args.n}",
            float64_grid_s=t_plain,
            float64_grid_with_estimate_s=t_est,
            mp_point_s=t_mp,
            digits=args.digits,
            float64_point_s=per_point,
            speed_ratio_mp_to_float64=t_mp / per_point,
        )
        rows.append(row)
        print(
            f"{label:28s} {dec:3s} {t_plain:12.3f} {t_est:13.3f} {t_mp:12.4f} {per_point * 1e6:14.1f} "
            f"{t_mp / per_point:12.0f}"
        )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=2)


if __name__ == "__main__":
    main()

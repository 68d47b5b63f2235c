"""The numerical kernels of this tree and an older commit side by side in one run (old, this tree, old again).

Two measurements, each in a fresh process per tree with the tree's ``src/`` first on ``PYTHONPATH`` and one
BLAS thread, the configuration of *this* tree's ``config/`` for both:

* **pendulum**: one co-simulation run (1 s at H = 1 ms) of three configurations -- projection ff k = 1
  (Jacobi), Baumgarte fd k = 0 (Gauss-Seidel 1->2), projection dd k = 2 (Jacobi) -- the best of three
  CPU times each, after a warm-up that compiles the numba kernels;
* **stability**: every panel of Fig. 9 (float64 sweep, error estimates, certification), CPU seconds.

Prints the CPU seconds per tree, the ratio this tree / older commit (mean of its two runs), and whether
the results are bitwise equal (the angles of the runs; every panel's rho and verdict).  Never a timed
assertion: a measurement to quote.

    python benchmarks/kernels.py [--old COMMIT] [--figure 9]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from _workflow import ROOT, tree

CHILD = r"""
import json, pickle, sys, time, yaml
import numpy as np
root, figure, out = sys.argv[1], sys.argv[2], sys.argv[3]
import icosim
assert icosim.__file__.startswith(sys.argv[4]), icosim.__file__
from icosim.studies.pendulum.datasets import run_job
from icosim.studies.stability.datasets import stability_panel
from icosim.studies.stability.panels import figure_panels
P = yaml.safe_load(open(f"{root}/config/pendulum.yaml"))["pendulum"]
S = yaml.safe_load(open(f"{root}/config/stability.yaml"))["stability"]
times, results = {}, {}
for method, dec, k, scheme in [("projection", "ff", 1, "jacobi"), ("baumgarte", "fd", 0, "gauss-seidel-12"),
                               ("projection", "dd", 2, "jacobi")]:
    job = {"method": method, "decomposition": dec, "k": k, "method_params": P["methods"][method],
           "model": P["model"], "H": P["H"], "t_end": 1.0, "scheme": scheme,
           **{key: P[key] for key in ("integrator", "sensitivities", "corrector", "divergence")}}
    run_job(dict(job, t_end=0.01))  # compiles (or loads) the kernels
    best = float("inf")
    for _ in range(3):
        t = time.process_time()
        _, ds = run_job(job)
        best = min(best, time.process_time() - t)
    name = f"pendulum {method} {dec} k={k} {scheme}"
    times[name], results[name] = best, ds["phi1"].values
t = time.process_time()
for spec in figure_panels(figure, S["figures"][figure], grid=S["grid"], zoom_grid=S["zoom_grid"],
                          precision=S["precision"]):
    ds = stability_panel(spec)
    results[f"panel {spec.scheme} {spec.row} {spec.k} {spec.view}"] = (ds["rho"].values, ds["verdict"].values)
times[f"stability fig{figure} panels"] = time.process_time() - t
pickle.dump(results, open(out, "wb"))
print(json.dumps(times))
"""


def measure(src_root: Path, figure: str, out: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src_root / "src"), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, str(ROOT), figure, str(out), str(src_root)],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(proc.stdout.strip().splitlines()[-1])


def equal(a, b) -> bool:
    import numpy as np

    def same(x, y):
        if isinstance(x, tuple):
            return all(same(u, v) for u, v in zip(x, y))
        return np.array_equal(x, y, equal_nan=np.asarray(x).dtype.kind == "f")

    return a.keys() == b.keys() and all(same(a[key], b[key]) for key in a)


def main(argv=None):
    import pickle

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", default="7b10cd9")
    ap.add_argument("--figure", default="9")
    args = ap.parse_args(argv)
    with tree(args.old) as old, tempfile.TemporaryDirectory() as tmp:
        runs = []
        for label, root in ((f"{args.old} (1)", old), ("this tree", ROOT), (f"{args.old} (2)", old)):
            out = Path(tmp) / f"{len(runs)}.pkl"
            runs.append((label, measure(root, args.figure, out), pickle.load(open(out, "rb"))))
    names = list(runs[1][1])
    print(f"{'CPU s':<48}" + "".join(f"{label:>16}" for label, _, _ in runs) + f"{'ratio':>8}")
    for name in names:
        old_mean = (runs[0][1][name] + runs[2][1][name]) / 2
        row = "".join(f"{t[name]:>16.3f}" for _, t, _ in runs)
        print(f"{name:<48}{row}{runs[1][1][name] / old_mean:>8.2f}")
    print("results bitwise equal to the older commit's:", equal(runs[0][2], runs[1][2]))


if __name__ == "__main__":
    main()

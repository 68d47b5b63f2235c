"""Benchmark of the convergence part (Figs. 21-23), measured side by side in one run.

1. The convergence part of the workflow (``snakemake -c2 results/report/convergence.html`` from a
   clean results/) three times, one after the other:
   * this tree, default configuration (floor-free errors, ``stepping: error``, H = 1e-6 ... 1e-2 s);
   * this tree with ``stepping: matrix`` (the float64-only computation of the same curves, same H);
   * this tree with the old range H = 1e-5 ... 1e-2 s (16 sizes): what the extension to 1e-6 costs;
   * an older commit (default ``06f2834``, before the floor-free errors: float64 state stepping,
     H = 1e-5 ... 1e-2 s), from a ``git worktree``.
   Prints wall and CPU seconds and the ratios new / float64-only and new / old (the target of the
   floor-free errors: at most 1.5x the old convergence part).
2. Per-step costs of the co-simulation stepping: icosim.engine.run.simulate against the linear-map
   paths (float64 state stepping and the error recurrence), for a few schemes.

    python benchmarks/convergence.py [--old COMMIT] [--skip-workflow]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _workflow import run_workflow, tree

from icosim.studies.convergence.experiment import Setup, dimensional_method
from icosim.studies.convergence.study import Study
from icosim.studies.convergence.work_precision import time_macro_steps

SCHEMES = [
    ("baumgarte", {"index": 1, "mu": 5e-3}, "ff", 2),
    ("weighted", {"index": 1, "a": 1.0, "b": 1.0}, "fd", 1),
    ("projection", {}, "dd", 2),
]
TARGET = ["results/report/convergence.html"]


def workflow_runs(old: str):
    runs = []
    with tree(None) as new:
        runs.append(run_workflow(new, TARGET, label="this tree (floor-free, H 1e-6 ... 1e-2)"))
        runs.append(
            run_workflow(
                new,
                TARGET,
                label="this tree, stepping: matrix (float64 only, same H)",
                overrides={"convergence": {"stepping": "matrix"}},
            )
        )
        runs.append(
            run_workflow(
                new,
                TARGET,
                label="this tree, H 1e-5 ... 1e-2 (16 sizes)",
                overrides={"convergence": {"step_sizes": {"H_min": 1e-5, "H_max": 1e-2, "num": 16}}},
            )
        )
    with tree(old) as old_tree:
        runs.append(run_workflow(old_tree, TARGET, label=f"commit {old} (float64, H 1e-5 ... 1e-2)"))
    print(f"{'convergence part':55s} {'wall s':>8s} {'CPU s':>8s}")
    for r in runs:
        print(f"{r.label:55s} {r.wall:8.1f} {r.cpu:8.1f}")
    new, f64, short, before = runs
    print(
        f"extension of the range to 1e-6 s: +{new.wall - short.wall:.1f} s wall, +{new.cpu - short.cpu:.1f} s CPU; "
        f"ratio floor-free / float64-only: wall {new.wall / f64.wall:.2f}, CPU {new.cpu / f64.cpu:.2f}; "
        f"ratio this tree / {old}: wall {new.wall / before.wall:.2f}, CPU {new.cpu / before.cpu:.2f} "
        f"(load average at the end of each run: {', '.join(f'{r.load[0]:.1f}' for r in runs)})"
    )


def per_step_costs():
    setup = Setup()
    H, N = 1e-4, 10000
    study = Study(setup, [N // 10, N])
    print(f"{'scheme':45s} {'simulate':>10s} {'matrix':>10s} {'error':>10s}  (us per macro step)")
    for method, params, dec, k in SCHEMES:
        m = dimensional_method(method, H, **params)
        sim = time_macro_steps(setup, H, method, params, dec, k, steps=200, repeats=3, warmup_steps=10)
        costs = []
        for stepping in ("matrix", "error"):
            best = np.inf
            for _ in range(3):
                t0 = time.process_time()
                study._errors(m, dec, k, 1, stepping)  # (errors, diverged, bits, certificate)
                best = min(best, time.process_time() - t0)
            costs.append(best / N * 1e6)
        label = f"{method} {params} {dec} k={k}"
        print(f"{label:45s} {sim['seconds_per_step'] * 1e6:10.1f} {costs[0]:10.2f} {costs[1]:10.2f}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", default="06f2834", help="commit to compare with (default: before the floor-free errors)")
    ap.add_argument("--skip-workflow", action="store_true", help="only the per-step costs")
    args = ap.parse_args(argv)
    per_step_costs()
    if not args.skip_workflow:
        workflow_runs(args.old)


if __name__ == "__main__":
    main()

"""Pendulum benchmark: cost of one co-simulation run against the monolithic reference.

The co-simulation integrates each link per macro step for the predictor plus
the finite-difference perturbations (one batched Radau call per link) and for
the corrector (one more call per link), compiled with numba
(icosim.problems.pendulum.integrator.compiled); each run is also timed on the tests' numpy reference
(tests/reference_radau.py: ``NumpyPendulum``, the same algorithm in numpy on the links'
closures), side by side, for the compiled kernel's speed-up.  Its cost is set against the
monolithic pendulum (minimal coordinates) solved with the *same integrator and
tolerance* (``icosim.problems.pendulum.integrator.systems.monolithic_radau``, Radau IIA, rtol = atol = 1e-6):

* ``monolithic, free steps``: one call over [0, T], the integrator picks its
  steps (what a monolithic simulation would cost);
* ``monolithic, macro grid``: restarted at every macro point (the
  co-simulation's communication grid, one step per macro step);
* scipy ``solve_ivp(method='Radau')`` over [0, T] for comparison, and the cost
  of one ``solve_ivp`` call over one macro step on a link subsystem (what every
  one of the co-simulation's 4 integrations per macro step would cost with
  scipy instead of the compiled integrator).

Minimum of ``--repeat`` runs after a warm-up, one core (thread variables set).
Run: ``python benchmarks/pendulum.py [--t-end 0.5] [--json FILE]``.
"""

import os

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from _timing import best_of  # noqa: E402  (benchmarks/ is on sys.path when run as a script)
from scipy.integrate import solve_ivp  # noqa: E402

from icosim import make_method  # noqa: E402
from icosim.problems.pendulum import runs  # noqa: E402
from icosim.problems.pendulum.integrator.systems import CompiledLink, monolithic_radau  # noqa: E402
from icosim.problems.pendulum.links import Link2  # noqa: E402
from icosim.problems.pendulum.model import PendulumParameters  # noqa: E402
from icosim.problems.pendulum.reference import Monolithic  # noqa: E402
from icosim.problems.pendulum.runs import run_cosimulation  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from reference_radau import NumpyPendulum  # noqa: E402

RUNS = [
    ("baumgarte", {"index": 1, "mu": 1e-3}, "ff", 1),
    ("projection", {}, "ff", 1),
    ("baumgarte", {"index": 1, "mu": 1e-3}, "fd", 1),
    ("projection", {}, "dd", 1),
    ("projection", {}, "dd", 2),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--t-end", type=float, default=0.5, help="simulated time per run (s)")
    ap.add_argument("--H", type=float, default=1e-3, help="macro step (s)")
    ap.add_argument("--tol", type=float, default=1e-6, help="rtol = atol of the subsystem integrator")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", help="write the numbers to this file")
    args = ap.parse_args()
    p = PendulumParameters()
    H, T, tol = args.H, args.t_end, args.tol
    n = int(round(T / H))
    mono = Monolithic(p)
    y0 = mono.initial_state()

    def mono_free():
        return monolithic_radau(p, 0.0, T, y0, rtol=tol, atol=tol)

    def mono_grid():
        y = y0[None, :]
        for i in range(n):
            y = monolithic_radau(p, i * H, (i + 1) * H, y, rtol=tol, atol=tol).y
        return y

    def scipy_free():
        return solve_ivp(mono.rhs, (0.0, T), y0, method="Radau", rtol=tol, atol=tol)

    link = Link2(p, "force")
    coef = np.array([[[1.0, 9.0]]])
    fun = link.rhs(coef, H)
    kernel = CompiledLink(link)
    s2 = p.initial_state()[2:]

    def scipy_link_step():
        return solve_ivp(lambda t, y: fun(t, y[None, :])[0], (0.0, H), s2, method="Radau", rtol=tol, atol=tol)

    def ours_link_step():
        return kernel.radau(coef, H, 0.0, H, s2[None, :], rtol=tol, atol=tol)

    results = {"t_end": T, "H": H, "tol": tol, "macro_steps": n}
    results["monolithic_free"] = best_of(mono_free, args.repeat)
    results["monolithic_free_steps"] = mono_free().n_steps
    results["monolithic_grid"] = best_of(mono_grid, args.repeat)
    results["scipy_radau_free"] = best_of(scipy_free, args.repeat)
    results["scipy_link_step"] = best_of(lambda: [scipy_link_step() for _ in range(20)], args.repeat) / 20
    results["icosim_link_step"] = best_of(lambda: [ours_link_step() for _ in range(20)], args.repeat) / 20
    rows = []
    for name, params, dec, k in RUNS:
        method = make_method(name, **params)

        def cosim(method=method, dec=dec, k=k):
            return run_cosimulation(p, method, dec, k, H=H, t_end=T, rtol=tol, atol=tol)

        t = best_of(cosim, max(1, args.repeat - 1))
        stats = cosim().stats
        # the same run on the tests' numpy reference (radau_batch with the links' closures)
        compiled_problem, runs.PendulumCosimulation = runs.PendulumCosimulation, NumpyPendulum
        try:
            t_numpy = best_of(cosim, max(1, args.repeat - 1))
        finally:
            runs.PendulumCosimulation = compiled_problem
        rows.append(
            {
                "run": f"{name} {dec} k={k}",
                "seconds": t,
                "ms_per_macro_step": 1e3 * t / n,
                "numpy_path_ms_per_macro_step": 1e3 * t_numpy / n,
                "compiled_speedup": t_numpy / t,
                "integrations_per_macro_step": stats["integrations"] / n,
                "radau_steps_per_integration": stats["steps"] / stats["integrations"],
                "vs_monolithic_free": t / results["monolithic_free"],
                "vs_monolithic_grid": t / results["monolithic_grid"],
            }
        )
    results["cosimulation"] = rows

    print(f"Double pendulum, H = {H:g} s, T = {T:g} s ({n} macro steps), Radau IIA rtol = atol = {tol:g}")
    print(
        f"  monolithic, same integrator, free steps : {results['monolithic_free'] * 1e3:8.2f} ms ({results['monolithic_free_steps']} steps)"
    )
    print(f"  monolithic, same integrator, macro grid : {results['monolithic_grid'] * 1e3:8.2f} ms")
    print(f"  monolithic, scipy solve_ivp Radau       : {results['scipy_radau_free'] * 1e3:8.2f} ms")
    print(
        f"  one link over one macro step: scipy solve_ivp Radau {results['scipy_link_step'] * 1e6:.0f} us, icosim.problems.pendulum.integrator.compiled {results['icosim_link_step'] * 1e6:.0f} us"
    )
    print(
        f"{'co-simulation run':24s} {'time [s]':>9s} {'ms/step':>8s} {'numpy ms':>8s} {'speedup':>8s} "
        f"{'int/step':>8s} {'x mono free':>12s} {'x mono grid':>12s}"
    )
    for r in rows:
        print(
            f"{r['run']:24s} {r['seconds']:9.3f} {r['ms_per_macro_step']:8.3f} "
            f"{r['numpy_path_ms_per_macro_step']:8.3f} {r['compiled_speedup']:8.2f} {r['integrations_per_macro_step']:8.1f} "
            f"{r['vs_monolithic_free']:12.0f} {r['vs_monolithic_grid']:12.1f}"
        )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=2)


if __name__ == "__main__":
    main()

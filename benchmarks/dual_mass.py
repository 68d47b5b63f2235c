"""OMSimulator's DualMassOscillator split force/displacement, System2 a drive by position, velocity and acceleration
(docs/fmi.md): the error against the exact solution of DualMassOscillator.mo, and the order of convergence against
the built-in linear model's, per method, index and k.

Two pairs of units: ``c`` -- ``fmus/msd`` with System1's parameters and ``fmus/move_oscillator`` (System2's
equations, integrated exactly, co-simulation); ``om`` -- OMSimulator's own System1 and System2 (OpenModelica 1.24,
``../shared/outside/omsimulator``) as Model Exchange (icosim's integrator, relative tolerance ``--tolerance``).

* ``x1(10 s)``: the scene as a user runs it (the start coupling computed, ``run_scene``), H = 1e-3;
* the order: from the exact start (the coupling history at ``T_0 ... T_-k`` the exact solution's), the largest
  error of ``x1`` over ``[0, 0.25 s]`` at H = 2e-3 ... 2.5e-4, :func:`icosim.order_fit.asymptotic_order`; next to it
  the built-in linear two-mass model's order under the same method, ``k`` and decomposition (the two-unit study).

A measurement to quote (docs/benchmarks.md), never an assertion:

    python benchmarks/dual_mass.py [--units c,om] [--only errors,orders] [--tolerance 1e-12] [--outside DIR]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "tests" / "problems" / "fmu")]

import test_drives_outside  # noqa: E402
from test_drives import AMPLITUDE, builtin_order, exact, exact_start_positions, write  # noqa: E402

from icosim.order_fit import asymptotic_order  # noqa: E402
from icosim.problems.fmu.errors import FmuError, SceneError  # noqa: E402
from icosim.problems.fmu.run import run_scene  # noqa: E402
from icosim.problems.fmu.scene import load_scene  # noqa: E402

CASES = [
    ("projection", 0, {}),
    ("projection", 1, {}),
    ("projection", 2, {}),
    ("baumgarte", 0, {"index": 1, "mu": 1e-3}),
    ("baumgarte", 1, {"index": 1, "mu": 1e-3}),
    ("baumgarte", 2, {"index": 1, "mu": 1e-3}),
    ("baumgarte", 0, {"index": 2, "mu": 1e-3}),
    ("baumgarte", 0, {"index": 3}),
    ("weighted", 0, {"index": 1, "a": 1.0, "b": 1.0}),
    ("weighted", 1, {"index": 1, "a": 1.0, "b": 1.0}),
    ("weighted", 2, {"index": 1, "a": 1.0, "b": 1.0}),
    ("weighted", 0, {"index": 2, "a": 1.0}),
]
HS = [2e-3, 1e-3, 5e-4, 2.5e-4]


def scene(units, tmp, method, k, H, t_end, params, tolerance):
    if units == "om":
        return test_drives_outside.om_scene(tmp, method, k, H, t_end, params, tolerance=tolerance)
    return write(tmp, method, k, H, t_end, params=params)


def error_at_10(units, tmp, method, k, params, tolerance):
    clock = time.perf_counter()
    try:
        run = run_scene(scene(units, tmp, method, k, 1e-3, 10.0, params, tolerance))
    except (FmuError, SceneError) as exc:
        return f"refused: {str(exc).split(': ', 2)[-1][:90]}"
    wall = time.perf_counter() - clock
    if run.status != "completed":
        return f"{run.status} ({run.reason[:60]})"
    x = run.states[-1, 0, 0]
    err = abs(x - exact([10.0])[0, 0])
    return f"x1(10) = {x:.10f}, error {err:.3e} m = {err / AMPLITUDE:.2e} of the amplitude ({wall:.0f} s)"


def order(units, tmp, method, k, params, tolerance):
    errors = []
    for H in HS:
        try:
            sc = load_scene(scene(units, tmp, method, k, H, 0.25, params, tolerance))
            x = exact_start_positions(sc)
        except (FmuError, SceneError) as exc:
            return f"refused: {str(exc).split(': ', 2)[-1][:90]}"
        ok = len(x) == sc.n_steps + 1
        errors.append(float(np.max(np.abs(x - exact(H * np.arange(len(x)))[:, 0]))) if ok else np.nan)
    fit = asymptotic_order(HS, errors)
    built = builtin_order(method, k, HS, params=params)
    text = " ".join(f"{e:.2e}" for e in errors)
    return f"errors {text}: order {fit.order:.2f} ({fit.status}); built-in {built:.2f}"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--units", default="c,om")
    parser.add_argument("--only", default="errors,orders")
    parser.add_argument("--tolerance", type=float, default=1e-12)
    parser.add_argument("--outside", type=Path, default=test_drives_outside.OUTSIDE, help="the other tools' units")
    args = parser.parse_args(argv)
    test_drives_outside.UNITS = args.outside / "omsimulator"
    with tempfile.TemporaryDirectory(prefix="icosim-dual-mass-") as tmp:
        for units in args.units.split(","):
            for method, k, params in CASES:
                label = f"{units:2s} {method} {params.get('index', '')} k={k}"
                if "errors" in args.only:
                    print(label, "|", error_at_10(units, Path(tmp), method, k, params, args.tolerance), flush=True)
                if "orders" in args.only:
                    print(label, "|", order(units, Path(tmp), method, k, params, args.tolerance), flush=True)


if __name__ == "__main__":
    main()

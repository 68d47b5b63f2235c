"""What sub-steps cost and buy: a unit that cannot interpolate its inputs (no input derivatives) is stepped in
``coupling.substeps`` doSteps per integration, each with the coupling polynomial's value at the sub-step's midpoint.

For ``substeps`` 1, 2, 4, 8, 16 (and the references 64, 128), each-step and first-step sensitivities, at each
macro step ``H``: the doStep calls per macro step of each unit, the wall time of the whole run (the minimum of the
timed runs after a warm-up, as benchmarks/peers.py measures), and two errors at the end time:

* **sub-steps' share**: the difference to the same run with 128 sub-steps.  The route's error is of second order
  in the sub-step ``H/substeps``, so that reference is ``|x(64) - x(128)| / 3`` from the limit; the ratio of
  successive differences (about 4 per doubling) is printed as the check.
* **total**: against the truth -- on OSP's quarter truck libcosim's extrapolated fixed-step run with the units' RK4
  (benchmarks/peers.py's reference, its own error printed), on the DualMassOscillator the exact solution of
  DualMassOscillator.mo (tests/problems/fmu/test_drives.exact).  Sub-steps matter where their share is not small
  against the total.

The systems: **quarter truck** (OSP's Chassis and Wheel, ``../shared/outside/osp-quarter-truck``; neither
interpolates its inputs; the units' solver RK4 at 1e-5 s so that their own error is below the coupling's, and as
the file sets them, Euler) joined as icosim.studies.peers.runners.truck_scene does, Baumgarte index 1 with
``mu = 10 H``, k = 1; **DualMassOscillator** (fmus/msd with System1's parameters and fmus/move_oscillator,
System2's equations: tests/problems/fmu/test_drives.write, units that integrate exactly) with ``inputs:
substeps`` forced, beside the same run with input derivatives (``inputs: derivatives``, the exact input).
OMSimulator's own System1 and System2 run as Model Exchange, where the coupling polynomial is the input at every
right-hand side evaluation: sub-steps do not apply there.  A measurement to quote (docs/benchmarks.md), never an
assertion:

    python benchmarks/substeps.py [--only truck,dmo] [--repeat 3] [--budget 8] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "benchmarks"), str(ROOT / "tests"), str(ROOT / "tests" / "problems" / "fmu")]

import peers  # noqa: E402
from test_drives import exact, write  # noqa: E402

from icosim.problems.fmu.run import run_dataset_data, run_scene  # noqa: E402
from icosim.studies.peers import runners as P  # noqa: E402

SUBSTEPS = [1, 2, 4, 8, 16]
REFERENCES = [64, 128]
T_TRUCK, T_DMO = 1.0, 2.0


def with_coupling(path: Path, **coupling) -> Path:
    """The scene at ``path`` with ``coupling`` keys set, written beside it."""
    data = yaml.safe_load(path.read_text())
    data["coupling"] |= coupling
    out = path.with_name(f"{path.stem}_{'_'.join(f'{k}{v}' for k, v in coupling.items())}.yaml")
    out.write_text(yaml.safe_dump(data, sort_keys=False))
    return out


def outcome(path: Path, body: int = 0) -> dict:
    """A whole run (``run_scene``): the end time, position and velocity of ``body``, each unit's doStep calls per
    macro step (the checks' probing steps apart)."""
    run = run_scene(path)
    attrs = run_dataset_data(run).attrs
    steps = len(run.times) - 1
    per_unit = {name: int(attrs[f"{name}_do_step_calls"]) / steps for name in run.scene.names}
    return {"t": float(run.times[-1]), "x": float(run.states[-1, body, 0]), "v": float(run.states[-1, body, 1]),
            "status": run.status, "reason": run.reason, "macro_steps": steps, "per_macro_step": per_unit,
            "do_steps": int(attrs["do_step_calls"])}  # fmt: skip


def measured(make, t_end, args) -> dict:
    """The run of ``make(t_end)`` with its minimum wall time (peers.measure: a warm-up, then timed runs)."""
    out, wall, runs = peers.measure(lambda t: outcome(make(t)), t_end, args.repeat, args.budget)
    return out | {"wall": wall, "runs": runs}


def sweep(label, make, error, t_end, args) -> list:
    """Rows for every sub-step count and sensitivity choice of ``make(t, substeps, sensitivities)``; errors against
    the 128 sub-steps run and the total ``error(outcome)`` (x, v)."""
    with P.quiet():  # the quarter truck's units print banners
        refs = {n: outcome(make(t_end, n, "each-step")) for n in REFERENCES}
    d = abs(refs[64]["x"] - refs[128]["x"]), abs(refs[64]["v"] - refs[128]["v"])
    print(f"{label}: 64 against 128 sub-steps differ by {d[0]:.2e} m, {d[1]:.2e} m/s (the 128's share ~ a third)")
    rows = []
    for sens in ("each-step", "first-step"):
        for n in SUBSTEPS:
            r = measured(lambda t, n=n, s=sens: make(t, n, s), t_end, args)
            if r["status"] != "completed":
                rows.append({"system": label, "substeps": n, "sensitivities": sens, "status": r["status"]})
                print(f"  {n:3d} {sens:10s} {r['status']}: {r['reason']}", flush=True)
                continue
            total = error(r)
            r |= {"system": label, "substeps": n, "sensitivities": sens,
                  "share_x": abs(r["x"] - refs[128]["x"]), "share_v": abs(r["v"] - refs[128]["v"]),
                  "total_x": total[0], "total_v": total[1]}  # fmt: skip
            rows.append(r)
            per = ", ".join(f"{k} {v:g}" for k, v in r["per_macro_step"].items())
            print(f"  {n:3d} {sens:10s} share {r['share_x']:.2e} m {r['share_v']:.2e} m/s  total {r['total_x']:.2e} "
                  f"m {r['total_v']:.2e} m/s  wall {r['wall']:.3f} s  doSteps per macro step: {per}", flush=True)  # fmt: skip
    ratios = [abs(rows[i]["share_x"] / rows[i + 1]["share_x"]) for i in range(len(SUBSTEPS) - 1)
              if rows[i + 1].get("share_x")]  # fmt: skip
    print(f"  share ratios per doubling (x, each-step): {[round(q, 2) for q in ratios]}")
    return rows


def truck(tmp: Path, args, versions) -> list:
    rows = []
    if peers.available(versions, "libcosim"):
        ref = peers.truck_reference(tmp)
        print(f"reference x(1 s) = {ref['x']:.12f} m (error ~{ref['x_error']:.1e}), v = {ref['v']:.10f} m/s "
              f"(~{ref['v_error']:.1e})", flush=True)  # fmt: skip
        at = peers.truck_error(ref)
        error = lambda o: (at(o)["error_x"], at(o)["error_v"])  # noqa: E731
    else:
        print(f"no reference for the total error: libcosim {versions['libcosim']}")
        error = lambda o: (float("nan"), float("nan"))  # noqa: E731
    for solver in ("RK4", "Euler"):
        for H in args.truck_H:

            def make(t, n=16, sens="each-step", H=H, s=solver):
                return with_coupling(
                    P.truck_scene(tmp, H, 1, t, unit_dir=peers.TRUCK, solver=s), substeps=n, sensitivities=sens
                )

            rows += sweep(f"quarter truck, units {solver}, H = {H:g}", make, error, T_TRUCK, args)
    return rows


def dmo_error(o) -> tuple:
    """x1 and v1 at the run's end against the exact solution."""
    x1, _, v1, _ = exact([o["t"]])[0]
    return abs(o["x"] - x1), abs(o["v"] - v1)


def dmo(tmp: Path, args) -> list:
    rows = []
    for k, H in ((1, 1e-3), (2, 1e-2)):

        def make(t, n=16, sens="each-step", k=k, H=H):
            path = write(tmp, "baumgarte", k, H, t, params={"index": 1, "mu": 10 * H})
            return with_coupling(path, inputs="substeps", substeps=n, sensitivities=sens)

        exact_inputs = outcome(with_coupling(write(tmp, "baumgarte", k, H, T_DMO, params={"index": 1, "mu": 10 * H}),
                                             inputs="derivatives"))  # fmt: skip
        print(f"DualMassOscillator, k = {k}, H = {H:g}: with input derivatives the error is "
              f"{dmo_error(exact_inputs)[0]:.2e} m, {dmo_error(exact_inputs)[1]:.2e} m/s")  # fmt: skip
        rows += sweep(f"DualMassOscillator, k = {k}, H = {H:g}", make, dmo_error, T_DMO, args)
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default="truck,dmo", help="truck, dmo (comma-separated)")
    parser.add_argument("--repeat", type=int, default=3, help="timed runs after the warm-up (fewer past --budget)")
    parser.add_argument("--budget", type=float, default=8.0, help="seconds of timed runs per setting")
    parser.add_argument("--truck-H", type=float, nargs="+", default=[4e-3, 1e-3], help="the truck's macro steps")
    parser.add_argument("--json", type=Path, help="write the rows here")
    args = parser.parse_args(argv)
    versions = peers.installed()
    load = os.getloadavg()
    print(f"masters: {versions}\nload average at the start: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}", flush=True)
    clock, rows = time.perf_counter(), []
    with tempfile.TemporaryDirectory(prefix="icosim-substeps-") as tmp:
        if "dmo" in args.only:
            rows += dmo(Path(tmp), args)
        if "truck" in args.only:
            rows += truck(Path(tmp), args, versions)
    end = os.getloadavg()
    print(f"load average at the end: {end[0]:.2f} {end[1]:.2f} {end[2]:.2f}; {time.perf_counter() - clock:.0f} s")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1, default=float))


if __name__ == "__main__":
    main()

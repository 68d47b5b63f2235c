"""Work-precision against the peers: icosim beside libcosim (fixed step and ECCO), Ecos and FMPy's ``simulate_ssp``
on the same unit files, side by side in one run (SciMLBenchmarks style).

For each system, master and setting: the error against a reference, the wall time (the minimum of the timed runs
after a warm-up run over a tenth of the interval; a run longer than ``--budget`` seconds is timed once), and the
doStep calls.  Each run is one whole run as its users start it: the units loaded, initialised and stepped to the
stop time (icosim: ``run_scene`` in the process, the units checked first; their probing steps are counted apart).

* **quarter truck** (OSP's ``Chassis.fmu`` and ``Wheel.fmu`` with libcosim's ``OspSystemStructure.xml``): the
  chassis's position and velocity at 1 s.  The **reference** is libcosim's fixed step with the units' solver RK4
  (step ``min(h, 1e-5)``) at h = 4e-5, 2e-5, 1e-5, 5e-6, extrapolated (Richardson, first order): the differences
  of the plain runs halve with h (the ratios are printed), those of the extrapolated ones fall by about 4, and the
  reference's error is taken as the last extrapolated difference.  A master that ends past 1 s (ECCO's last step)
  is compared with the reference carried to its end time by its acceleration (Taylor, second order).
  The units as in the file (explicit Euler at 1e-5 s, ``units: Euler``) and, to show the coupling's error alone,
  with RK4 (``units: RK4``).
* **DualMassOscillator** (OMSimulator's System1 and System2): x1 and x2 at 10 s against the exact solution of
  DualMassOscillator.mo (tests/problems/fmu/test_drives.exact); the peers run the units' co-simulation (explicit
  Euler at the communication step inside), icosim their Model Exchange (they cannot roll back a co-simulation step).
  OMSimulator's own published results (its tests' ``## Result`` blocks) are listed beside.

A peer that is not installed, or cannot run a system, is a row with its reason.  Then, per system and error level,
the fastest setting of each master and the ratio of icosim's time to each peer's.  The runners are those of
icosim.studies.peers.runners (the workflow's peers study runs them on fewer settings).  A measurement to quote
(docs/benchmarks.md), never an assertion:

    python benchmarks/peers.py [--only truck,dmo] [--repeat 3] [--budget 8] [--quick] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import tempfile
import time
import traceback
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "tests" / "problems" / "fmu")]

from test_drives import exact  # noqa: E402
from test_drives_outside import BAUMGARTE  # noqa: E402
from test_peers import OMSIMULATOR_CS, OMSIMULATOR_ME  # noqa: E402
from toolchains import OUTSIDE  # noqa: E402

from icosim.studies.peers import runners as P  # noqa: E402
from icosim.studies.peers.fastest import fastest as peer_fastest  # noqa: E402
from icosim.studies.peers.masters import available, installed  # noqa: E402
from icosim.studies.peers.timing import measure  # noqa: E402

T_TRUCK, T_DMO = 1.0, 10.0
UNIT_STEP = 1e-5  # the quarter truck's units' internal step in the file
LEVELS = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7]
TRUCK, OM = OUTSIDE / "osp-quarter-truck", OUTSIDE / "omsimulator"


def row(system, master, setting, units="", group=None):
    """``group``: the rows compared with each other (the quarter truck's per unit solver; default ``units``)."""
    return {"system": system, "master": master, "setting": setting, "units": units,
            "group": units if group is None else group}  # fmt: skip


def attempt(base, run, t_end, args, error, H=None):
    """A row with the measured error, wall time, runs and doSteps; a run that fails or diverges is a row too."""
    try:
        outcome, wall, runs = measure(run, t_end, args.repeat, args.budget, H)
    except Exception as exc:  # a peer's or a scene's failure is reported by name, never dropped
        return base | {"status": f"failed: {type(exc).__name__}: {str(exc).splitlines()[0][:400]}"}
    if outcome.get("status", "completed") != "completed":
        return base | {"status": f"{outcome['status']}: {outcome.get('reason', '')[:200]}", "wall": wall}
    return base | {"status": "completed", "wall": wall, "runs": runs, "t": outcome["t"],
                   "do_steps": outcome.get("do_steps"), "check_steps": outcome.get("check_steps"),
                   **error(outcome)}  # fmt: skip


def added(rows: list, r: dict, label: str, errors) -> None:
    """Append the row ``r`` and print it: ``label``, then its errors (``errors(r)``), wall time and doSteps, or why
    it did not complete."""
    rows.append(r)
    measured = f"{errors(r)}  wall {r['wall']:.3f} s  doSteps {r['do_steps']}" if r["status"] == "completed" else None
    print(f"  {label} {measured or r['status']}", flush=True)


# -- the quarter truck ------------------------------------------------------------------------------------------


def truck_reference(tmp: Path) -> dict:
    """libcosim fixed step, units RK4, h halved thrice, extrapolated; what shows it converges."""
    hs = [4e-5, 2e-5, 1e-5, 5e-6]
    with P.quiet():
        runs = [P.libcosim_truck(P.truck_osp(tmp / f"ref_{h:g}", h, unit_dir=TRUCK, solver="RK4",
                                             time_step=min(h, 1e-5)), T_TRUCK) for h in hs]  # fmt: skip
    out = {"steps": hs}
    for key in ("x", "v", "a"):
        plain = np.array([r[key] for r in runs])
        rich = 2 * plain[1:] - plain[:-1]
        out[key] = float(rich[-1])
        out[f"{key}_plain"] = plain.tolist()
        out[f"{key}_extrapolated"] = rich.tolist()
        out[f"{key}_plain_ratios"] = (np.diff(plain)[:-1] / np.diff(plain)[1:]).tolist()
        out[f"{key}_extrapolated_ratio"] = float((rich[1] - rich[0]) / (rich[2] - rich[1]))
        out[f"{key}_error"] = float(abs(rich[-1] - rich[-2]))
    return out


def truck_error(ref):
    def error(o):
        dt = o["t"] - T_TRUCK  # ECCO's last step ends past the stop time
        x = ref["x"] + ref["v"] * dt + 0.5 * ref["a"] * dt**2
        v = ref["v"] + ref["a"] * dt
        return {"error_x": abs(o["x"] - x), "error_v": abs(o["v"] - v)}

    return error


def truck_rows(tmp: Path, args, versions) -> tuple[list, dict | None]:
    system, rows = "quarter truck", []
    ref = None
    if available(versions, "libcosim"):
        ref = truck_reference(tmp)
        print(f"reference x(1 s) = {ref['x']:.12f} m (error ~{ref['x_error']:.1e}), v = {ref['v']:.10f} m/s "
              f"(~{ref['v_error']:.1e}); plain ratios {np.round(ref['x_plain_ratios'], 3).tolist()}, extrapolated "
              f"{ref['x_extrapolated_ratio']:.2f}", flush=True)  # fmt: skip
    else:
        rows.append(row(system, "reference", "libcosim fixed step, RK4") | {"status": versions["libcosim"]})
        return rows, None
    error = truck_error(ref)
    quick = args.quick
    solvers = ["Euler", "RK4"]

    def add(base, run, H=None):
        added(rows, attempt(base, run, T_TRUCK, args, error, H), f"{base['master']:9s} {base['setting']:42s} "
              f"{base['units']:5s}", lambda r: f"err x {r['error_x']:.2e}")  # fmt: skip

    for solver in solvers:
        # libcosim fixed step and ECCO
        if available(versions, "libcosim"):
            steps = [1e-3, 1e-4, 1e-5] if quick else [1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5]
            for h in steps if solver == "Euler" else [1e-3, 1e-4, 1e-5]:
                folder = P.truck_osp(tmp / f"lc_{solver}_{h:g}", h, unit_dir=TRUCK, solver=solver, time_step=UNIT_STEP)
                add(row(system, "libcosim", f"fixed step {h:g}", solver),
                    lambda t, f=folder: P.libcosim_truck(f, t))  # fmt: skip
            for tol in [1e-4, 1e-6] if quick else [1e-4, 1e-5, 1e-6, 1e-7]:
                folder = P.truck_osp(tmp / f"ecco_{solver}_{tol:g}", 1e-4, unit_dir=TRUCK, algorithm="ecco",
                                     solver=solver, time_step=UNIT_STEP, tolerance=tol)  # fmt: skip
                label = "ECCO, the file's" if tol == 1e-6 else f"ECCO, tolerances {tol:g}"
                add(row(system, "libcosim", label, solver), lambda t, f=folder: P.libcosim_truck(f, t))
        else:
            rows.append(row(system, "libcosim", "all", solver) | {"status": versions["libcosim"]})
        if available(versions, "Ecos"):
            for h in [1e-3, 1e-4, 1e-5]:
                add(row(system, "Ecos", f"fixed step {h:g}", solver),
                    lambda t, h=h, s=solver: P.ecos_truck(h, t, unit_dir=TRUCK, solver=s,
                                                          time_step=UNIT_STEP))  # fmt: skip
        else:
            rows.append(row(system, "Ecos", "all", solver) | {"status": versions["Ecos"]})
        if solver == "Euler":
            rows.append(row(system, "FMPy", "simulate_ssp", solver) | {"status": (
                "not run: simulate_ssp sets Real, Integer and Boolean values only, and the file sets the units' "
                "String solverType (Euler); with the units' default solver (VRK2) it would run other units")})  # fmt: skip
        # icosim: Baumgarte index 1 with mu = 10 H (the truck_scene default)
        Hs = [4e-3, 1e-3] if quick else [8e-3, 4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4]
        variants = [(k, H, 16, "each-step") for k in ([0, 1, 2] if solver == "Euler" else [1]) for H in Hs]
        variants += [(1, H, 4, "each-step") for H in ([2e-3] if quick else [4e-3, 2e-3, 1e-3, 5e-4])]
        variants += [(1, H, 64, "each-step") for H in ([1e-3] if quick else [1e-3, 5e-4])]
        variants += [(1, H, n, "first-step") for H, n in [(8e-3, 4), (4e-3, 4), (2e-3, 4), (1e-3, 4), (5e-4, 4),
                                                           (1e-3, 16)]]  # fmt: skip
        variants += [(2, 4e-3, 4, "first-step")]
        for k, H, n, sens in variants:
            label = f"Baumgarte 1, k = {k}, H = {H:g}" + ("" if n == 16 else f", {n} sub-steps")
            label += "" if sens == "each-step" else ", first-step sensitivities"
            coupling = {"substeps": n, "sensitivities": sens}
            add(row(system, "icosim", label, solver),
                lambda t, H=H, k=k, c=coupling, s=solver: P.icosim_run(
                    P.truck_scene(tmp, H, k, t, unit_dir=TRUCK, solver=s, coupling=c)), H)  # fmt: skip
        if solver == "Euler":
            add(
                row(system, "icosim", "projection, k = 1, H = 0.001", solver),
                lambda t: P.icosim_run(P.truck_scene(tmp, 1e-3, 1, t, unit_dir=TRUCK, method="projection")),
            )
            for tol in [1e-3, 1e-5]:
                control = {"control": {"tolerance": tol, "H_min": 1e-7, "H_max": 1e-2}}
                add(row(system, "icosim", f"Baumgarte 1, k = 1, controlled, tolerance {tol:g}", solver),
                    lambda t, c=control: P.icosim_run(P.truck_scene(tmp, 1e-4, 1, t, unit_dir=TRUCK,
                                                                    coupling=c)))  # fmt: skip
            # ECCO's own estimate (the power residual) in icosim, at ECCO's first step and bounds of the file
            for tol in [1e-5, 1e-6]:
                control = {"substeps": 4, "sensitivities": "first-step",
                           "control": {"estimate": "power-residual", "absolute_tolerance": tol, "H_min": 1e-5,
                                       "H_max": 1e-2}}  # fmt: skip
                add(row(system, "icosim", f"Baumgarte 1, k = 1, power residual, tolerances {tol:g}, 4 sub-steps, "
                        "first-step sensitivities", solver),
                    lambda t, c=control: P.icosim_run(P.truck_scene(tmp, 1e-4, 1, t, unit_dir=TRUCK,
                                                                    coupling=c)))  # fmt: skip
    return rows, ref


# -- the DualMassOscillator -------------------------------------------------------------------------------------


def dmo_error(o):
    x1, x2 = exact([o["t"]])[0, :2]
    return {"error_x": abs(o["x1"] - x1), "error_x2": abs(o["x2"] - x2)}


def icosim_dmo(tmp: Path, k: int, H: float, t_end: float, tolerance: float, coupling: dict) -> dict:
    path = P.dmo_scene(tmp, "baumgarte", k, H, t_end, BAUMGARTE, unit_dir=OM, tolerance=tolerance,
                       record=("mass2.s",), coupling=coupling)  # fmt: skip
    out = P.icosim_run(path)
    return out | {"x1": out["x"], "x2": out.get("system2.mass2.s", math.nan)}


def dmo_adder(rows: list, args):
    """``add(base, run, H=None)``: a DualMassOscillator row measured, appended and printed."""

    def add(base, run, H=None):
        added(rows, attempt(base, run, T_DMO, args, dmo_error, H), f"{base['master']:11s} {base['setting']:50s}",
              lambda r: f"err x1 {r['error_x']:.2e} x2 {r['error_x2']:.2e}")  # fmt: skip

    return add


def dmo_peer_rows(tmp: Path, args, versions, system="DualMassOscillator") -> list:
    """The peers' fixed-step runs of the units' co-simulation with OMSimulator's four connections, and
    OMSimulator's published results."""
    rows: list = []
    add = dmo_adder(rows, args)
    cs = {"units": "co-simulation", "group": ""}
    steps = [1e-3, 1e-4] if args.quick else [1e-3, 1e-4, 1e-5]
    if available(versions, "libcosim"):
        for h in steps:
            folder = P.dmo_osp(tmp / f"dmo_lc_{h:g}", h, unit_dir=OM)
            add(row(system, "libcosim", f"fixed step {h:g}", **cs),
                lambda t, f=folder: P.libcosim_dmo(f, t))  # fmt: skip
    else:
        rows.append(row(system, "libcosim", "all", **cs) | {"status": versions["libcosim"]})
    if available(versions, "Ecos"):
        for h in steps:
            add(row(system, "Ecos", f"fixed step {h:g}", **cs), lambda t, h=h: P.ecos_dmo(h, t, unit_dir=OM))
    else:
        rows.append(row(system, "Ecos", "all", **cs) | {"status": versions["Ecos"]})
    if available(versions, "FMPy"):
        ssp = P.dmo_ssp(tmp / "DualMassOscillator.ssp", unit_dir=OM)
        for h in steps:
            add(row(system, "FMPy", f"simulate_ssp, fixed step {h:g}", **cs), lambda t, h=h: P.fmpy_dmo(ssp, h, t))
    else:
        rows.append(row(system, "FMPy", "all", **cs) | {"status": versions["FMPy"]})
    for name, (x1, x2) in [("co-simulation, fixed step 1e-4", OMSIMULATOR_CS),
                           ("model exchange, CVODE, 1e-4", OMSIMULATOR_ME)]:  # fmt: skip
        rows.append(row(system, "OMSimulator", f"published: {name}", **cs)
                    | {"status": "published", "t": T_DMO, **dmo_error({"t": T_DMO, "x1": x1, "x2": x2})})  # fmt: skip
    return rows


def dmo_rows(tmp: Path, args, versions) -> list:
    system, quick = "DualMassOscillator", args.quick
    rows = dmo_peer_rows(tmp, args, versions, system)
    add = dmo_adder(rows, args)
    # Baumgarte index 1 with mu = 10 H (with mu = 1e-3 s it diverges at H = 2.5e-3 s), first-step sensitivities
    # (exact for linear units, as these are), the Model Exchange integrator's tolerance as said
    cases = [(2, 1e-2, 1e-8, "first-step"), (2, 5e-3, 1e-8, "first-step"), (1, 1e-2, 1e-8, "first-step")]
    if not quick:
        cases += [(2, 2e-2, 1e-8, "first-step"), (2, 2e-3, 1e-8, "first-step"), (1, 5e-3, 1e-8, "first-step"),
                  (1, 2e-3, 1e-8, "first-step"), (0, 5e-3, 1e-8, "first-step"), (2, 5e-3, 1e-10, "each-step"),
                  (2, 5e-2, 1e-6, "first-step"), (1, 5e-2, 1e-6, "first-step"), (2, 2e-2, 1e-6, "first-step")]  # fmt: skip
    for k, H, tol, sens in sorted(cases):
        label = f"Baumgarte 1, k = {k}, H = {H:g}, integrator tolerance {tol:g}, {sens} sensitivities"
        coupling = {"mu": 10 * H, "sensitivities": sens}
        add(row(system, "icosim", label, "model exchange", ""),
            lambda t, k=k, H=H, tol=tol, c=coupling: icosim_dmo(tmp, k, H, t, tol, c), H)  # fmt: skip
    for tol in [1e-4, 1e-6] if quick else [1e-4, 1e-5, 1e-6, 1e-7]:
        label = f"Baumgarte 1 (mu = 0.02), k = 2, controlled, tolerance {tol:g}, H_max = 0.005"
        coupling = {"mu": 2e-2, "sensitivities": "first-step",
                    "control": {"tolerance": tol, "H_min": 1e-7, "H_max": 5e-3}}  # fmt: skip
        add(row(system, "icosim", label, "model exchange", ""),
            lambda t, c=coupling: icosim_dmo(tmp, 2, 1e-3, t, 1e-8, c), 1e-3)  # fmt: skip
    return rows


# -- who reaches each error fastest -----------------------------------------------------------------------------


def fastest(rows: list, levels=LEVELS) -> list:
    """Per system, units, error measure and level: each master's fastest setting with that error at or below the
    level, and icosim's time over each peer's.  The measures: the quarter truck's position and velocity apart (m,
    m/s), the DualMassOscillator's larger of x1 and x2 (m)."""
    return [e for key in ("error_x", "error_v") for e in _fastest(rows, levels, key)]


def _fastest(rows, levels, key) -> list:
    """icosim.studies.peers.fastest.fastest per system and group on the error ``key`` (with x2 beside x1)."""
    table = []
    done = [r for r in rows if r.get("status") == "completed"]
    for system in dict.fromkeys(r["system"] for r in done):
        for units in dict.fromkeys(r["group"] for r in done if r["system"] == system):
            group = [r for r in done if r["system"] == system and r["group"] == units]
            measured = [r | {"error": max(r[key], r.get("error_x2", 0.0))} for r in group if key in r]
            measure = {"error_x": "x1, x2" if "error_x2" in group[0] else "position", "error_v": "velocity"}
            for e in peer_fastest(measured, levels):
                table.append({"system": system, "units": units, "measure": measure[key], "level": e["level"],
                              "best": {m: {"setting": r["setting"], "wall": r["wall"], "do_steps": r["do_steps"]}
                                       for m, r in e["best"].items()}, "icosim_over": e["icosim_over"]})  # fmt: skip
    return table


def print_table(rows, summary):
    print("\n| system | units | master | setting | error x | error v or x2 | wall (s) | runs | doSteps |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        if r.get("status") in ("completed", "published"):
            other = r.get("error_v", r.get("error_x2", math.nan))
            wall = f"{r['wall']:.3f}" if "wall" in r else "-"
            print(f"| {r['system']} | {r['units']} | {r['master']} | {r['setting']} | {r['error_x']:.2e} | "
                  f"{other:.2e} | {wall} | {r.get('runs', '-')} | {r.get('do_steps') or '-'} |")  # fmt: skip
        else:
            print(f"| {r['system']} | {r['units']} | {r['master']} | {r['setting']} | {r['status']} |||||")
    print("\n| system | units | error of | at most | fastest per master (wall s, doSteps) | icosim / peer |")
    print("|---|---|---|---|---|---|")
    for e in summary:
        best = "; ".join(f"{m}: {b['setting']} ({b['wall']:.3f}, {b['do_steps']})" for m, b in e["best"].items())
        ratios = ", ".join(f"{m} {v:.2f}" for m, v in e.get("icosim_over", {}).items()) or "-"
        print(f"| {e['system']} | {e['units']} | {e['measure']} | {e['level']:.0e} | {best} | {ratios} |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default="truck,dmo", help="truck, dmo (comma-separated)")
    parser.add_argument("--repeat", type=int, default=3, help="timed runs after the warm-up (fewer past --budget)")
    parser.add_argument("--budget", type=float, default=8.0, help="seconds of timed runs per setting")
    parser.add_argument("--quick", action="store_true", help="fewer settings (development)")
    parser.add_argument("--json", type=Path, help="write the rows, the reference and the summary here")
    args = parser.parse_args(argv)
    unknown = set(args.only.split(",")) - {"truck", "dmo"}
    if unknown:
        parser.error(f"--only: unknown {sorted(unknown)}; allowed: truck, dmo")
    if not (OUTSIDE / "README.md").is_file():
        parser.error(f"the other tools' units are not in {OUTSIDE}")
    versions = installed()
    load = os.getloadavg()
    print(f"masters: {versions}\nload average at the start: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}", flush=True)
    rows, reference = [], None
    clock = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="icosim-peers-") as tmp:
        try:
            if "truck" in args.only:
                print(f"quarter truck, {T_TRUCK:g} s:", flush=True)
                truck, reference = truck_rows(Path(tmp), args, versions)
                rows += truck
            if "dmo" in args.only:
                print(f"DualMassOscillator, {T_DMO:g} s:", flush=True)
                rows += dmo_rows(Path(tmp), args, versions)
        except KeyboardInterrupt:
            traceback.print_exc()
    summary = fastest(rows)
    print_table(rows, summary)
    end = os.getloadavg()
    print(f"\nload average at the end: {end[0]:.2f} {end[1]:.2f} {end[2]:.2f}; {time.perf_counter() - clock:.0f} s")
    if args.json:
        machine = {"python": platform.python_version(), "processor": platform.processor() or platform.machine(),
                   "cpus": os.cpu_count(), "load_start": load, "load_end": end}  # fmt: skip
        args.json.write_text(json.dumps({"masters": versions, "machine": machine, "reference": reference,
                                         "rows": rows, "fastest": summary}, indent=1, default=float))  # fmt: skip


if __name__ == "__main__":
    main()

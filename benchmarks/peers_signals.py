"""Work-precision against the peers on signal-coupled systems: icosim's explicit and implicit coupling of signal
connections beside libcosim (fixed step), Ecos and FMPy's ``simulate_ssp`` on the same unit files, timed as
benchmarks/peers.py times them (its runners, rows and summary).

* **DualMassOscillator by signals** (OMSimulator's System1 and System2, its four connections F, x1, v1, a1): x1
  and x2 at 10 s against the exact solution (tests/problems/fmu/test_drives.exact).  The peers' fixed-step runs
  of the units' co-simulation as in benchmarks/peers.py; icosim explicit Jacobi (k = 0, 1, 2) on the Model
  Exchange units and on the co-simulation ones, and implicit (Newton on the connections' conditions at T_N+1,
  k = 0, 1, 2) on the Model Exchange units (the co-simulation units cannot save their state).
* **QuarterCarModel** (OMSimulator's, both decompositions, the road of road.csv on the Wheel's ``z``): the
  Chassis's position and velocity at 1 s against the ReferenceSystem of QuarterCarModel.mo
  (tests/problems/fmu/test_quarter_car.exact).  How each peer gets the road: tests/problems/fmu/test_peers_signals.py.

Each icosim row also says its doSteps per macro step, Newton's iterations (mean), the perturbed steps of the
Jacobian and the Model Exchange units' right-hand-side evaluations: what its time goes to.  A measurement to quote
(docs/benchmarks.md), never an assertion:

    python benchmarks/peers_signals.py [--only dmo,quarter-car] [--repeat 2] [--budget 6] [--quick] [--json FILE]
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

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))

import peers  # noqa: E402
import test_peers_signals as S  # noqa: E402
from peers import P, added, attempt, available, dmo_peer_rows, fastest, installed, row  # noqa: E402
from test_quarter_car import exact as qc_exact  # noqa: E402
from test_signals_outside import CONNECTIONS as DMO_CONNECTIONS  # noqa: E402

from icosim.problems.fmu.scene import load_scene  # noqa: E402
from icosim.problems.fmu.signal_scene import run_signal_scene  # noqa: E402

T_QC = 1.0
SYSTEMS = ("dmo", "quarter-car")


def icosim_signals(path: Path) -> dict:
    """A signal scene's run as ``icosim cosim`` runs it (in the process): the end time, the last value of every
    connected and recorded variable, the doSteps summed over the units (for a Model Exchange unit its
    integrations over a step, the perturbed ones included), Newton's iterations and the Jacobians' perturbed steps,
    the right-hand-side evaluations."""
    run = run_signal_scene(load_scene(path))
    out = {"t": float(run.times[-1]), "status": run.status, "reason": run.reason,
           **{key: float(values[-1]) for key, values in run.series.items()}}  # fmt: skip
    out["do_steps"] = sum(int(u["do_step_calls"]) for u in run.units.values())
    out["rhs"] = sum(int(u.get("rhs_evaluations", 0)) for u in run.units.values())
    out["macro_steps"] = len(run.times) - 1
    if run.iterations:
        out |= {"newton": sum(run.iterations) / len(run.iterations), "jacobian_steps": run.jacobian_steps}
    return out


def scene_file(tmp: Path, name: str, data: dict) -> Path:
    path = tmp / f"{name}_{len(list(tmp.iterdir()))}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def coupling_label(k, H, implicit, interface, tol=None):
    how = "implicit" if implicit else "explicit Jacobi"
    units = "" if tol is None else f", integrator tolerance {tol:g}"
    return f"{how}, k = {k}, H = {H:g}{units}" if interface == "model-exchange" else f"{how}, k = {k}, H = {H:g}"


def cost(r: dict) -> dict:
    """What an icosim row's time goes to."""
    if r.get("status") != "completed" or not r.get("macro_steps"):
        return {}
    out = {"do_steps_per_step": r["do_steps"] / r["macro_steps"]}
    for key in ("newton", "jacobian_steps", "rhs"):
        if r.get(key):
            out[key] = r[key]
    return out


def recorded(run):
    """``run`` keeping its last outcome's Newton and integration counters (``attempt`` keeps the errors only) as
    ``.last``."""

    def wrapped(t):
        out = run(t)
        wrapped.last = {k: out[k] for k in ("newton", "jacobian_steps", "rhs") if k in out}  # type: ignore[attr-defined]
        return out

    wrapped.last = {}  # type: ignore[attr-defined]
    return wrapped


def measured(base, run, t_end, args, error, H):
    """The row of ``run`` (a :func:`recorded` one) with its cost per macro step."""
    r = attempt(base, run, t_end, args, error, H)
    return r | cost(r | {"macro_steps": round(t_end / H), **run.last})


# -- the DualMassOscillator by signals ----------------------------------------------------------------------------


def dmo_signal_scene(tmp: Path, k, H, t_end, interface, implicit, tol) -> Path:
    subs = {"system1": {"fmu": str(peers.OM / P.DMO_UNITS["system1"]), "start": {"x1_start": 0.0}},
            "system2": {"fmu": str(peers.OM / P.DMO_UNITS["system2"]), "start": {"x2_start": 0.5},
                        "record": ["mass2.s"]}}  # fmt: skip
    for sub in subs.values():
        sub["interface"] = interface
        if tol is not None:
            sub["tolerance"] = tol
    data = {"subsystems": subs,
            "connections": [{"from": f"{a}.{y}", "to": f"{b}.{u}"} for a, y, b, u, _, _ in DMO_CONNECTIONS],
            "coupling": {"H": H, "k": k, "scheme": "jacobi", **({"implicit": True} if implicit else {})},
            "t_end": t_end}  # fmt: skip
    return scene_file(tmp, "dmo", data)


def dmo_signal_rows(tmp: Path, args, versions) -> list:
    system = "DualMassOscillator, signals"
    rows = dmo_peer_rows(tmp, args, versions, system)
    quick = args.quick
    me = [(k, H, False, 1e-8) for k in (0, 1, 2) for H in ([1e-2] if quick else [5e-2, 2e-2, 1e-2, 5e-3, 2e-3])]
    me += [(k, H, True, 1e-8) for k in (0, 1, 2) for H in ([1e-2] if quick else [1e-1, 5e-2, 2e-2, 1e-2, 5e-3])]
    me += (
        [] if quick else [(1, 5e-2, False, 1e-6), (2, 5e-2, False, 1e-6), (2, 5e-2, True, 1e-6), (2, 5e-3, True, 1e-10)]
    )
    cs = [(k, 1e-3, False, None) for k in (0, 1, 2)] + ([] if quick else [(0, 1e-4, False, None)])
    for (k, H, implicit, tol), interface in [(c, "model-exchange") for c in sorted(me)] + [
        (c, "co-simulation") for c in cs
    ]:
        base = row(system, "icosim", coupling_label(k, H, implicit, interface, tol), interface.replace("-", " "), "")
        run = recorded(lambda t, k=k, H=H, i=implicit, f=interface, tol=tol: _dmo_run(tmp, k, H, t, f, i, tol))
        added(rows, measured(base, run, peers.T_DMO, args, peers.dmo_error, H), f"{'icosim':11s} {base['setting'] + ', ' + interface:50s}",
              lambda r: f"err x1 {r['error_x']:.2e} x2 {r['error_x2']:.2e}")  # fmt: skip
    return rows


def _dmo_run(tmp, k, H, t, interface, implicit, tol):
    out = icosim_signals(dmo_signal_scene(tmp, k, H, t, interface, implicit, tol))
    return out | {"x1": out["system1.x1"], "x2": out["system2.mass2.s"]}


# -- the QuarterCarModel ------------------------------------------------------------------------------------------


def qc_error(o):
    x, v = qc_exact(o["t"])[:2]
    return {"error_x": abs(o["x"] - x), "error_v": abs(o["v"] - v)}


def qc_scene(tmp: Path, decomposition, k, H, t_end, interface, implicit, tol) -> Path:
    sub = {"interface": interface, **({} if tol is None else {"tolerance": tol})}
    data = {"subsystems": {u: {"fmu": str(S.qc_fmu(decomposition, u)), **sub} for u in ("chassis", "wheel")},
            "connections": [{"from": f"{a}.{y}", "to": f"{b}.{u}"} for a, y, b, u in S.CONNECTIONS[decomposition]],
            "sources": [{"to": "wheel.z", "table": str(S.ROAD), "column": "road"}],
            "coupling": {"H": H, "k": k, "scheme": "jacobi", **({"implicit": True} if implicit else {})},
            "t_end": t_end}  # fmt: skip
    return scene_file(tmp, f"qc_{decomposition}", data)


def _qc_run(tmp, decomposition, k, H, t, interface, implicit, tol):
    out = icosim_signals(qc_scene(tmp, decomposition, k, H, t, interface, implicit, tol))
    return out | {"x": out["chassis.z_c"], "v": out["chassis.der_z_c"]}


def qc_rows(tmp: Path, args, versions) -> list:
    rows: list = []
    quick = args.quick
    steps = [1e-3, 1e-4] if quick else [1e-3, 1e-4, 1e-5]
    cs = {"units": "co-simulation", "group": ""}
    for decomposition in S.CONNECTIONS:
        system = f"QuarterCarModel, {decomposition}"

        def add(base, run, H=None, extra=False):
            r = measured(base, run, T_QC, args, qc_error, H) if extra else attempt(base, run, T_QC, args, qc_error, H)
            added(rows, r, f"{base['master']:9s} {base['setting'] + ', ' + base['units']:58s}",
                  lambda r: f"err x {r['error_x']:.2e} v {r['error_v']:.2e}")  # fmt: skip

        if available(versions, "libcosim"):
            for h in steps:
                folder, scenario = S.qc_osp(tmp / f"qc_lc_{decomposition}_{h:g}", decomposition, h, T_QC)
                add(row(system, "libcosim", f"fixed step {h:g}, road by a scenario file", **cs),
                    lambda t, f=folder, s=scenario: S.libcosim_qc(f, s, t))  # fmt: skip
        else:
            rows.append(row(system, "libcosim", "all", **cs) | {"status": versions["libcosim"]})
        if available(versions, "Ecos"):
            for h in steps:
                add(row(system, "Ecos", f"fixed step {h:g}, road by set_real at 0.1 s", **cs),
                    lambda t, h=h, d=decomposition: S.ecos_qc(d, h, t))  # fmt: skip
        else:
            rows.append(row(system, "Ecos", "all", **cs) | {"status": versions["Ecos"]})
        if available(versions, "FMPy"):
            ssp = S.qc_ssp(tmp / f"qc_{decomposition}.ssp", decomposition)
            for h in steps:
                add(row(system, "FMPy", f"simulate_ssp, fixed step {h:g}, road by input=", **cs),
                    lambda t, h=h, s=ssp: S.fmpy_qc(s, h, t))  # fmt: skip
        else:
            rows.append(row(system, "FMPy", "all", **cs) | {"status": versions["FMPy"]})
        rows.append(row(system, "OMSimulator", "its test (CSV component BC, fixed step 1e-3)", **cs)
                    | {"status": "not run: OMSimulator is not installed here, and its test publishes no values"})  # fmt: skip
        me = [(k, H, False, 1e-8) for k in (0, 1, 2) for H in ([1e-3] if quick else [1e-2, 4e-3, 2e-3, 1e-3, 5e-4])]
        me += [(k, H, True, 1e-8) for k in (0, 1, 2) for H in ([1e-3] if quick else [4e-3, 2e-3, 1e-3])]
        me += [] if quick else [(2, 5e-4, False, 1e-10), (1, 1e-3, False, 1e-10)]
        me += [] if quick else [(1, H, False, 1e-6) for H in (1e-2, 4e-3, 2e-3, 1e-3)]
        for k, H, implicit, tol in sorted(me):
            base = row(system, "icosim", coupling_label(k, H, implicit, "model-exchange", tol), "model exchange", "")
            add(base, recorded(lambda t, d=decomposition, k=k, H=H, i=implicit, tol=tol: _qc_run(
                tmp, d, k, H, t, "model-exchange", i, tol)), H, extra=True)  # fmt: skip
        for k, H in [(0, 1e-3), (1, 1e-3)] + ([] if quick else [(1, 1e-4)]):
            base = row(system, "icosim", coupling_label(k, H, False, "co-simulation"), "co-simulation", "")
            add(base, recorded(lambda t, d=decomposition, k=k, H=H: _qc_run(
                tmp, d, k, H, t, "co-simulation", False, None)), H, extra=True)  # fmt: skip
        rows.append(row(system, "icosim", "implicit, co-simulation units", "co-simulation", "")
                    | {"status": "not run: the units declare canGetAndSetFMUstate=false (icosim refuses, naming it)"})  # fmt: skip
    return rows


# -- the tables -----------------------------------------------------------------------------------------------------


def print_tables(rows, summary):
    print(
        "\n| system | units | master | setting | error x | error v or x2 | wall (s) | runs | doSteps | per step | "
        "Newton | Jacobian steps | rhs evaluations |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        if r.get("status") in ("completed", "published"):
            other = r.get("error_v", r.get("error_x2", math.nan))
            wall = f"{r['wall']:.3f}" if "wall" in r else "-"
            per = f"{r['do_steps_per_step']:.0f}" if "do_steps_per_step" in r else "-"
            newton = f"{r['newton']:.2f}" if "newton" in r else "-"
            print(f"| {r['system']} | {r['units']} | {r['master']} | {r['setting']} | {r['error_x']:.2e} | "
                  f"{other:.2e} | {wall} | {r.get('runs', '-')} | {r.get('do_steps') or '-'} | {per} | {newton} | "
                  f"{r.get('jacobian_steps', '-')} | {r.get('rhs', '-') or '-'} |")  # fmt: skip
        else:
            print(f"| {r['system']} | {r['units']} | {r['master']} | {r['setting']} | {r['status']} ||||||||")
    print("\n| system | error of | at most | fastest per master (wall s, doSteps) | icosim / peer |")
    print("|---|---|---|---|---|")
    for e in summary:
        best = "; ".join(f"{m}: {b['setting']} ({b['wall']:.3f}, {b['do_steps']})" for m, b in e["best"].items())
        ratios = ", ".join(f"{m} {v:.2f}" for m, v in e.get("icosim_over", {}).items()) or "-"
        print(f"| {e['system']} | {e['measure']} | {e['level']:.0e} | {best} | {ratios} |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default=",".join(SYSTEMS), help="dmo, quarter-car (comma-separated)")
    parser.add_argument("--repeat", type=int, default=2, help="timed runs after the warm-up (fewer past --budget)")
    parser.add_argument("--budget", type=float, default=6.0, help="seconds of timed runs per setting")
    parser.add_argument("--quick", action="store_true", help="fewer settings (development)")
    parser.add_argument("--json", type=Path, help="write the rows and the summary here")
    args = parser.parse_args(argv)
    unknown = set(args.only.split(",")) - set(SYSTEMS)
    if unknown:
        parser.error(f"--only: unknown {sorted(unknown)}; allowed: {', '.join(SYSTEMS)}")
    if not (peers.OUTSIDE / "README.md").is_file():
        parser.error(f"the other tools' units are not in {peers.OUTSIDE}")
    versions = installed()
    load = os.getloadavg()
    print(f"masters: {versions}\nload average at the start: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}", flush=True)
    rows: list = []
    clock = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="icosim-peers-signals-") as tmp:
        try:
            if "dmo" in args.only.split(","):
                print(f"DualMassOscillator by signals, {peers.T_DMO:g} s:", flush=True)
                rows += dmo_signal_rows(Path(tmp), args, versions)
            if "quarter-car" in args.only.split(","):
                print(f"QuarterCarModel, {T_QC:g} s:", flush=True)
                rows += qc_rows(Path(tmp), args, versions)
        except KeyboardInterrupt:
            traceback.print_exc()
    summary = fastest(rows)
    print_tables(rows, summary)
    end = os.getloadavg()
    print(f"\nload average at the end: {end[0]:.2f} {end[1]:.2f} {end[2]:.2f}; {time.perf_counter() - clock:.0f} s")
    if args.json:
        machine = {"python": platform.python_version(), "processor": platform.processor() or platform.machine(),
                   "cpus": os.cpu_count(), "load_start": load, "load_end": end}  # fmt: skip
        args.json.write_text(json.dumps({"masters": versions, "machine": machine, "rows": rows, "fastest": summary},
                                        indent=1, default=float))  # fmt: skip


if __name__ == "__main__":
    main()

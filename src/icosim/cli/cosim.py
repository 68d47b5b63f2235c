"""``icosim cosim``: run an FMU scene (two co-simulation units, a coupling method) and write its trajectory.

The scene (:mod:`icosim.fmi.scene`) is checked against its JSON schema, its units are opened and checked against
what the scene names (co-simulation, saved states, variables and their causality) before the first macro step;
bad input exits with status 2 and one line ``icosim cosim: error: <file or unit>: <key>: ...``.  A unit that
refuses a step stops the run the same way, naming the unit, the macro step and the time; no dataset is written
then.  The dataset (NetCDF, written atomically) holds ``position`` and ``velocity`` per subsystem and time,
``multiplier`` and ``gap`` per time, the scene as JSON and each unit's provenance and counters (docs/fmi.md).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

__all__ = ["add_parser", "run"]


def add_parser(sub):
    """Register ``cosim`` on the ``icosim`` sub-command parsers."""
    p = sub.add_parser(
        "cosim",
        help="run an FMU scene with an implicit coupling method",
        description="Couple two FMI co-simulation units (a scene file, YAML) with a method of the paper "
        "(baumgarte, weighted, projection), any order k and scheme (Jacobi, Gauss-Seidel), and write the "
        "trajectory as NetCDF.",
        epilog="Scene format and what each unit must offer: docs/fmi.md.  Units named by a source directory "
        "(fmus/) are built on first use into $ICOSIM_FMU_CACHE (default ~/.cache/icosim/fmus).",
    )
    p.add_argument("scene", metavar="SCENE.yaml", help="the scene file")
    p.add_argument("--out", metavar="RUN.nc", help="the NetCDF file to write (required unless --predict)")
    p.add_argument(
        "--predict",
        action="store_true",
        help="do not run: identify m, c, d of the (linear) units from a few probing steps and print the spectral "
        "radius for the scene's scheme and every other one",
    )
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.set_defaults(subparser=p)
    return p


def _error(message: str) -> int:
    print(f"icosim cosim: error: {' '.join(str(message).split())}", file=sys.stderr)
    return 2


def run(args, parser) -> int:
    """``icosim cosim``: check the scene, the output and the units (exit 2 naming what is wrong), then run."""
    from ..advise.output import Progress
    from ..fmi.errors import SceneError, UnitStepError
    from ..fmi.run import run_dataset, run_scene, run_summary
    from ..fmi.scene import load_scene
    from ..io.jsonio import dumps
    from ..io.netcdf import write_netcdf

    if args.predict:
        return _predict(args)
    if args.out is None:
        return _error("argument --out is required (or --predict)")
    out = Path(args.out)
    if not out.parent.resolve().is_dir():
        return _error(f"argument --out: directory {out.parent} does not exist")
    if out.is_dir():
        return _error(f"argument --out: {out} is a directory")
    if not os.access(out.parent.resolve(), os.W_OK):
        return _error(f"argument --out: directory {out.parent} is not writable")
    try:
        import fmpy  # noqa: F401
    except ImportError:
        return _error("running a scene needs fmpy: pip install 'icosim[fmi]'")
    try:
        scene = load_scene(args.scene)
        bar = Progress(scene.n_steps, label="macro steps")
        try:
            result = run_scene(scene, progress=bar)
        finally:
            bar.close()
    except SceneError as exc:
        return _error(str(exc))
    except UnitStepError as exc:
        return _error(f"{exc}; no dataset written")
    write_netcdf(run_dataset(result, command=f"icosim cosim {args.scene} --out {args.out}"), out)
    summary = {**run_summary(result), "out": str(out)}
    if args.json:
        print(dumps(summary))
    else:
        print(_text(summary))
    return 0


def _predict(args) -> int:
    from ..fmi.errors import SceneError, UnitStepError
    from ..fmi.predict import predict_scene
    from ..fmi.scene import load_scene
    from ..io.jsonio import dumps

    try:
        answer = predict_scene(load_scene(args.scene))
    except (SceneError, UnitStepError) as exc:
        return _error(str(exc))
    print(dumps(answer) if args.json else _prediction_text(answer))
    return 0


def _prediction_text(a: dict) -> str:
    lines = [f"scene {a['scene']}: {a['method']}, {a['decomposition']}, k = {a['k']}, H = {a['H']:g} s"]
    for name, u in a["units"].items():
        lines.append(
            f"  {name} identified: m = {u['m']:.6g} kg, c = {u['c']:.6g} N/m, d = {u['d']:.6g} N s/m "
            f"(misfit of the linear model {u['misfit']:.1e}, {u['probe_do_step_calls']} probing doStep calls)"
        )
        if u["misfit"] > 1e-6:
            lines.append(
                f"    {name} is not a linear oscillator: the prediction is that of a linear fit about its start"
            )
    lines.append("spectral radius per macro step (float64, error estimate):")
    for row in a["schemes"]:
        mark = "*" if row["scene"] else " "
        if row["rho"] is None:
            lines.append(f"  {mark} {row['scheme']:<32} not defined: {row['reason']}")
        else:
            lines.append(
                f"  {mark} {row['scheme']:<32} rho = {row['rho']:.10g} (+- {row['rho_error']:.1e})  {row['verdict']}"
            )
    lines.append("  (* the scene's scheme)")
    return "\n".join(lines)


def _text(s: dict) -> str:
    c = s["coupling"]
    lines = [
        f"scene {s['scene']}: {c['method']}, {c['decomposition']}, k = {c['k']}, {c['scheme']}, H = {c['H']:g} s",
    ]
    for name, u in s["units"].items():
        lines.append(
            f"  {name}: {u['model_name']} (FMI {u['fmi_version']}, {u['generation_tool'] or 'unknown tool'}), "
            f"inputs by {u['inputs']}: {u['do_step_calls']} doStep calls, {u['states_saved']} states saved, "
            f"{u['states_restored']} restored"
        )
    lines.append(
        f"{s['status']}: {s['macro_steps']} macro steps to t = {s['t_end']:g} s "
        f"({s['do_step_calls_per_macro_step']:g} doStep calls per macro step), max |gap| = {s['max_abs_gap']:.3g} m, "
        f"{s['wall_time_s']:.2f} s"
    )
    if s["reason"]:
        lines.append(f"  {s['reason']}")
    lines.append(f"wrote {s['out']}")
    return "\n".join(lines)

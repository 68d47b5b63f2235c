"""``icosim cosim``: run an FMU scene (two co-simulation units, a coupling method) and write its trajectory.

The scene (:mod:`icosim.problems.fmu.scene`) is checked against its JSON schema, its units are opened and checked against
what the scene names (co-simulation, saved states, variables, their causality, types and units of measure, start
values) and then measured (:mod:`icosim.problems.fmu.inspection`: rollback, feedthrough, direction) and the start made
consistent before the first macro step; bad input exits with status 2 and one line
``icosim cosim: error: <file or unit>: <key>: ...``.  ``--check`` runs only these checks and prints a table per
unit.  A unit that refuses a step, returns a value that is not finite, outlasts the per-call time limit or
crashes the process stops the run the same way, naming the unit, the call and the macro step; no dataset is
written then.  A run that diverges ends with status 1 and says at which step; its dataset says so too.  The
dataset (NetCDF, written atomically) holds ``position`` and ``velocity`` per subsystem and time, ``multiplier``
and ``gap`` per time, the scene as JSON and each unit's provenance and counters (docs/fmi.md).
``--tolerance TOL`` runs a scene of joints or of signal connections with controlled macro steps at ``TOL``
(:func:`icosim.problems.fmu.controlled.at_tolerance`); a value that is no positive number, a scene of joints beside
connections and a control of another estimate are refused before any unit is opened.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from .arguments import positive_number

__all__ = ["add_parser", "run"]


def add_parser(sub):
    """Register ``cosim`` on the ``icosim`` sub-command parsers."""
    p = sub.add_parser(
        "cosim",
        help="run an FMU scene with an implicit coupling method",
        description="Couple two FMI co-simulation units (a scene file, YAML) with a method of the paper "
        "(baumgarte, weighted, projection), any order k and scheme (Jacobi, Gauss-Seidel), and write the "
        "trajectory as NetCDF.",
        epilog="Scene format, what each unit must offer and how it is checked: docs/fmi.md.  Units named by a "
        "source directory (fmus/) are built on first use into $ICOSIM_FMU_CACHE (default ~/.cache/icosim/fmus).",
    )
    p.add_argument(
        "scene",
        metavar="SCENE.yaml",
        help="the scene file (YAML), or a system file (.ssp, .ssd, OspSystemStructure.xml, or a folder holding one) "
        "run with its own defaults",
    )
    p.add_argument("--out", metavar="RUN.nc", help="the NetCDF file to write (required unless --predict or --check)")
    what = p.add_mutually_exclusive_group()
    what.add_argument(
        "--predict",
        action="store_true",
        help="do not run: identify m, c, d of the (linear) units from probing steps (a scene of signals: each "
        "unit's A, B, C, D) and print the spectral radius for the scene's scheme and every other one",
    )
    what.add_argument(
        "--check",
        action="store_true",
        help="do not run: check every unit (types, units of measure, start values, rollback, feedthrough, "
        "direction; a scene of signals: the units, the connections and the first step) and the start, and print a "
        "table per unit; exit 2 if one is refused",
    )
    p.add_argument(
        "--tolerance",
        metavar="TOL",
        type=positive_number,
        help="run with controlled macro steps at this tolerance (> 0) of the predictor-corrector estimate: sets "
        "coupling.control.tolerance, with the scene's other control keys or, without them, H_min = 1e-6 H and "
        "H_max = t_end - t_start (scenes of joints)",
    )
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.set_defaults(subparser=p)
    return p


def _error(message: str) -> int:
    print(f"icosim cosim: error: {' '.join(str(message).split())}", file=sys.stderr)
    return 2


def run(args, parser) -> int:
    """``icosim cosim``: check the scene, the output and the units (exit 2 naming what is wrong), then run."""
    if not (args.predict or args.check):
        if args.out is None:
            return _error("argument --out is required (or --predict, --check)")
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
    from ..problems.fmu.errors import SceneError
    from ..problems.fmu.guard import CALL_SECONDS, supervised
    from ..problems.fmu.scene import load_scene

    try:
        scene = load_scene(args.scene)
    except SceneError as exc:
        return _error(str(exc))
    for note in scene.system.notes if scene.system is not None else ():
        print(f"icosim cosim: note: {note}", file=sys.stderr)
    limit = float(scene.data.get("limits", {}).get("call_seconds", CALL_SECONDS))
    signals = getattr(scene, "connections", None) is not None  # units coupled by signal connections
    both = hasattr(scene, "signal_units")  # joints beside connections (icosim.problems.fmu.joint_signal_scene)
    if both and (args.predict or args.check):
        flag = "--predict" if args.predict else "--check"
        return _error(f"argument {flag}: {args.scene} joins units by joints beside connections, which {flag} does not "
                      f"serve yet (a scene of joints or one of connections); run it without {flag}")  # fmt: skip
    if args.tolerance is not None:
        if both:
            return _error(
                f"argument --tolerance: {args.scene} joins units by joints beside connections, which run at fixed "
                "steps; a tolerance applies to a scene of joints or one of connections (or run it without --tolerance)"
            )
        from ..problems.fmu.controlled import at_tolerance

        try:
            scene = at_tolerance(scene, args.tolerance)
        except SceneError as exc:
            return _error(f"argument --tolerance: {exc}")
    if signals and args.predict:
        target, leftovers = (lambda: _predict(scene, args, signals=True)), ()
    elif signals and not args.check:
        out = Path(args.out)
        target = lambda: _run(scene, args, out, signals="both" if both else True)
        leftovers = (out.parent / f".{out.name}.*.part", out.parent / f".{out.name}.sha256.*.part")
    elif args.predict:
        target, leftovers = (lambda: _predict(scene, args)), ()
    elif args.check:
        target, leftovers = (lambda: _check(scene, args, signals=signals)), ()
    else:
        out = Path(args.out)
        target = lambda: _run(scene, args, out)
        leftovers = (out.parent / f".{out.name}.*.part", out.parent / f".{out.name}.sha256.*.part")
    outcome = supervised(target, call_seconds=limit, leftovers=leftovers)
    if outcome.message:
        nothing = "" if args.predict or args.check else "; no dataset written"
        return _error(f"{outcome.message}{nothing}")
    return outcome.status


def _run(scene, args, out, signals=False) -> int:
    """A scene's run, its dataset written and its summary printed; ``signals``: a scene of signal connections."""
    from ..advise.output import Progress
    from ..io.jsonio import dumps
    from ..io.netcdf import write_netcdf
    from ..problems.fmu.errors import SceneError, UnitStepError

    if signals == "both":
        from ..problems.fmu.joint_signal_run import joint_signal_dataset as dataset
        from ..problems.fmu.joint_signal_run import run_joint_signal_scene as run
    elif signals:
        from ..problems.fmu.signal_scene import run_signal_scene as run
        from ..problems.fmu.signal_scene import signal_dataset as dataset
    else:
        from ..problems.fmu.run import run_dataset as dataset
        from ..problems.fmu.run import run_scene as run
    try:
        bar = Progress(scene.n_steps, label="macro steps")
        try:
            result = run(scene, progress=bar)
        finally:
            bar.close()
    except SceneError as exc:
        return _error(str(exc))
    except UnitStepError as exc:
        return _error(f"{exc}; no dataset written")
    tolerance = "" if args.tolerance is None else f" --tolerance {args.tolerance!r}"
    write_netcdf(dataset(result, command=f"icosim cosim {args.scene}{tolerance} --out {args.out}"), out)
    if signals == "both":  # the joints' summary and the connected variables' last values
        from ..problems.fmu.run import run_summary

        last = {key: values[-1] for key, values in result.signals.series.items()}
        summary = {**run_summary(result.joints), "status": result.status, "out": str(out), **last}
        text = "\n".join([_text(summary), *(f"{k}: {v}" for k, v in last.items())])
    elif signals:
        last = {key: values[-1] for key, values in result.series.items()}
        summary = {"status": result.status, "reason": result.reason, "t": result.times[-1], "out": str(out), **last}
        if result.loop:  # an algebraic loop: the root its first solve found, and from where
            summary["loop"] = result.loop["loop_message"]
        if result.steps is not None:  # a controlled run: its steps
            summary |= {"accepted_steps": len(result.steps.H), "rejected_steps": int(result.steps.n_rejected)}
        text = "\n".join(f"{k}: {v}" for k, v in summary.items())
    else:
        from ..problems.fmu.run import run_summary

        summary = {**run_summary(result), "out": str(out)}
        if result.steps is not None:  # a controlled run: its estimate, tolerance and steps
            from ..problems.fmu.controlled import controlled_entries

            attrs = controlled_entries(result)[1]
            tolerance = scene.coupling["control"].get("tolerance")
            summary["control"] = {k.removeprefix("control_"): v for k, v in attrs.items()} | {"tolerance": tolerance}
        warning = (summary["initial"] or {}).get("warning")
        if warning:
            print(f"icosim cosim: warning: {warning}", file=sys.stderr)
        text = _text(summary)
    print(dumps(summary) if args.json else text)
    return 0 if result.status == "completed" else 1


def _predict(scene, args, signals=False) -> int:
    from ..io.jsonio import dumps
    from ..problems.fmu.errors import SceneError, UnitStepError

    if signals:
        from ..problems.fmu.predict_signals import predict_signal_scene as predict
    else:
        from ..problems.fmu.predict import predict_scene as predict
    try:
        answer = predict(scene)
    except (SceneError, UnitStepError) as exc:
        return _error(str(exc))
    text = _signal_prediction_text if signals else _prediction_text
    print(dumps(answer) if args.json else text(answer))
    return 0


def _check(scene, args, *, signals=False) -> int:
    from ..io.jsonio import dumps
    from ..problems.fmu.check import check_scene
    from ..problems.fmu.check_signals import check_signal_scene

    report = check_signal_scene(scene) if signals else check_scene(scene)
    print(dumps(report) if args.json else _check_text(report))
    return 2 if report["refused"] else 0


def _check_text(report: dict) -> str:
    lines = [f"scene {report['scene']}: {report['coupling']}"]
    for unit in report["units"]:
        lines.append(f"  {unit['name']}: {unit['unit']}")
        for row in unit["findings"]:
            fix = f" -- fix: {row['fix']}" if row.get("fix") else ""
            lines.append(f"    {row['check']:<13} {row['verdict']:<8} {row['detail']}{fix}")
    for row in report["scene_findings"]:
        fix = f" -- fix: {row['fix']}" if row.get("fix") else ""
        lines.append(f"  {row['check']:<15} {row['verdict']:<8} {row['detail']}{fix}")
    lines.append("refused" if report["refused"] else "every check passed")
    return "\n".join(lines)


def _prediction_text(a: dict) -> str:
    lines = [f"scene {a['scene']}: {a['coupling']}"]
    for name, u in a["units"].items():
        preload = f", F0 = {u['F0']:.6g} N" if u["F0"] else ""
        through = "" if u.get("feedthrough", True) else "; no direct feedthrough: identified through steps"
        lines.append(
            f"  {name} identified: m = {u['m']:.6g} kg, c = {u['c']:.6g} N/m, d = {u['d']:.6g} N s/m{preload} "
            f"(misfit of the linear model {u['misfit']:.1e}, {u['probe_do_step_calls']} probing doStep calls{through})"
        )
        if u["misfit"] > 1e-6:
            lines.append(
                f"    {name} is not a linear oscillator: the prediction is that of a linear fit about its start"
            )
    lines += _radius_lines(a["schemes"], 32, "not defined: ")
    return "\n".join(lines)


def _radius_lines(schemes: list, width: int, undefined: str) -> list[str]:
    """The spectral radius of each scheme as a table's lines, the scene's marked; ``undefined`` heads the reason of
    a row without one."""
    lines = ["spectral radius per macro step (float64, error estimate):"]
    for row in schemes:
        mark = "*" if row["scene"] else " "
        if row["rho"] is None:
            lines.append(f"  {mark} {row['label']:<{width}} {undefined}{row['reason']}")
        else:
            lines.append(f"  {mark} {row['label']:<{width}} rho = {row['rho']:.10g} (+- {row['rho_error']:.1e})  "
                         f"{row['verdict']}")  # fmt: skip
    return lines + ["  (* the scene's scheme)"]


def _signal_prediction_text(a: dict) -> str:
    lines = [f"scene {a['scene']}: {a['coupling']}"]
    for name, u in a["units"].items():
        if "undecided" in u:
            lines.append(f"  {name} ({u['interface']}): not identified, because {u['undecided']}")
            continue
        how = f"{u['evaluations']} evaluations" if "evaluations" in u else f"{u['probe_do_step_calls']} probing steps"
        lines.append(f"  {name} identified ({u['interface']}, {u['model']}; states {', '.join(u['states']) or 'none'}; "
                     f"misfit of the linear model {u['misfit']:.1e}, {how}):")  # fmt: skip
        for key in "ABCD":
            rows = "; ".join(" ".join(f"{v:.6g}" for v in row) for row in u[key])
            lines.append(f"    {key} = [{rows}]")
        if u["misfit"] > 1e-6:
            lines.append(f"    {name} is not linear: the prediction is that of a linear fit about its start")
    lines += _radius_lines(a["schemes"], 40, "undecided, because ")
    limit = a["largest_stable_H"]
    if limit["H_max"] is None:
        lines.append(f"largest stable H: undecided, because {limit['reason']}")
    else:
        anew = (
            f"; the co-simulation units identified anew at each step tried, {limit['identifications']} times"
            if "identifications" in limit
            else ""
        )
        lines.append(f"largest stable H of the scene's scheme: {limit['H_max']:.6g} s ({limit['status']}{anew}; "
                     f"scanned at a ratio of {limit['scan_ratio']:.3g}: a band of instability narrower than that "
                     "between two scan points below it would not be seen)")  # fmt: skip
    return "\n".join(lines)


def _text(s: dict) -> str:
    lines = [f"scene {s['scene']}: {s['described']}"]
    for name, u in s["units"].items():
        warned = f", {u['warnings']} warnings (first: {u['first_warning']})" if u.get("warnings") else ""
        lines.append(
            f"  {name}: {u['model_name']} (FMI {u['fmi_version']}, {u['generation_tool'] or 'unknown tool'}), "
            f"inputs by {u['inputs']}: {u['do_step_calls']} doStep calls, {u['states_saved']} states saved, "
            f"{u['states_restored']} restored{warned}"
        )
    start = s.get("initial") or {}
    if start:
        values = ", ".join(f"{v:.6g}" for v in start["coupling_values"])
        gap = (
            f", joint gap at start {start['position_gap']:.3g} m, {start['velocity_gap']:.3g} m/s (as-is)"
            if start["mode"] == "as-is"
            else ""
        )
        lines.append(f"  initial coupling variables {values} ({start['coupling']}){gap}")
    per_step = s["do_step_calls_per_macro_step"]
    lines.append(
        f"{s['status']}: {s['macro_steps']} macro steps to t = {s['t_end']:g} s "
        + (f"({per_step:g} doStep calls per macro step), " if per_step is not None else "")
        + f"max |gap| = {s['max_abs_gap']:.3g} m, {s['wall_time_s']:.2f} s"
    )
    if s.get("control"):
        c = s["control"]
        at = f" at tolerance {c['tolerance']:g}" if c["tolerance"] is not None else ""
        lines.append(f"  controlled ({c['estimate']}{at}): {c['accepted_steps']} steps accepted, "
                     f"{c['rejected_steps']} rejected")  # fmt: skip
    if s["reason"]:
        lines.append(f"  {s['reason']}")
    lines.append(f"wrote {s['out']}")
    return "\n".join(lines)

"""``icosim cosim SCENE --check``: every check a run makes before its first macro step, as a table per unit.

Per unit: opening it (the kind of unit, saved states, the variables the scene names, their causality, type and
units of measure, the start values by the standard's rules), then the measured checks of
:func:`icosim.problems.fmu.inspection.inspect_unit` (rollback, feedthrough, direction).  For the scene: the direction
of every joint's multiplier on its two units, the scheme against the units' feedthrough, the joints' consistency
at ``t_start`` and the coupling variables there.  Nothing is
run beyond the probing steps; a refusal is a row, not an exception, so one run shows everything that is wrong.
"""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from .errors import FmuError
from .inspection import Finding, inspect_unit, joint_direction
from .joints import check_scheme
from .problem import Coupling, FmuCosimulation
from .run import consistent_start, open_unit

__all__ = ["check_scene"]


def check_scene(scene, *, cache=None) -> dict:
    """The checks of ``scene`` (a loaded :class:`~icosim.problems.fmu.scene.Scene`) as a JSON-ready report:
    ``units`` (name, what the unit is, its findings), ``scene_findings`` and ``refused`` (any refusal)."""
    c = scene.coupling
    graph = scene.graph()
    kinds = [graph.port_kind(i, 0) for i in range(graph.n_subsystems)]
    signs = scene.graph_signs()
    units, couplings, rows = [], [], []
    try:
        for (name, sub), kind in zip(scene.data["subsystems"].items(), kinds):
            row = {"name": name, "unit": str(scene.fmus[name]), "findings": []}
            rows.append(row)
            try:
                unit = open_unit(scene, name, kind, cache=cache)
            except FmuError as exc:
                row["findings"].append(asdict(Finding("open", "refused", _without_label(str(exc), name))))
                continue
            units.append(unit)
            md = unit.md
            row["unit"] = f"{md.modelName} (FMI {md.fmiVersion}, {md.generationTool or 'unknown tool'})"
            row["findings"].append(asdict(Finding("open", "pass", unit.opened)))
            found = inspect_unit(
                unit,
                kind=kind,
                force_sign=sub["force_sign"],
                H=float(c["H"]),
                t0=unit.t,
                rollback_tolerance=float(sub.get("rollback_tolerance", 0.0)),
            )
            row["findings"].extend(asdict(f) for f in found.findings)
            mass = sub.get("mass")
            mass = unit.get_named(mass) if isinstance(mass, str) else mass
            couplings.append(Coupling(kind, signs[len(couplings)], mass, found.feedthrough, found.gain))
        scene_rows = []
        if len(units) == len(scene.names):
            joint = joint_direction(
                scene.names, kinds, signs, [c.gain for c in couplings],
                [-int(sub["force_sign"]) for sub in scene.data["subsystems"].values()],
            )  # fmt: skip
            scene_rows.append(asdict(joint))
            scene_rows.append(
                _guarded("scheme", lambda: check_scheme(scene, units, couplings, graph), scene.scheme_text())
            )
            problem = FmuCosimulation(
                units, couplings, graph, c["k"], c["H"], t0=units[0].t, perturbation=c["perturbation"]
            )
            try:
                scene_rows.append(_start_row(scene, problem))
            finally:
                problem.close()
    finally:
        for unit in units:
            unit.close()
    refused = any(f["verdict"] == "refused" for r in rows for f in r["findings"]) or any(
        f["verdict"] == "refused" for f in scene_rows
    )
    return {"scene": str(scene.path), "coupling": scene.describe(), "units": rows, "scene_findings": scene_rows,
            "refused": bool(refused)}  # fmt: skip


def _without_label(message: str, name: str) -> str:
    return message[len(name) + 2 :] if message.startswith(f"{name}: ") else message


def _guarded(check, action, detail) -> dict:
    try:
        action()
    except FmuError as exc:
        return asdict(Finding(check, "refused", str(exc).split(": ", 2)[-1]))
    return asdict(Finding(check, "pass", detail))


def _start_row(scene, problem) -> dict:
    try:
        start = consistent_start(scene, problem)
    except FmuError as exc:
        text = str(exc).split("initial: ", 1)[-1]
        return asdict(Finding("start", "refused", text))
    except (np.linalg.LinAlgError, ValueError) as exc:
        return asdict(Finding("start", "refused", f"no coupling variables meet the joint at t_start ({exc})"))
    e0 = ", ".join(f"{v:.6g}" for v in start.history[0])
    gap = f"joint gap {start.position_gap:.3g} m, {start.velocity_gap:.3g} m/s"
    return asdict(
        Finding("start", "pass", f"{gap} ({start.initial}); coupling variables {e0} ({start.coupling_source})")
    )

"""``icosim cosim SIGNALSCENE --check``: the checks a run of signal connections makes before its first macro step,
and that step, as a table per unit (the report of :func:`icosim.problems.fmu.check.check_scene`).

Per unit: opening it as the run opens it (:func:`~icosim.problems.fmu.signal_scene.open_signal_unit`: the kind of unit, the
connected variables, their causality, type and units of measure, the start values by the standard's rules, the
orders of input derivatives it takes) and the variables it records. For the scene: the connections (an algebraic
loop, by the units' ``ModelStructure`` or measured, solved at ``t_start`` or refused), the start (the inputs
handed the outputs at ``t_start`` until they settle) and the first macro step. The checks of a unit on a joint do
not apply: a unit of connections is stepped forward only, once per macro step (no rollback), its feedthrough is
read from its model description (the loop), and a connection has no force whose direction could be wrong. A
refusal is a row, not an exception; the units are closed after the first step, nothing is written.
"""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from .check import _record_row, _without_label
from .errors import FmuError, SceneError, UnitStepError
from .inspection import Finding
from .signal_scene import open_signal_unit, signal_wiring

__all__ = ["check_signal_scene"]


def check_signal_scene(scene) -> dict:
    """The checks of a :class:`~icosim.problems.fmu.signal_scene.SignalScene` as a JSON-ready report: ``units``
    (name, what the unit is, its findings), ``scene_findings`` and ``refused`` (any refusal)."""
    from ...engine.run import simulate
    from .signals import SignalCosimulation

    c = scene.coupling
    cons, inputs, outputs, fed = signal_wiring(scene)
    units, rows, scene_rows = [], [], []
    try:
        for i, name in enumerate(scene.names):
            sub = scene.subsystems[name]
            row = {"name": name, "unit": str(sub["fmu"]), "findings": []}
            rows.append(row)
            try:
                unit = open_signal_unit(scene, name, inputs[i], outputs[i])
            except FmuError as exc:
                text = _without_label(str(exc), name).split(f"subsystems.{name}: ", 1)[-1]
                row["findings"].append(asdict(Finding("open", "refused", text, key=f"subsystems.{name}")))
                continue
            units.append(unit)
            md = unit.md
            row["unit"] = f"{md.modelName} (FMI {md.fmiVersion}, {md.generationTool or 'unknown tool'})"
            wired = f"inputs {', '.join(inputs[i]) or 'none'}; outputs {', '.join(outputs[i]) or 'none'}"
            row["findings"].append(asdict(Finding("open", "pass", f"{unit.opened}; {wired}")))
            if sub.get("record"):
                row["findings"].append(asdict(_record_row(unit, sub["record"], name)))
        if len(units) == len(scene.names):
            scene_rows = _scene_rows(scene, SignalCosimulation, simulate, units, inputs, outputs, cons, fed)
    finally:
        for unit in units:
            unit.close()
    refused = any(f["verdict"] == "refused" for r in rows for f in r["findings"] + scene_rows)
    describe = f"signal connections, k = {c['k']}, {c['scheme']}, H = {c['H']:g} s"
    return {"scene": str(scene.path), "coupling": describe, "units": rows, "scene_findings": scene_rows,
            "refused": bool(refused)}  # fmt: skip


def _scene_rows(scene, SignalCosimulation, simulate, units, inputs, outputs, cons, fed) -> list:
    """The connections, the start and the first macro step, as rows (a refusal ends them)."""
    c = scene.coupling
    try:
        problem = SignalCosimulation(units, inputs, outputs, cons, c["k"], c["H"], t0=scene.t0, sources=fed,
                                     implicit=c["implicit"], loop_tolerance=c["loop_tolerance"],
                                     loop_iterations=c["loop_iterations"])  # fmt: skip
        history = problem.initial_history()
    except SceneError as exc:  # a loop that cannot be solved at t_start
        return [asdict(Finding("connections", "refused", str(exc).split("connections: ", 1)[-1]))]
    loop = problem.loops.message() if problem.loops is not None else "no algebraic loop"
    rows = [asdict(Finding("connections", "pass", f"{len(cons)} connections, {loop}"))]
    values = ", ".join(f"{problem.label(j)} = {history[0][j]:.6g}" for j in range(len(cons)))
    rows.append(asdict(Finding("start", "pass", f"inputs at t_start: {values or 'none'}")))
    try:
        traj = simulate(problem, None, problem.initial_state(), history, 1, scheme=scene.scheme, record=False)
    except (UnitStepError, FmuError) as exc:
        return rows + [asdict(Finding("step", "refused", f"{exc}: the first macro step cannot be taken"))]
    if traj.failed_at is not None or traj.diverged_at is not None:
        why = traj.error or traj.reason
        return rows + [asdict(Finding("step", "refused", f"{why}: the first macro step cannot be taken"))]
    finite = bool(np.all(np.isfinite(traj.states[-1])))
    detail = f"the first macro step to t = {scene.t0 + c['H']:.12g} s" + ("" if finite else ": outputs not finite")
    rows.append(asdict(Finding("step", "pass" if finite else "refused", detail)))
    return rows

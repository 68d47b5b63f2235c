"""A unit checked before it is trusted: what the coupling needs of it, measured on the unit at its start.

* **rollback** -- save the state, step, read the outputs, restore, step again: the outputs must agree (bit for
  bit, or within ``rollback_tolerance``), and the restored unit must stand where it stood;
* **feedthrough** -- does the coupling output (acceleration of a force-driven unit, the drive's force of a
  kinematically driven one) follow the coupling input without a step, as the ``ModelStructure`` declares or
  not (a drive's force: its point's position or velocity input too, :mod:`icosim.problems.fmu.drives`); and does
  it respond at all, after a step.  The macro step and the identification use what the unit does;
* **direction** -- the sign of that response: with the scene's ``force_sign``s, every joint's multiplier must
  act on its two units with opposite signs (:func:`joint_direction`; a unit whose input acts against the
  physical force needs the other ``force_sign``); a kinematically driven unit must move the way its prescribed
  acceleration says;
* units of measure and start values are checked when the unit is opened (:mod:`icosim.problems.fmu.measures`,
  :mod:`icosim.problems.fmu.variables`); they appear in the report too.

Each check is a :class:`Finding`; :func:`inspect_unit` returns them all, so ``icosim cosim --check`` can print
a table, and :func:`refuse` raises the first refusal (a run starts only with units that pass).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .drives import KINEMATICS, drive_rows, is_drive, prescribed_end
from .errors import FmuError

__all__ = ["Finding", "Inspection", "inspect_unit", "joint_direction", "refuse", "declared_feedthrough"]


@dataclass(frozen=True)
class Finding:
    """One check of one unit: ``verdict`` is ``pass``, ``refused`` or ``note``."""

    check: str
    verdict: str
    detail: str
    fix: str = ""
    key: str = ""  # the scene key a refusal is about, where it is one


@dataclass
class Inspection:
    """What was measured on a unit and what was found."""

    label: str
    kind: str
    findings: list = field(default_factory=list)
    feedthrough: bool = True
    declared: bool | None = None
    gain: float = float("nan")  # d output / d input: algebraic where the unit has feedthrough, else after a step
    follows_point: bool = False  # a drive's force follows its point's position or velocity without a step

    @property
    def refused(self) -> list:
        return [f for f in self.findings if f.verdict == "refused"]


def declared_feedthrough(md, output_variable, input_variable):
    """Does the ``ModelStructure`` declare that the output depends on the input? ``None``: it does not say (an
    output without a ``dependencies`` list depends on everything, FMI 2.0 section 2.2.8)."""
    for unknown in md.outputs:
        if unknown.variable is output_variable:
            if unknown.dependencies is None:
                return None
            return any(dep is input_variable for dep in unknown.dependencies)
    return None


def _probe_outputs(unit, kind, point=None):
    """Position, velocity and the coupling output as the unit stands (SI), ``(3, components)``; a drive's
    position and velocity where it has no outputs for them are ``point`` (prescribed)."""
    out = "acceleration" if kind == "force" else "reaction_force"
    if point is None:
        return unit.get(("position", "velocity", out))
    return np.stack(
        [unit.get((k,))[0] if k in unit.elements else np.asarray(p) for k, p in zip(KINEMATICS, point)]
        + [unit.get((out,))[0]]
    )


def inspect_unit(unit, *, kind, force_sign, H, t0=0.0, rollback_tolerance=0.0) -> Inspection:
    """Measure ``unit`` at its start state and check it (the unit is left at its start, its input at zero).

    ``kind`` is ``"force"`` or ``"kinematic"``; ``force_sign`` the scene's.  Each component of a vector joint is
    probed on its own; the component that responds most gives the unit's gain (its sign is the unit's own input
    convention; :func:`joint_direction` checks the two units' together)."""
    drive = is_drive(unit, kind)
    key = "force" if kind == "force" else "drive" if drive else "acceleration_input"
    out = "acceleration" if kind == "force" else "reaction_force"
    found = Inspection(unit.label, kind)
    out_var = unit.elements[out][0].variable
    # a drive: the acceleration where it has that input, else the input nearest to it (velocity, position)
    in_var = unit.elements[key][-len(unit.elements[out])].variable
    found.declared = declared_feedthrough(unit.md, out_var, in_var)
    n = len(unit.elements[out])
    zero = np.zeros(n)
    rest = [0.0] * n  # a drive's point at rest at 0 while it is probed

    def put(u):
        if drive:
            values = {"position_input": rest, "velocity_input": rest, "acceleration_input": list(u)}
            unit.put("drive", [q for k in unit.drive_keys for q in values[k]])
        else:
            unit.set(key, u)

    def outputs(u=None, h=0.0):
        """The probed outputs; a drive's point after ``h`` with the acceleration ``u`` (at once: ``h = 0``)."""
        if not drive:
            return _probe_outputs(unit, kind)
        return _probe_outputs(unit, kind, prescribed_end([list(u)], rest, rest, h)[:2])

    unit_inputs = np.eye(n)  # 1 N or 1 m/s^2 on one component: finite whatever the unit's mass
    start = unit.save()
    algebraic, step_gain, velocity_gain = np.zeros(n), np.zeros(n), np.zeros(n)
    try:
        put(zero)
        base = outputs(zero)
        for c in range(n):
            put(unit_inputs[c])
            algebraic[c] = outputs(unit_inputs[c])[2, c] - base[2, c]
        point = 0.0  # a drive: its force's response to its point's position or velocity input, without a step
        for moved in ("position_input", "velocity_input") if drive else ():
            if moved in unit.drive_keys:
                values = {"position_input": rest, "velocity_input": rest, "acceleration_input": rest, moved: [1.0] * n}
                unit.put("drive", [q for k in unit.drive_keys for q in values[k]])
                point = max(point, float(np.max(np.abs(unit.get((out,))[0] - base[2]))))
        put(zero)

        def stepped(u):
            unit.restore(start)
            if drive:
                unit.step(key, np.array(drive_rows(unit.drive_keys, [list(u)], rest, rest, H)), t0, H, step_index=0)
                return outputs(u, H)
            unit.step(key, [u], t0, H, step_index=0)
            return _probe_outputs(unit, kind)

        first = stepped(zero)
        again = stepped(zero)
        for c in range(n):
            pushed = stepped(unit_inputs[c])
            step_gain[c] = pushed[2, c] - first[2, c]
            velocity_gain[c] = pushed[1, c] - first[1, c]
        unit.restore(start)
        put(zero)
        back = outputs(zero)
    finally:
        unit.restore(start)
        unit.free(start)
    scale = np.maximum(np.abs(base[2]), 1e-300)
    responds = np.isfinite(algebraic) & (np.abs(algebraic) > 1e-12 * scale)
    # a drive whose force follows its point at once has current outputs: read at the step's end as they are
    found.follows_point = point > 1e-12 * float(np.max(scale))
    found.feedthrough = bool(responds.any()) or found.follows_point
    gains = np.where(responds, algebraic, step_gain) if responds.any() else step_gain
    c = int(np.argmax(np.abs(np.nan_to_num(gains))))
    found.gain = float(gains[c])
    found.findings.append(_rollback(first, again, base, back, rollback_tolerance))
    found.findings.append(_feedthrough(kind, found, float(step_gain[c]), float(velocity_gain[c])))
    found.findings.append(_direction(kind, found, force_sign, float(velocity_gain[c])))
    found.findings.append(_units(unit))
    found.findings.append(_starts(unit))
    if unit.description_problems:
        problems = "; ".join(unit.description_problems)
        found.findings.append(
            Finding("description", "note", f"fmpy's validation of its modelDescription.xml reports: {problems}")
        )
    return found


def _rollback(first, again, base, back, tol) -> Finding:
    names = ("position", "velocity", "coupling output")
    for what, a, b in (("after a repeated step", first, again), ("after restoring the saved state", base, back)):
        a, b = np.asarray(a), np.asarray(b)
        bad = np.argwhere(~(np.abs(a - b) <= tol * np.maximum(np.abs(a), np.abs(b))))
        if bad.size:
            row, col = (int(i) for i in bad[0])
            return Finding(
                "rollback",
                "refused",
                f"its {names[row]} (component {col + 1}) differs {what}: {a[row, col]!r} then {b[row, col]!r} "
                "(the restored state is not the saved one)",
                "the coupling repeats steps from saved states, so a unit whose fmi2SetFMUstate does not restore "
                "everything cannot be coupled (rollback_tolerance in the subsystem accepts a relative difference)",
            )
    how = "bit for bit" if tol == 0 else f"within {tol:g} relative"
    return Finding("rollback", "pass", f"a restored step repeats {how}")


def _feedthrough(kind, found, step_gain, velocity_gain) -> Finding:
    out = "acceleration" if kind == "force" else "drive's force"
    inp = "force input" if kind == "force" else "acceleration input"
    said = {True: "declares it", False: "declares none", None: "does not say"}[found.declared]
    if found.follows_point and kind == "kinematic":
        return Finding(
            "feedthrough",
            "pass",
            f"its {out} follows its point's position or velocity input without a "
            "step (its acceleration input at the step's end: only through the motion it prescribes)",
        )
    if found.feedthrough:
        return Finding("feedthrough", "pass", f"its {out} follows its {inp} without a step (ModelStructure {said})")
    responds = abs(step_gain) > 0 or abs(velocity_gain) > 0
    if not responds:
        return Finding(
            "feedthrough",
            "refused",
            f"its {out} and velocity do not respond to its {inp}, neither at once nor after a step "
            f"(ModelStructure {said}): the scene's input does not drive this unit",
            f"name the input that drives the unit as {'force' if kind == 'force' else 'acceleration_input'}",
        )
    note = " (contrary to its ModelStructure)" if found.declared else ""
    return Finding(
        "feedthrough",
        "note",
        f"its {out} follows its {inp} only through a step{note}: the coupling and the identification step it",
    )


def _direction(kind, found, force_sign, velocity_gain) -> Finding:
    gain = found.gain
    per = "m/s^2 per N" if kind == "force" else "N per m/s^2"
    if kind == "kinematic" and velocity_gain < 0:
        return Finding(
            "direction",
            "refused",
            f"a positive prescribed acceleration moves it backwards (velocity after a step {velocity_gain:+.3g} "
            "m/s per m/s^2)",
            "its acceleration input is not the acceleration of its coupling point: name the right input",
        )
    if kind == "force" and gain * velocity_gain < 0:
        return Finding(
            "direction",
            "refused",
            f"its acceleration responds to the force with {gain:+.3g} m/s^2 per N but its velocity with "
            f"{velocity_gain:+.3g} m/s per N: the outputs contradict each other",
        )
    if not np.isfinite(gain) or gain == 0:
        return Finding("direction", "refused", f"its coupling output does not respond to its input ({gain!r} {per})")
    way = "with" if gain > 0 else "against"
    return Finding(
        "direction",
        "pass",
        f"{gain:+.4g} {per} of its input (the input acts {way} the physical "
        f"{'force' if kind == 'force' else 'drive'}); with force_sign {force_sign:+d} the multiplier acts on it "
        f"with {'+' if force_sign * gain > 0 else '-'}lambda",
    )


def joint_direction(labels, kinds, signs, gains, fixes=None) -> Finding:
    """The joints' check over all units: each joint's multiplier must act on its two units with opposite signs
    (Newton's third law).  ``signs[i]`` is the sign with which the graph's coupling force reaches unit ``i``'s
    input (its ``force_sign`` in the graph's sense: ``+lambda_j`` on a joint's first unit, ``-lambda_j`` on its
    second), ``gains[i]`` the unit's measured response; so ``signs[i] * gains[i]`` must have one sign over the
    connected units (positive in the graph's convention; all negative only turns every multiplier around).
    The refusal names the units whose sign departs from the rest (ties: from the positive convention);
    ``fixes[i]`` is the scene's ``force_sign`` that repairs unit ``i``."""
    acts = [float(np.sign(s * g)) for s, g in zip(signs, gains)]
    if len(set(acts)) == 1 and acts[0] != 0:
        return Finding("direction", "pass", "every joint's multiplier acts on its two units with opposite signs")
    expected = -1.0 if acts.count(-1.0) > acts.count(1.0) else 1.0
    wrong = [i for i, a in enumerate(acts) if a != expected]
    per = ["m/s^2 per N" if k == "force" else "N per m/s^2" for k in kinds]
    said = " and ".join(
        f"{labels[i]}'s {'acceleration' if kinds[i] == 'force' else 'drive force'} by {gains[i]:+.4g} {per[i]} of "
        f"its input"
        for i in wrong
    )
    fixes = fixes if fixes is not None else [-int(signs[i]) for i in range(len(signs))]
    return Finding(
        "direction",
        "refused",
        f"the multiplier would move {said}, in the direction it moves the unit(s) at the other end of the joint: "
        "the joint would push both units the same way",
        "; ".join(f"set subsystems.{labels[i]}.force_sign: {fixes[i]:d}" for i in wrong)
        + " (each multiplier then acts with +lambda on its first unit and -lambda on its second)",
        f"subsystems.{labels[wrong[0]]}.force_sign",
    )


def _units(unit) -> Finding:
    parts = []
    for key, measures in unit.measures.items():
        for el, m in zip(unit.elements[key], measures):
            if m.read_from == "not declared":
                parts.append(f"{key} {el.name}: no unit (taken as SI)")
            elif m.read_from == "not understood":
                parts.append(f"{key} {el.name}: {m.unit} not read (taken as SI)")
            else:
                conv = "" if m.factor == 1 else f", x {m.factor:g} to SI"
                parts.append(f"{key} {el.name}: {m.unit}{conv}")
    verdict = "pass" if all(m.checked for ms in unit.measures.values() for m in ms) else "note"
    return Finding("units", verdict, "; ".join(parts))


def _starts(unit) -> Finding:
    if not unit.start_values:
        return Finding("start values", "pass", "none given")
    text = ", ".join(f"{s.name} = {s.text} ({s.variable.type}, {s.setter}, {s.state})" for s in unit.start_values)
    return Finding("start values", "pass", text)


def refuse(inspection: Inspection):
    """Raise :class:`FmuError` for the first refused check, naming the unit, what was measured and the fix."""
    for f in inspection.refused:
        fix = f"; {f.fix}" if f.fix else ""
        raise FmuError(f"{inspection.label}: {f.check}: {f.detail}{fix}")

"""A unit checked before it is trusted: what the coupling needs of it, measured on the unit at its start.

* **doStep flag** -- does the unit's step depend on ``noSetFMUStatePriorToCurrentPoint``; such a unit is stepped
  with ``true`` on every step where its restored steps still repeat with it, and refused otherwise;
* **rollback** -- save the state, step, read the outputs, restore, step again: the outputs must agree within
  the rollback tolerance (:func:`rollback_tolerance`), and the restored unit must stand where it stood;
* **moves** -- over a probing step the position's change against the trapezoid integral of the velocity, the
  velocity's against the acceleration's, and the step against the same interval in sub-steps;
* **responds** -- the position and velocity follow the input at all, the same way;
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

from . import motion
from .drives import KINEMATICS, drive_rows, is_drive, prescribed_end
from .errors import FmuError
from .findings import Finding, relative
from .motion import MOVE_SUBSTEPS
from .roles import force_fit, kinematic_fit

__all__ = [
    "Finding",
    "Inspection",
    "inspect_unit",
    "joint_direction",
    "refuse",
    "declared_feedthrough",
    "rollback_tolerance",
    "ROLLBACK_TOLERANCE",
]


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


#: The relative difference accepted by default between a step and the same step repeated from a restored state
#: (a subsystem's ``rollback_tolerance`` replaces it): see :func:`rollback_tolerance`.
ROLLBACK_TOLERANCE = 1e-12


def rollback_tolerance(sub) -> float:
    """The relative difference a subsystem ``sub`` (its scene entry) accepts between a step and the same step
    repeated from a restored state: its ``rollback_tolerance``, else :data:`ROLLBACK_TOLERANCE`.

    Why ``1e-12``: the coupling sees a unit through its outputs and their difference quotients (the perturbation
    ``p max(1, |u|)``, ``p = 1e-3`` by default).  A repeated step that is off by ``delta |y|`` moves a quotient
    by ``delta |y| / (p max(1, |u|))``: at ``delta = 1e-12`` a relative ``1e-9`` of the output per unit input,
    far below what the corrector and the coupling's own error (a power of ``H``) resolve; a difference above it
    is no longer the last digits of a variable-step solver but a state that is not restored."""
    value = sub.get("rollback_tolerance")
    return ROLLBACK_TOLERANCE if value is None else float(value)


def inspect_unit(unit, *, kind, force_sign, H, t0=0.0, rollback_tolerance=ROLLBACK_TOLERANCE) -> Inspection:
    """Measure ``unit`` at its start state and check it (the unit is left at its start, its input at zero).

    ``kind`` is ``"force"`` or ``"kinematic"``; ``force_sign`` the scene's.  Each component of a vector joint is
    probed on its own; the component that responds most gives the unit's gain (its sign is the unit's own input
    convention; :func:`joint_direction` checks the two units' together).  A unit whose step depends on doStep's
    ``noSetFMUStatePriorToCurrentPoint`` is stepped with ``true`` from here on (:attr:`Unit.always_final`).  A
    drive (:func:`~icosim.problems.fmu.drives.is_drive`) is probed with its point starting at rest at 0, the
    point's position and velocity where it has no outputs for them being the prescribed ones."""
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
    at_rest = (rest, rest)

    def put(u):
        if drive:
            values = {"position_input": rest, "velocity_input": rest, "acceleration_input": list(u)}
            unit.set("drive", [q for k in unit.drive_keys for q in values[k]])
        else:
            unit.set(key, u)

    def outputs(point=at_rest):
        """The probed outputs; a drive's point where it has no outputs for it: ``point`` (prescribed)."""
        return _probe_outputs(unit, kind, point if drive else None)

    def advance(u, t, h, point=at_rest, final=False):
        """One step of ``h`` from ``t`` with the input ``u`` held; the driven point after it (a drive's)."""
        if not drive:
            unit.step(key, [u], t, h, step_index=0, final=final)
            return point
        rows = np.array(drive_rows(unit.drive_keys, [list(u)], *point, h))
        unit.step(key, rows, t, h, step_index=0, final=final)
        return tuple(prescribed_end([list(u)], *point, h)[:2])

    unit_inputs = np.eye(n)  # 1 N or 1 m/s^2 on one component: finite whatever the unit's mass
    moving = tuple(k for k in KINEMATICS if k in unit.elements)
    # the motion checks read the unit's own position and velocity outputs (a drive without them has none to check)
    checks_motion = moving[:2] == ("position", "velocity")
    start = unit.save()
    algebraic, step_gain, velocity_gain, position_gain = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    probes = []  # (what, outputs at the start, after one step of H, after the same interval in sub-steps)
    try:
        flag = motion.flag_probe(unit, advance, outputs, unit_inputs[0], start, t0, H, rollback_tolerance)
        put(zero)
        base = outputs()
        base_moving = unit.get(moving) if checks_motion else None
        pushed_moving = []
        for c in range(n):
            put(unit_inputs[c])
            algebraic[c] = outputs()[2, c] - base[2, c]
            pushed_moving.append(unit.get(moving) if checks_motion else None)
        point = 0.0  # a drive: its force's response to its point's position or velocity input, without a step
        for moved in ("position_input", "velocity_input") if drive else ():
            if moved in unit.drive_keys:
                values = {"position_input": rest, "velocity_input": rest, "acceleration_input": rest, moved: [1.0] * n}
                unit.set("drive", [q for k in unit.drive_keys for q in values[k]])
                point = max(point, float(np.max(np.abs(unit.get((out,))[0] - base[2]))))
        put(zero)

        def stepped(u, parts=1):
            unit.restore(start)
            at = at_rest
            for j in range(parts):
                at = advance(u, t0 + j * H / parts, H / parts, at)
            return outputs(at), (unit.get(moving) if checks_motion else None)

        def twice(u):  # two steps: an explicit integration moves the position only in the second
            unit.restore(start)
            at = advance(u, t0, H)
            return outputs(advance(u, t0 + H, H, at))[0]

        first, first_moving = stepped(zero)
        again, _ = stepped(zero)
        still = twice(zero)
        if checks_motion:
            probes.append(("without input", base_moving, first_moving, stepped(zero, MOVE_SUBSTEPS)[1]))
        for c in range(n):
            pushed, pushed_end = stepped(unit_inputs[c])
            step_gain[c] = pushed[2, c] - first[2, c]
            velocity_gain[c] = pushed[1, c] - first[1, c]
            position_gain[c] = twice(unit_inputs[c])[c] - still[c]
            if checks_motion:
                what = "with a unit input" + (f" on component {c + 1}" if n > 1 else "")
                probes.append((what, pushed_moving[c], pushed_end, stepped(unit_inputs[c], MOVE_SUBSTEPS)[1]))
        unit.restore(start)
        put(zero)
        back = outputs()
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
    rollback = _not_finite(unit, kind, base, first, again, back) or _rollback(
        unit, first, again, base, back, rollback_tolerance
    )
    if flag is not None:
        if rollback.verdict == "refused":
            flag = Finding(
                "doStep flag",
                "refused",
                f"{flag.detail}; and with the flag it needs (true on every step) its restored steps do not repeat: "
                f"{rollback.detail}",
                "the coupling repeats steps from saved states: a unit that integrates again from where it stood "
                "before, rather than from its restored state, cannot be coupled; export it without that behaviour",
            )
        found.findings.append(flag)
    found.findings.append(rollback)
    found.findings.append(_feedthrough(kind, found, float(step_gain[c]), float(velocity_gain[c])))
    found.findings.append(_direction(kind, found, force_sign, float(velocity_gain[c])))
    fit = kinematic_fit(unit, H=H, t0=t0) if kind == "kinematic" else force_fit(unit)
    found.findings.append(Finding("role", *fit))
    if checks_motion:
        found.findings.append(motion.moves(unit, H, moving, probes, rollback_tolerance))
        if not drive:  # a drive's point moves as the master prescribes it
            found.findings.append(motion.responds(unit, kind, key, position_gain, velocity_gain))
    found.findings.append(_units(unit))
    found.findings.append(_starts(unit))
    if unit.description_problems:
        problems = "; ".join(unit.description_problems)
        found.findings.append(
            Finding("description", "note", f"fmpy's validation of its modelDescription.xml reports: {problems}")
        )
    return found


def _not_finite(unit, kind, base, first, again, back) -> Finding | None:
    """A refusal where the unit's outputs are not finite at its start, after a step with its input at zero (or
    that step repeated) or restored (a NaN is no value to compare: the rollback check would blame the restore);
    None where they are finite."""
    keys = ("position", "velocity", "acceleration" if kind == "force" else "reaction_force")
    after = "after a step with its input at zero"
    read = (("at its start", base), (after, first), (f"{after}, repeated", again), ("restored", back))
    for when, values in read:
        bad = np.argwhere(~np.isfinite(np.asarray(values, dtype=float)))
        if bad.size:
            row, col = (int(i) for i in bad[0])
            name = unit.elements[keys[row]][col].name
            return Finding(
                "outputs",
                "refused",
                f"its {keys[row]} {name} is {float(values[row][col])!r} {when}{unit.said()}",
                "a unit whose outputs are not finite cannot be coupled: check its start values and parameters",
            )
    return None


def _rollback(unit, first, again, base, back, tol) -> Finding:
    """A step repeated from the restored start, and the restored start itself, against the first: the largest
    relative difference (kept as :attr:`Unit.rollback_difference`) within ``tol`` (:func:`rollback_tolerance`)."""
    names = ("position", "velocity", "coupling output")
    worst, where = 0.0, None
    for what, a, b in (("after a repeated step", first, again), ("after restoring the saved state", base, back)):
        d = relative(a, b)
        if d.size and float(np.max(d)) > worst:
            worst = float(np.max(d))
            if where is None and worst > tol:  # the first that differs is named
                row, col = (int(i) for i in np.unravel_index(int(np.argmax(d)), d.shape))
                where = (what, float(np.asarray(a)[row, col]), float(np.asarray(b)[row, col]), row, col, worst)
    unit.rollback_difference = worst
    flag = " (stepped with noSetFMUStatePriorToCurrentPoint true)" if unit.always_final else ""
    if where is not None:
        what, a, b, row, col, by = where
        return Finding(
            "rollback",
            "refused",
            f"its {names[row]} (component {col + 1}) differs {what}{flag}: {a!r} then {b!r}, {by:.3g} relative, "
            f"more than the rollback tolerance {tol:g} (the restored state is not the saved one: the coupling's "
            "difference quotients and corrector would follow that difference, not the unit's response)",
            "the coupling repeats steps from saved states, so a unit whose fmi2SetFMUstate does not restore "
            "everything cannot be coupled (rollback_tolerance in the subsystem accepts a larger relative difference)",
        )
    if worst == 0:
        return Finding("rollback", "pass", f"a restored step repeats bit for bit{flag}")
    return Finding("rollback", "pass", f"a restored step repeats within {worst:.3g} relative (tolerance {tol:g}){flag}")


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

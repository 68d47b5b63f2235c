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

from .drives import KINEMATICS, drive_rows, is_drive, prescribed_end
from .errors import FmuError
from .roles import kinematic_fit

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


#: The relative difference accepted by default between a step and the same step repeated from a restored state
#: (a subsystem's ``rollback_tolerance`` replaces it): see :func:`rollback_tolerance`.
ROLLBACK_TOLERANCE = 1e-12

#: Sub-steps in which the movement check takes a probing step again.
MOVE_SUBSTEPS = 2


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


def _relative(a, b) -> np.ndarray:
    """``|a - b| / max(|a|, |b|)`` elementwise (0 where both are 0, inf where either is not finite)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    size = np.maximum(np.abs(a), np.abs(b))
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.where(a == b, 0.0, np.abs(a - b) / size)
    return np.where(np.isfinite(a) & np.isfinite(b), d, np.inf)


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
            unit.put("drive", [q for k in unit.drive_keys for q in values[k]])
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
        flag = _flag_probe(unit, advance, outputs, unit_inputs[0], start, t0, H, rollback_tolerance)
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
                unit.put("drive", [q for k in unit.drive_keys for q in values[k]])
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
    if kind == "kinematic":
        found.findings.append(Finding("role", *kinematic_fit(unit, H=H, t0=t0)))
    if checks_motion:
        found.findings.append(_moves(unit, H, moving, probes, rollback_tolerance))
        if not drive:  # a drive's point moves as the master prescribes it
            found.findings.append(_responds(unit, kind, key, position_gain, velocity_gain))
    found.findings.append(_units(unit))
    found.findings.append(_starts(unit))
    if unit.description_problems:
        problems = "; ".join(unit.description_problems)
        found.findings.append(
            Finding("description", "note", f"fmpy's validation of its modelDescription.xml reports: {problems}")
        )
    return found


def _flag_probe(unit, advance, outputs, push, start, t0, H, tol) -> Finding | None:
    """Does the unit's step depend on doStep's ``noSetFMUStatePriorToCurrentPoint``?  From the restored start,
    a step of ``H`` (flag true) and a second one taken with each value of the flag (the same history before it,
    the input ``push`` held: the unit moves), and the first pair again (a unit that does not repeat it is
    not restored, which the rollback check names).  FMI 2.0 (section 4.2.2) and 3.0 say the flag only tells whether
    a state before the current point may later be restored; a unit that reads false as "reject the last step
    and integrate it again from its start" stands still under a master that rolls back.  None: it does not
    depend on it; else a note, and the unit is stepped with true on every step (:attr:`Unit.always_final`)."""
    ends = []
    for final in (True, False, True):
        unit.restore(start)
        point = advance(push, t0, H, final=True)
        ends.append(outputs(advance(push, t0 + H, H, point, final=final)))
    unit.restore(start)
    if np.any(_relative(ends[0], ends[2]) > tol):
        return None  # the same steps do not repeat: a restore that fails, which the rollback check names
    ends = {True: ends[0], False: ends[1]}
    d = _relative(ends[True], ends[False])
    if not np.any(d > tol):
        return None
    unit.always_final = True
    row, col = (int(i) for i in np.argwhere(d > tol)[0])
    keys = (*KINEMATICS[:2], "acceleration" if "force" in unit.elements else "reaction_force")
    name = unit.elements[keys[row]][col].name if keys[row] in unit.elements else f"{keys[row]} (prescribed)"
    return Finding(
        "doStep flag",
        "note",
        f"its step depends on doStep's noSetFMUStatePriorToCurrentPoint (the standard gives it no such meaning): "
        f"after two steps of {H:g} s its {name} is {float(ends[True][row, col])!r} with true on the second, "
        f"{float(ends[False][row, col])!r} with false; it is stepped with true on every step",
    )


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
        d = _relative(a, b)
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


def _moves(unit, H, moving, probes, tol) -> Finding:
    """Does the unit move as its outputs say?  Over each probing step of ``H`` (outputs ``s`` at its start,
    ``e`` at its end): the position's change against the trapezoid integral of the velocity, the velocity's
    against the acceleration's; and the step against the same interval taken in :data:`MOVE_SUBSTEPS`
    sub-steps.

    The tolerance: a consistent one-step integration of any order changes ``x`` by ``H v(xi)`` for some ``xi``
    in the step (the mean value theorem for the exact solution; explicit and implicit Euler at the step's two
    ends), so over a step short enough that ``v`` is monotone the change lies between ``H v(s)`` and ``H v(e)``
    and departs from the trapezoid by at most ``H |v(e) - v(s)| / 2``; twice that is allowed, ``H |v(e) -
    v(s)|``, plus the unit's relative tolerance ``tol`` (its rollback tolerance, at least 16 rounding units) of
    the quantity's scale ``max |x| + H max |v|`` over the step and the components (for the velocity ``max |x| / H
    + max |v| + H max |a|``: a velocity is known to the rounding of the position it moves).  Sub-steps are held to the same bound (two first-order integrations of one interval differ
    by at most ``H^2 |a| / 2``).  A unit that does not integrate (stands still, or moves every other step) is
    off by the whole change."""
    rtol = max(float(tol), 16 * np.finfo(float).eps)
    pairs = [(0, 1)] + ([(1, 2)] if len(moving) == 3 else [])
    worst = None
    for what, s, e, sub in probes:
        for lo, hi in pairs:  # the quantity and its derivative
            # the scale of every component and level (a velocity at rest beside a position of 1 m is known to the
            # rounding of that position over H, not to 0)
            size = sum(np.max(np.abs([s[j], e[j], sub[j]])) * H ** (j - lo) for j in range(hi + 1))
            floor = rtol * size
            for c in range(s.shape[1]):
                x0, x1, d0, d1 = s[lo, c], e[lo, c], s[hi, c], e[hi, c]
                trapezoid = H * (d0 + d1) / 2
                allowed = H * abs(d1 - d0) + floor
                for check, measured, against in (
                    ("trapezoid", x1 - x0, trapezoid),
                    ("sub-steps", sub[lo, c] - x0, x1 - x0),
                ):
                    defect = abs(measured - against)
                    if not defect <= allowed:
                        excess = defect / allowed if allowed > 0 else np.inf
                        if worst is None or excess > worst[0]:
                            worst = (excess, what, lo, hi, c, check, measured, against, allowed, d0, d1)
    if worst is None:
        return Finding(
            "moves",
            "pass",
            f"over a step of {H:g} s its position changes as its velocity integrates"
            + (", its velocity as its acceleration" if len(moving) == 3 else "")
            + f" (trapezoid), and {MOVE_SUBSTEPS} sub-steps agree",
        )
    _, what, lo, hi, c, check, measured, against, allowed, d0, d1 = worst
    quantity, rate = unit.elements[moving[lo]][c].name, unit.elements[moving[hi]][c].name
    if check == "trapezoid":
        said = (
            f"over a step of {H:g} s {what}, its {moving[lo]} {quantity} changes by {measured:.6g} but the "
            f"trapezoid integral of its {moving[hi]} {rate} ({d0:.6g} to {d1:.6g}) is {against:.6g}"
        )
    else:
        said = (
            f"over {H:g} s {what}, its {moving[lo]} {quantity} changes by {against:.6g} in one step but by "
            f"{measured:.6g} in {MOVE_SUBSTEPS} sub-steps (sub-step check)"
        )
    return Finding(
        "moves",
        "refused",
        f"{said}: off by {abs(measured - against):.3g}, more than the {allowed:.3g} a consistent integration "
        "allows: the unit does not move as its outputs say",
        "a unit with a fixed internal step larger than the macro step, or one that does not integrate over the "
        "step it is given, cannot be coupled at this H: take H a multiple of the unit's internal step, or check "
        f"that {moving[lo]} and {moving[hi]} name the unit's {moving[lo]} and its derivative",
    )


def _responds(unit, kind, key, position_gain, velocity_gain) -> Finding:
    """With a unit input, the velocity must have moved after a step and the position after two (an explicit
    integration moves it only in the second), both the same way: a gain of exactly zero is a variable that does
    not follow the input, e.g. a constant named as the position."""
    per = "N" if kind == "force" else "m/s^2"
    when = {"position": "two steps", "velocity": "a step"}
    for name, gains in (("position", position_gain), ("velocity", velocity_gain)):
        c = int(np.argmax(np.abs(np.nan_to_num(gains))))
        if not np.isfinite(gains[c]) or gains[c] == 0:
            var = unit.elements[name][0].name
            return Finding(
                "responds",
                "refused",
                f"its {name} {var} does not respond to its {key} ({float(gains[c])!r} {_unit_of(name)} per {per} "
                f"after {when[name]}): it is not the {name} of the body the input drives",
                f"name the unit's {name} output as {name}",
                name,
            )
    bad = np.sign(position_gain) * np.sign(velocity_gain) < 0
    if bad.any():
        c = int(np.argmax(bad))
        return Finding(
            "responds",
            "refused",
            f"its position moves by {position_gain[c]:+.3g} m in two steps but its velocity by "
            f"{velocity_gain[c]:+.3g} m/s in one, per {per} of its input: the outputs contradict each other",
        )
    return Finding(
        "responds",
        "pass",
        f"its position moves by {position_gain[0]:+.3g} m in two steps, its velocity by {velocity_gain[0]:+.3g} "
        f"m/s in one, per {per} of its input",
    )


def _unit_of(name) -> str:
    return {"position": "m", "velocity": "m/s"}[name]


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

"""A unit must move as it says (docs/fmi.md): the checks of its motion over the probing steps of
:func:`icosim.problems.fmu.inspection.inspect_unit`.

* **doStep flag** -- does the unit's step depend on ``noSetFMUStatePriorToCurrentPoint`` (:func:`flag_probe`);
* **moves** -- the position's change against the trapezoid integral of the velocity, the velocity's against the
  acceleration's, a step against the same interval in sub-steps (:func:`moves`);
* **responds** -- the position and velocity follow the input at all, the same way (:func:`responds`).
"""

from __future__ import annotations

import numpy as np

from .drives import KINEMATICS
from .findings import Finding, relative

__all__ = ["MOVE_SUBSTEPS", "flag_probe", "moves", "responds"]

#: Sub-steps in which the movement check takes a probing step again.
MOVE_SUBSTEPS = 2


def flag_probe(unit, advance, outputs, push, start, t0, H, tol) -> Finding | None:
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
    if np.any(relative(ends[0], ends[2]) > tol):
        return None  # the same steps do not repeat: a restore that fails, which the rollback check names
    ends = {True: ends[0], False: ends[1]}
    d = relative(ends[True], ends[False])
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


def moves(unit, H, moving, probes, tol) -> Finding:
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


def responds(unit, kind, key, position_gain, velocity_gain) -> Finding:
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

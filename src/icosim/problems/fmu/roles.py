"""Does a unit fit the role the scene gives it?  A force-driven unit takes the force on its coupling point and
outputs that point's motion; a kinematically driven unit takes the point's acceleration and outputs the force its
drive exerts; a compliant unit takes a velocity and returns a force (OSP's Wheel: ``in_vel`` in,
``out_spring_damper_f`` out), which is joined as a drive through its velocity (``velocity_input``), or by signal
(power-bond) coupling, which icosim does not yet offer.

What separates them (docs/fmi.md, roles):

* declared units of measure or quantities: a role input declared as a velocity is a compliant unit's
  (:func:`velocity_input`, read where :mod:`icosim.problems.fmu.measures` reads the units);
* measured, in a kinematic role: the drive prescribes the point's motion, so over one step ``H`` with the
  acceleration input held at ``delta`` the acceleration output moves by exactly ``delta`` and the velocity by
  ``H delta``, whatever else the unit holds (:func:`kinematic_fit`).  A unit whose outputs move otherwise is not
  driven at the point it outputs; where its acceleration moves at once by a factor other than 1 and its drive force
  with it, it responds as a compliant unit does (read as a velocity input: a damping over a mass, 1/s, and a
  damping, N s/m);
* in a force role the named port alone cannot tell a velocity input from a force: any passive response of the
  point's velocity to the input (a positive-real mobility) is that of some network of masses, springs and dampers
  driven by a force, so only the declared units or quantities refuse a compliant unit there.
"""

from __future__ import annotations

import numpy as np

from .errors import FmuError

__all__ = ["velocity_input", "kinematic_fit", "COMPLIANT"]

#: What a compliant unit is and why it is refused.
COMPLIANT = (
    "a compliant unit (velocity in, force out): join it as a drive through its velocity (velocity_input: its "
    "velocity input, reaction_force: the force it returns, as the kinematically driven side of the joint), or by "
    "signal (power-bond) coupling, which icosim does not yet offer"
)

# the FMI quantity attribute (Modelica's names) that says a variable is a velocity
_VELOCITY_QUANTITIES = ("velocity", "linearvelocity", "speed")


def velocity_input(label, key, variable):
    """Refuse a role input (``force``, ``acceleration_input``) whose declared quantity is a velocity, naming it a
    compliant unit's; a unit declared in m/s is refused by :func:`icosim.problems.fmu.measures.measure` alike."""
    quantity = variable.quantity or (variable.declaredType.quantity if variable.declaredType is not None else None)
    if (
        key in ("force", "acceleration_input")
        and quantity
        and quantity.replace(" ", "").lower() in _VELOCITY_QUANTITIES
    ):
        raise FmuError(
            f"{label}: {key}: {variable.name!r} is declared a {quantity} (quantity), but {key} must be "
            f"{'a force' if key == 'force' else 'an acceleration'}: the unit takes a velocity, {COMPLIANT}"
        )


def kinematic_fit(unit, *, H, t0=0.0, tol=1e-2) -> tuple:
    """The kinematic role measured on ``unit`` at its start (left there, its input at zero): with the acceleration
    input held at 1 (SI) on one component over a step ``H``, against 0, the acceleration output must move by 1 on
    that component and the velocity by ``H`` (within ``tol``, relative), the other components not at all.  A unit
    without an acceleration input or output has its kinematics in its inputs: nothing to measure here.  Returns the
    check's ``(verdict, detail, fix, key)`` (:class:`~icosim.problems.fmu.inspection.Finding` ``role``)."""
    key = "acceleration_input"
    if key not in unit.elements or "acceleration" not in unit.elements or "velocity" not in unit.elements:
        return "pass", "no kinematic outputs named: the coupling point's motion is its inputs", "", ""
    if any(k in unit.elements for k in ("position_input", "velocity_input")):  # a drive through several inputs
        return "pass", "its position or velocity inputs prescribe the point's motion with it", "", ""
    n = len(unit.elements[key])
    outputs = ("velocity", "acceleration", "reaction_force")
    start = unit.save()
    try:
        unit.set(key, np.zeros(n))
        at_once = unit.get(outputs)

        def stepped(u):
            unit.restore(start)
            unit.step(key, [u], t0, H, step_index=0)
            return unit.get(outputs)

        base = stepped(np.zeros(n))
        moved = [stepped(np.eye(n)[c]) - base for c in range(n)]
        unit.restore(start)
        unit.set(key, np.eye(n)[0])
        force_at_once = unit.get(outputs)[2] - at_once[2]
    finally:
        unit.restore(start)
        unit.set(key, np.zeros(n))
        unit.free(start)
    for c, d in enumerate(moved):
        want = np.eye(n)[c]
        dv, da = d[0], d[1]
        if np.all(np.abs(da - want) <= tol) and np.all(np.abs(dv - H * want) <= tol * H):
            continue
        acc, vel = unit.elements["acceleration"][c].name, unit.elements["velocity"][c].name
        inp = unit.elements[key][c].name
        detail = (
            f"over a step of H = {H:g} s with its acceleration input {inp} held at 1 m/s^2, its acceleration {acc} "
            f"moves by {da[c]:+.4g} m/s^2 and its velocity {vel} by {dv[c]:+.4g} m/s (a driven point: by 1 and by "
            f"H = {H:g}): the input does not prescribe the motion of the point it outputs"
        )
        force = float(d[2][c]) if np.isfinite(d[2][c]) else 0.0
        if da[c] * force > 0 and abs(da[c] - 1) > tol:
            # a drive force that accelerates a body of the unit's own: read as a velocity input, through a damper
            detail += (
                f"; its drive force moves by {force:+.4g} N{' at once' if abs(force_at_once[c]) > 0 else ''}, "
                f"{force / da[c]:.4g} kg times that acceleration: if {inp} is a velocity, a damping of {force:.4g} "
                f"N s/m on a body of {force / da[c]:.4g} kg ({da[c]:.4g} 1/s, a damping over a mass), the response "
                f"of {COMPLIANT}"
            )
        return (
            "refused",
            detail,
            "a kinematically driven unit names the acceleration input of its coupling point and that point's "
            "position, velocity and acceleration outputs",
            f"subsystems.{unit.label}.acceleration_input",
        )
    return "pass", f"its kinematic outputs move as its acceleration input prescribes (H = {H:g} s)", "", ""

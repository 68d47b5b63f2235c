"""Before a run: identify the scene's units as linear single-mass oscillators from probing steps, and predict the
spectral radius of the coupling for the scene's scheme and every other one (``icosim cosim --predict``), as
``icosim advise`` does for a two-mass system typed in.

A force-driven unit is taken to obey ``m a = -c x - d v + F + F_0`` in the physical coupling force ``F`` (the
joint's multiplier acts with ``+lambda`` on the first unit and ``-lambda`` on the second; the unit's input is
``force_sign`` times it), a kinematically driven one ``F = m a + c x + d v + F_0`` with ``F`` the force its drive
exerts.  From its start the unit takes :data:`PROBES` steps of ``H`` with inputs held over each step; after each,
its coupling output, position and velocity give one row of a least-squares fit of the output against input,
position, velocity and a constant.  Steps, not a re-read of the output with another input, so a unit whose
output follows its input only through a step is identified too.  The inputs are finite whatever the unit: a
first step with a unit input measures how far the unit moves, and the probing input is scaled to move it by
about 1 % of its position scale per step.  The fit's residual, and a last step predicted from the fit, give the
``misfit`` of the linear model (relative): a unit that is not linear is reported, and its prediction is only that
of a linear fit about its start.  One unit's identification may take at most ``limits.identify_seconds``.
"""

from __future__ import annotations

import time

import numpy as np

from ...engine.decompositions import get_decomposition
from ...engine.graph import CouplingGraph
from ...engine.schemes import get_scheme, standard_schemes
from ...engine.stages import check, plan
from ..linear.model import PhysicalModel
from .errors import FmuError, SceneError
from .run import open_units

__all__ = ["identify", "predict_scene", "PROBES", "IDENTIFY_SECONDS"]

#: Probing inputs per step, in units of the probing amplitude: no pattern, so that position, velocity and
#: input vary independently (a symmetric sequence makes them collinear); the last step checks the fit.
PROBES = (1.0, -0.3, -0.8, 0.6, 0.2, -1.0, 0.9, -0.4, 0.1)

#: The default time limit of one unit's identification, in seconds.
IDENTIFY_SECONDS = 60.0


def identify(unit, coupling, H, *, physical=1, limit=IDENTIFY_SECONDS) -> dict:
    """``m``, ``c``, ``d``, the constant ``F0`` and the ``misfit`` of the linear model (relative) of one unit, from
    probing steps of ``H`` from its start state (left at its start, restored).  ``physical`` (+1 or -1) is the
    sign of the physical force (or drive force) per unit of the unit's input (or coupling output)."""
    kind = coupling.kind
    key = coupling.input_key
    out = "acceleration" if kind == "force" else "reaction_force"
    clock = time.perf_counter()
    start = unit.save()
    rows, values = [], []
    try:
        x0, v0 = unit.get(("position", "velocity"))[:, 0]
        scale = max(1.0, abs(x0))

        def step(u):
            if time.perf_counter() - clock > limit:
                raise FmuError(
                    f"{unit.label}: --predict: identifying the unit took longer than {limit:g} s "
                    f"(after {len(rows)} probing steps); raise limits.identify_seconds in the scene"
                )
            unit.step(key, [u], unit.t, H, step_index=0)
            x, v, q = unit.get(("position", "velocity", out))[:, 0]
            return x, v, q

        if kind == "force":
            # a unit force over one step moves the unit by dv = H/m: it sizes the probing force
            x1, v1, _ = step(1.0)
            unit.restore(start)
            x_free, v_free, _ = step(0.0)
            unit.restore(start)
            moved = abs(v1 - v_free) * H + abs(x1 - x_free)
            if not np.isfinite(moved) or moved == 0:
                raise FmuError(f"{unit.label}: --predict: the unit does not move when its force input changes")
            amplitude = 1e-2 * scale / moved
        else:
            amplitude = 2e-2 * scale / H**2
        for p in PROBES:
            u = p * amplitude
            x, v, q = step(u)
            rows.append([u, x, v, 1.0])
            values.append(q)
    finally:
        unit.restore(start)
        unit.free(start)
    A, y = np.array(rows[:-1]), np.array(values[:-1])
    norms = np.linalg.norm(A, axis=0)
    norms[norms == 0] = 1.0
    coef = np.linalg.lstsq(A / norms, y, rcond=None)[0] / norms
    gain, alpha, beta, offset = coef
    fitted = A @ coef
    predicted = np.array(rows[-1]) @ coef
    spread = max(float(np.max(np.abs(values))), abs(gain * amplitude), 1e-300)
    misfit = max(float(np.max(np.abs(fitted - y))), abs(predicted - values[-1])) / spread
    if kind == "force":
        g = gain * physical  # acceleration per unit of physical force
        m = 1.0 / g
        c, d, f0 = -alpha * m, -beta * m, offset * m
        force_scale = abs(m) * spread
    else:
        m, c, d, f0 = gain * physical, alpha * physical, beta * physical, offset * physical
        force_scale = spread
    if abs(f0) <= 1e-9 * force_scale:  # a constant at the fit's rounding is none
        f0 = 0.0
    return {"m": float(m), "c": float(c), "d": float(d), "F0": float(f0), "misfit": float(misfit)}


def predict_scene(scene) -> dict:
    """The identified units and the spectral radius of the scene's coupling for every standard scheme
    (float64 with its error estimate, :func:`icosim.problems.linear.spectral.spectral_radius_float64`)."""
    from ...errors import ParameterError
    from ..linear.spectral import spectral_radius_float64

    c = scene.coupling
    H = float(c["H"])
    if any(isinstance(sub["position"], list) and len(sub["position"]) > 1 for sub in scene.data["subsystems"].values()):
        raise SceneError(
            f"{scene.path}: --predict identifies single-mass oscillators (one position per unit); this scene's "
            "joint has more components"
        )
    limit = float(scene.data.get("limits", {}).get("identify_seconds", IDENTIFY_SECONDS))
    units, couplings = open_units(scene)
    try:
        found = {}
        for u, cp in zip(units, couplings):
            before = u.do_steps
            physical = np.sign(cp.gain)  # the joint acts with opposite signs on the two units (checked)
            found[u.label] = identify(u, cp, H, physical=physical, limit=limit)
            found[u.label] |= {"probe_do_step_calls": u.do_steps - before, "feedthrough": cp.feedthrough}
    finally:
        for unit in units:
            unit.close()
    p1, p2 = found.values()
    for name, p in found.items():
        if not (np.isfinite(p["m"]) and p["m"] > 0):
            raise FmuError(f"{name}: --predict: the identified mass is {p['m']!r}; the unit is not a driven mass")
    model = PhysicalModel(m1=p1["m"], m2=p2["m"], c1=p1["c"], c2=p2["c"], d1=p1["d"], d2=p2["d"], H=H)
    dec = get_decomposition(c["decomposition"])
    names = list(dict.fromkeys([get_scheme(c["scheme"]).name, *standard_schemes()]))
    rows = []
    for name in names:
        scheme = get_scheme(name)
        row = {"scheme": name, "scene": name == get_scheme(c["scheme"]).name}
        try:
            check(scheme, dec)
        except (ParameterError, AttributeError) as exc:
            rows.append(row | {"rho": None, "verdict": "not defined", "reason": str(exc)})
            continue
        lacking = [units[i].label for i in plan(scheme, CouplingGraph.pair(dec)).reevaluated
                   if not couplings[i].feedthrough]  # fmt: skip
        if lacking:
            why = f"it re-evaluates {lacking[0]} without a step, which has no direct feedthrough"
            rows.append(row | {"rho": None, "verdict": "not defined", "reason": why})
            continue
        rho, err = spectral_radius_float64(model.coefficients(), scene.method, dec, c["k"], scheme=scheme)
        rho, err = float(rho), float(err)
        verdict = "stable" if rho + err < 1 else "unstable" if rho - err > 1 else "undecided"
        rows.append(row | {"rho": rho, "rho_error": err, "verdict": verdict})
    return {
        "scene": str(scene.path),
        "units": found,
        "H": H,
        "method": scene.method.name,
        "decomposition": dec.name,
        "k": c["k"],
        "schemes": rows,
    }

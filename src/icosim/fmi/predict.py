"""Before a run: identify the scene's units as linear single-mass oscillators from a few probing steps, and
predict the spectral radius of the coupling for the scene's scheme and every other one (``icosim cosim
--predict``), as ``icosim advise`` does for a two-mass system typed in.

A force-driven unit's acceleration is taken to be linear in its state and input, ``a = (-c x - d v + u)/m``:
its value at the start state with two inputs gives ``1/m``; two probing steps from the restored start (a probing
force one way and the other) give two more states, and the three states give ``c`` and ``d`` (least squares).
A kinematically driven unit's reaction force ``F = m a + c x + d v`` is read the same way.  The fit's residual
and one more evaluation check the linear model (``misfit``, relative): a unit that is not linear (or has a
preload) is reported, and its prediction is only that of a linear fit about its start.
"""

from __future__ import annotations

import numpy as np

from ..engine.decompositions import get_decomposition
from ..engine.model import PhysicalModel
from ..engine.schemes import get_scheme, standard_schemes
from .errors import SceneError
from .run import open_units

__all__ = ["identify", "predict_scene"]


def identify(unit, coupling, H) -> dict:
    """``m``, ``c``, ``d`` and the ``misfit`` of the linear model (relative) of one unit, from its start state;
    the unit is left at its start state (restored)."""
    start = unit.save()
    key = coupling.input_key
    out = "acceleration" if coupling.kind == "force" else "reaction_force"
    try:

        def probe(u):
            unit.set(key, u)
            return unit.get(("position", "velocity", out))[:, 0]

        x0, v0, q0 = probe(0.0)
        q1 = probe(1.0)[2]
        gain = q1 - q0  # 1/m (force driven) or m (kinematic)
        rows, values = [[x0, v0]], [q0]
        scale = max(1.0, abs(x0))
        # probing inputs that move the mass by about 1% of its scale over one step, one way and the other
        amplitude = 2e-2 * scale / H**2 * (1 / gain if coupling.kind == "force" else 1.0)
        for u in (amplitude, -amplitude):
            unit.restore(start)
            unit.step(key, [u], 0.0, H, step_index=0)
            x, v, q = probe(0.0)
            rows.append([x, v])
            values.append(q)
        (alpha, beta), *_ = np.linalg.lstsq(np.array(rows), np.array(values), rcond=None)
        # the affine model checked on all three states and at the last one with input 1
        fitted = np.array(rows) @ [alpha, beta]
        predicted = fitted[-1] + gain
        measured = probe(1.0)[2]
        spread = max(np.max(np.abs(values)), abs(gain), 1e-300)
        misfit = max(np.max(np.abs(fitted - values)), abs(measured - predicted)) / spread
    finally:
        unit.restore(start)
        unit.free(start)
    if coupling.kind == "force":
        m = 1.0 / gain
        c, d = -alpha * m, -beta * m
    else:
        m, c, d = gain, alpha, beta
    return {"m": float(m), "c": float(c), "d": float(d), "misfit": float(misfit)}


def predict_scene(scene) -> dict:
    """The identified units and the spectral radius of the scene's coupling for every standard scheme
    (float64 with its error estimate, :func:`icosim.engine.spectral.radius.spectral_radius_float64`)."""
    from ..engine.spectral.radius import spectral_radius_float64
    from ..errors import ParameterError

    c = scene.coupling
    H = float(c["H"])
    if any(isinstance(sub["position"], list) and len(sub["position"]) > 1 for sub in scene.data["subsystems"].values()):
        raise SceneError(
            f"{scene.path}: --predict identifies single-mass oscillators (one position per unit); this scene's "
            "joint has more components"
        )
    units, couplings = open_units(scene)
    try:
        found = {u.label: identify(u, cp, H) for u, cp in zip(units, couplings)}
        counters = {u.label: u.info() for u in units}
    finally:
        for unit in units:
            unit.close()
    p1, p2 = found.values()
    model = PhysicalModel(m1=p1["m"], m2=p2["m"], c1=p1["c"], c2=p2["c"], d1=p1["d"], d2=p2["d"], H=H)
    dec = get_decomposition(c["decomposition"])
    names = list(dict.fromkeys([get_scheme(c["scheme"]).name, *standard_schemes()]))
    rows = []
    for name in names:
        scheme = get_scheme(name)
        row = {"scheme": name, "scene": name == get_scheme(c["scheme"]).name}
        try:
            scheme.check_decomposition(dec)
        except (ParameterError, AttributeError) as exc:
            rows.append(row | {"rho": None, "verdict": "not defined", "reason": str(exc)})
            continue
        rho, err = spectral_radius_float64(model.coefficients(), scene.method, dec, c["k"], scheme=scheme)
        rho, err = float(rho), float(err)
        verdict = "stable" if rho + err < 1 else "unstable" if rho - err > 1 else "undecided"
        rows.append(row | {"rho": rho, "rho_error": err, "verdict": verdict})
    return {
        "scene": str(scene.path),
        "units": {name: {**found[name], "probe_do_step_calls": counters[name]["do_step_calls"]} for name in found},
        "H": H,
        "method": scene.method.name,
        "decomposition": dec.name,
        "k": c["k"],
        "schemes": rows,
    }

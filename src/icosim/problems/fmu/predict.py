"""Before a run: identify the scene's units as linear single-mass oscillators from probing steps, and predict the
spectral radius of the coupling for the scene's scheme and the others (``icosim cosim --predict``), as
``icosim advise`` does for a two-mass system typed in: the identified oscillators joined as the scene joins its
units are the built-in chain model (:func:`scene_chain`, :class:`~icosim.problems.linear.chain.Chain`; two units
are the paper's two-mass model), whose spectral radius is that of the scene's coupling.

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
from dataclasses import dataclass

import numpy as np

from ...engine.schemes import JACOBI, GaussSeidel, Scheme
from ...engine.spectral.radius import spectral_radius_float64
from ...engine.stages import plan
from ..linear.chain import Chain, ChainFamily, ChainSegment
from .drives import KINEMATICS
from .errors import FmuError, SceneError
from .run import open_units

__all__ = ["identify", "predict_scene", "scene_chain", "SceneChain", "PROBES", "IDENTIFY_SECONDS"]

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


@dataclass(frozen=True)
class SceneChain:
    """A scene's units as the built-in chain model (:class:`~icosim.problems.linear.chain.Chain`): the units in a
    row, ``path[q]`` the scene's unit (0-based, file order) that is the chain's segment ``q``; chain joint ``q``
    is the scene's joint ``joints[q]``, its sides exchanged where ``flipped[q]`` (the scene names the later unit
    first: ``fd`` becomes ``df``, the multiplier changes sign)."""

    chain: Chain
    path: tuple[int, ...]
    joints: tuple[int, ...]
    flipped: tuple[bool, ...]

    def scheme(self, scheme: Scheme) -> Scheme:
        """``scheme`` of the scene's units as the same scheme of the chain's segments."""
        order = getattr(scheme, "order", None)
        if order is None:
            return scheme
        where = {unit: q for q, unit in enumerate(self.path)}
        return GaussSeidel([where[i - 1] + 1 for i in order], scheme.leading_outputs)

    def orders(self) -> list[tuple[int, ...]]:
        """The Gauss-Seidel orders along the chain, from either end, in the scene's numbers (1-based)."""
        forward = tuple(i + 1 for i in self.path)
        return [forward, forward[::-1]]


def scene_chain(scene, parameters, H=None) -> SceneChain:
    """The chain of single-mass segments ``ChainSegment((m,), (c,), (d,))`` with ``parameters[name]`` (SI: ``m``,
    ``c``, ``d`` per unit) joined as the scene's joints join its units, at the scene's ``H`` (or ``H``).  The
    joints must hold the units in a row (each unit in at most two joints); the row starts at the end unit that
    comes first in the file.  Refused otherwise (:class:`~icosim.problems.fmu.errors.SceneError`)."""
    graph = scene.graph()
    names = scene.names
    crowded = [i for i in range(graph.n_subsystems) if len(graph.neighbours(i)) > 2]
    if crowded:
        i = crowded[0]
        raise SceneError(
            f"{scene.path}: joints: the built-in chain model holds its units in a row, but {names[i]} takes part "
            f"in {len(graph.neighbours(i))} joints; --predict and the chain comparisons need each unit in at most two"
        )
    start = min(i for i in range(graph.n_subsystems) if len(graph.neighbours(i)) == 1)
    path = [start]
    while len(path) < graph.n_subsystems:
        path.append(next(o for o in graph.neighbours(path[-1]) if o not in path))
    joints, flipped, decompositions = [], [], []
    for a, b in zip(path, path[1:]):
        j = next(j for j, jt in enumerate(graph.joints) if {jt.first, jt.second} == {a, b})
        jt = graph.joints[j]
        flip = jt.first != a
        kinds = jt.decomposition.kinds[::-1] if flip else jt.decomposition.kinds
        joints.append(j)
        flipped.append(flip)
        decompositions.append("".join("f" if k == "force" else "d" for k in kinds))
    segments = []
    for i in path:
        p = parameters[names[i]]
        segments.append(ChainSegment((p["m"],), (p["c"],), (p["d"],)))
    H = float(scene.coupling["H"]) if H is None else H
    return SceneChain(Chain(tuple(segments), tuple(decompositions), H), tuple(path), tuple(joints), tuple(flipped))


def _oscillator(name, p, H) -> dict:
    """``p`` with a spring or damper that is zero up to the fit's rounding set to zero (a free mass)."""
    if not (np.isfinite(p["m"]) and p["m"] > 0):
        raise FmuError(f"{name}: --predict: the identified mass is {p['m']!r}; the unit is not a driven mass")
    out = dict(p)
    for key, scale in (("c", H * H / p["m"]), ("d", H / p["m"])):
        if out[key] < 0 and abs(out[key]) * scale <= 1e-9:
            out[key] = 0.0
        if not (np.isfinite(out[key]) and out[key] >= 0):
            raise FmuError(
                f"{name}: --predict: the identified {key} = {out[key]!r} is negative: the unit is not a mass with "
                "a spring and a damper to the ground, which the prediction models"
            )
    return out


def predict_scene(scene, *, opened=None) -> dict:
    """The identified units and the spectral radius of the scene's coupling (float64 with its error estimate,
    :func:`icosim.engine.spectral.radius.spectral_radius_float64` on the built-in chain of the identified
    oscillators, :func:`scene_chain`) for the scene's scheme, Jacobi, the Gauss-Seidel orders along the chain
    from either end, and the scene's order and its reverse; an order the stages cannot serve, or one that
    re-evaluates a unit without feedthrough, is "not defined" with the reason.

    ``opened``: the scene's units and couplings as :func:`~icosim.problems.fmu.run.open_units` returned them, left
    open at their start with their counters as they were (a run may follow on them); else they are opened here
    and closed."""
    from ...errors import ParameterError

    c = scene.coupling
    H = float(c["H"])
    graph = scene.graph()
    for i, (name, sub) in enumerate(scene.data["subsystems"].items()):
        own = [k for k in KINEMATICS if k in sub]
        if graph.port_kind(i, 0) == "kinematic" and (
            len(own) < 3 or "position_input" in sub or "velocity_input" in sub
        ):
            raise SceneError(
                f"{scene.path}: subsystems.{name}: --predict identifies single-mass oscillators driven at their mass "
                f"by an acceleration input; {name} is a drive with the inputs or outputs of another kind of unit "
                "(docs/fmi.md, drives by position, velocity and acceleration): run the scene without --predict"
            )
    if any(isinstance(sub["position"], list) and len(sub["position"]) > 1 for sub in scene.data["subsystems"].values()):
        raise SceneError(
            f"{scene.path}: --predict identifies single-mass oscillators (one position per unit); this scene's "
            "joint has more components"
        )
    scene_chain(scene, {name: {"m": 1.0, "c": 0.0, "d": 0.0} for name in scene.names})  # a row, before any unit
    limit = float(scene.data.get("limits", {}).get("identify_seconds", IDENTIFY_SECONDS))
    units, couplings = open_units(scene) if opened is None else opened
    try:
        found = {}
        for u, cp in zip(units, couplings):
            counters = u.do_steps, u.saved, u.restored, u.warnings, u.first_warning
            physical = np.sign(cp.gain)  # every joint acts with opposite signs on its two units (checked)
            found[u.label] = identify(u, cp, H, physical=physical, limit=limit)
            found[u.label] |= {"probe_do_step_calls": u.do_steps - counters[0], "feedthrough": cp.feedthrough}
            if opened is not None:  # the probes are not the run's: its counters as they were
                u.do_steps, u.saved, u.restored, u.warnings, u.first_warning = counters
    finally:
        if opened is None:
            for unit in units:
                unit.close()
    chain = scene_chain(scene, {name: _oscillator(name, p, H) for name, p in found.items()})
    family = ChainFamily(chain.chain, int(c["k"]))
    graph = scene.graph()
    mine = scene.scheme
    candidates = [mine, JACOBI] + [GaussSeidel(o) for o in chain.orders()]
    if getattr(mine, "order", None) is not None:
        candidates += [
            GaussSeidel(mine.order, mine.leading_outputs),
            GaussSeidel(mine.order[::-1], mine.leading_outputs),
        ]
    schemes = list({s.name: s for s in candidates}.values())
    rows = []
    for scheme in schemes:
        order = getattr(scheme, "order", None)
        row = {
            "scheme": scheme.name,
            "order": None if order is None else [scene.names[i - 1] for i in order],
            "label": scene.scheme_text(scheme),
            "scene": scheme.name == mine.name,
        }
        try:
            p = plan(scheme, graph, scene.method)
        except ParameterError as exc:
            rows.append(row | {"rho": None, "verdict": "not defined", "reason": str(exc)})
            continue
        lacking = [units[i].label for i in p.reevaluated if not couplings[i].feedthrough]
        if lacking:
            why = f"it re-evaluates {lacking[0]} without a step, which has no direct feedthrough"
            rows.append(row | {"rho": None, "verdict": "not defined", "reason": why})
            continue
        rho, err = spectral_radius_float64(family, scene.method, scheme=chain.scheme(scheme))
        rho, err = float(rho), float(err)
        verdict = "stable" if rho + err < 1 else "unstable" if rho - err > 1 else "undecided"
        rows.append(row | {"rho": rho, "rho_error": err, "verdict": verdict})
    return {
        "scene": str(scene.path),
        "units": found,
        "H": H,
        "method": scene.method.name,
        "decomposition": c["decomposition"] if not scene.has_joints else ", ".join(scene.decompositions),
        "coupling": scene.describe(scheme=False),
        "k": c["k"],
        "schemes": rows,
    }

"""Before a run of a signal scene: identify each unit's linear input/output model at its start and predict the
spectral radius of its coupling (``icosim cosim --predict``; docs/signals.md).

The identified units, coupled as the scene's connections couple them, are the built-in signal-coupled model
(:mod:`icosim.problems.linear.signals`), whose recurrence is the macro step's own (by linearity).  Its inputs and
outputs are the unit's connected ones, in SI, in the order :func:`~icosim.problems.fmu.signals.connections_of`
gives them.

* A Model Exchange unit: ``x' = A x + B u``, ``y = C x + D u`` by central differences of its derivatives and
  outputs in its continuous states and inputs at its start.  The difference step of each variable is
  :data:`DIFFERENCE` times its size (at least one); the matrices are formed again with steps a hundred times larger,
  and their largest change relative to their largest entry is the ``misfit`` of the linear model.
* A Co-Simulation unit: the one-step map over the scene's ``H`` with held inputs, ``x_n+1 = Phi x_n + Gamma u_n``,
  ``y_n+1 = C x_n+1 + D u_n`` (a constant beside), by least squares from forward probing steps from its start,
  :data:`CS_PROBES` times as many as a row has unknowns and one more that checks the fit, with inputs drawn at
  random (seeded) in ``+-max(1, |u_start|)``; ``x_n`` are the variables its ModelStructure's ``<Derivatives>`` are
  the derivatives of, read after each step.  The fit's largest residual (the last step's included), relative to
  the largest value fitted, is the ``misfit``.  One unit's probing may take at most ``limits.identify_seconds``.
  Where those variables cannot be read, the unit is "undecided"; with ``k > 0`` the recurrence needs the response
  to an input that changes over the step, which the map over held inputs does not hold: "undecided" too.

The answer: the spectral radius for the scene's scheme and ``k`` (implicit where the scene couples implicitly: the
recurrence of its connections' conditions at ``T_N+1``, :mod:`icosim.engine.connection_conditions`), for explicit
Jacobi and for the Gauss-Seidel orders of the units in the file's order and its reverse (float64 with its error
estimate); and the largest stable
``H`` of the scene's scheme (:func:`~icosim.problems.linear.signals.signal_limit`), a
co-simulation unit's map identified anew at each step the search tries (``k = 0`` only).
"""

from __future__ import annotations

import time

import numpy as np

from ...engine.schemes import JACOBI, GaussSeidel
from ...errors import ParameterError
from ..linear.signals import StateSpaceUnit, signal_limit, signal_radius
from .errors import FmuError, SceneError
from .predict import IDENTIFY_SECONDS

__all__ = [
    "predict_signal_scene",
    "identify_exchange",
    "identify_stepped",
    "DIFFERENCE",
    "CS_PROBES",
    "SCAN_PER_DECADE",
    "SCAN_PER_DECADE_STEPPED",
]

#: The relative difference step of the Model Exchange identification.
DIFFERENCE = 1e-6

#: Probing rows of a co-simulation unit, per unknown of one fitted row (its states, inputs and the constant).
CS_PROBES = 3

#: Step sizes a decade of the largest stable H's scan: dense for continuous models (a radius costs an eigenvalue
#: problem), sparse for co-simulation units (identified anew at each).
SCAN_PER_DECADE, SCAN_PER_DECADE_STEPPED = 64, 4


def _jacobians(unit, x0, u0, rel, inputs, outputs):
    """``A, B, C, D`` by central differences with steps ``rel`` times each variable's size (at least ``rel``)."""
    from .signals import INPUTS, OUTPUTS

    def at(x, u):
        if inputs:
            unit.set(INPUTS, u)
        dx, y = unit.derivatives(x, (OUTPUTS,) if outputs else None)
        return np.concatenate([dx, np.zeros(0) if y is None else y.ravel()])

    nx, nu = len(x0), len(u0)
    cols = []
    for j in range(nx + nu):
        h = rel * max(1.0, abs(x0[j] if j < nx else u0[j - nx]))
        e = np.zeros(nx + nu)
        e[j] = h
        cols.append((at(x0 + e[:nx], u0 + e[nx:]) - at(x0 - e[:nx], u0 - e[nx:])) / (2 * h))
    J = np.array(cols).T if cols else np.zeros((nx + len(outputs), 0))
    return J[:nx, :nx], J[:nx, nx:], J[nx:, :nx], J[nx:, nx:]


def identify_exchange(unit, inputs, outputs) -> dict:
    """A Model Exchange unit's ``A, B, C, D`` at its start (module docstring); the unit is left at its start."""
    from .signals import INPUTS

    start = unit.save()
    x0 = np.array(start[0], dtype=float)
    u0 = unit.get((INPUTS,)).ravel() if inputs else np.zeros(0)
    try:
        fine = _jacobians(unit, x0, u0, DIFFERENCE, inputs, outputs)
        coarse = _jacobians(unit, x0, u0, 100 * DIFFERENCE, inputs, outputs)
    finally:
        unit.restore(start)
    scale = max([float(np.max(np.abs(m))) for m in fine if m.size] + [1e-300])
    misfit = max(float(np.max(np.abs(a - b))) for a, b in zip(fine, coarse) if a.size) / scale
    names = [d.variable.derivative.name if d.variable.derivative else d.variable.name for d in unit.md.derivatives]
    return {"interface": "model-exchange", "model": "continuous", "states": names, "A": fine[0], "B": fine[1],
            "C": fine[2], "D": fine[3], "misfit": misfit, "evaluations": 4 * (len(x0) + len(u0))}  # fmt: skip


def identify_stepped(unit, inputs, outputs, H, *, seed=0, limit=IDENTIFY_SECONDS) -> dict:
    """A Co-Simulation unit's one-step map over ``H`` with held inputs (module docstring), from forward steps of the
    unit from its start (it is left where they end: close it after); at most ``limit`` seconds."""
    from .signals import INPUTS, OUTPUTS

    clock = time.perf_counter()
    names = [d.variable.derivative.name if d.variable.derivative else None for d in unit.md.derivatives]
    found = {"interface": "co-simulation", "model": f"one-step map over H = {H:g} s", "states": names}
    if None in names or (not names and unit.md.numberOfContinuousStates):
        return found | {"undecided": "its ModelStructure does not name its state variables (a <Derivatives> entry "
                        "without the state it is the derivative of), so its one-step map cannot be read"}  # fmt: skip
    try:
        x = np.array([unit.get_named(n) for n in names])
    except (FmuError, KeyError, ValueError) as exc:
        return found | {"undecided": f"its state variables {', '.join(names)} cannot be read ({exc})"}
    nx, nu = len(names), len(inputs)
    u0 = unit.get((INPUTS,)).ravel() if inputs else np.zeros(0)
    scale = np.maximum(1.0, np.abs(u0))
    rng = np.random.default_rng(seed)
    rows = CS_PROBES * (nx + nu + 1) + 1  # the last one checks the fit
    before, after, ins, outs = [], [], [], []
    for n in range(rows):
        if time.perf_counter() - clock > limit:
            raise FmuError(f"{unit.label}: --predict: identifying the unit took longer than {limit:g} s (after {n} "
                           "probing steps); raise limits.identify_seconds in the scene")  # fmt: skip
        u = scale * rng.uniform(-1.0, 1.0, nu)
        if inputs:
            unit.step(INPUTS, u[None], unit.t, H, step_index=n + 1, final=True)
        else:
            unit._do_step(unit.t, H, n + 1, True)
            unit.t += H
        x_new = np.array([unit.get_named(n_) for n_ in names])
        before.append(x), after.append(x_new), ins.append(u)
        outs.append(unit.get((OUTPUTS,)).ravel() if outputs else np.zeros(0))
        x = x_new
    X0, X1, U, Y = map(np.array, (before, after, ins, outs))
    one = np.ones((rows, 1))
    fits, misfit = [], 0.0
    for basis, target in ((np.hstack([X0, U, one]), X1), (np.hstack([X1, U, one]), Y)):
        norms = np.linalg.norm(basis[:-1], axis=0)
        norms[norms == 0] = 1.0
        coef = np.linalg.lstsq(basis[:-1] / norms, target[:-1], rcond=None)[0] / norms[:, None]
        fits.append(coef.T)
        spread = max(float(np.max(np.abs(target))) if target.size else 0.0, 1e-300)
        misfit = max(misfit, float(np.max(np.abs(basis @ coef - target), initial=0.0)) / spread)
    (F, G), (Cy, Dy) = ((f[:, :nx], f[:, nx : nx + nu]) for f in fits)
    if nx and np.max(np.abs(X1 - X0), initial=0.0) == 0.0:
        return found | {"undecided": f"its state variables {', '.join(names)} do not change over its steps"}
    return found | {"A": F, "B": G, "C": Cy, "D": Dy, "misfit": misfit, "probe_do_step_calls": rows}


def _open(scene, name, keys):
    from .exchange import ExchangeUnit, open_fmu_unit
    from .signal_scene import _fmu_path
    from .signals import ForwardUnit

    sub, c = scene.subsystems[name], scene.coupling
    start, path = dict(sub.get("start") or {}), _fmu_path(scene, sub)
    if sub.get("interface", "co-simulation") == "co-simulation":
        return ForwardUnit(name, path, keys, start, inputs=c["inputs"], substeps=c["substeps"], t0=scene.t0)
    unit = open_fmu_unit(name, path, keys, start, interface=sub["interface"], tolerance=sub.get("tolerance"),
                         inputs=c["inputs"], substeps=c["substeps"], t0=scene.t0)  # fmt: skip
    if not isinstance(unit, ExchangeUnit):  # interface auto chose co-simulation: stepped forward only
        unit.close()
        return ForwardUnit(name, path, keys, start, inputs=c["inputs"], substeps=c["substeps"], t0=scene.t0)
    return unit


def predict_signal_scene(scene) -> dict:
    """The identified units and the spectral radius of the scene's coupling, explicit or implicit (module
    docstring)."""
    from ...engine.graph import CouplingGraph
    from .description import read_description
    from .exchange import ExchangeUnit
    from .signal_scene import _fmu_path
    from .signals import INPUTS, OUTPUTS, connections_of, feedthrough_loop

    names, c = list(scene.names), scene.coupling
    H, k = float(c["H"]), int(c["k"])
    cons, inputs, outputs = connections_of(scene.connections, names)
    graph = CouplingGraph(len(names), (), names=tuple(names), connections=tuple(cons))
    mds = [read_description(n, _fmu_path(scene, scene.subsystems[n]))[0] for n in names]
    loop = feedthrough_loop(graph, inputs, outputs, mds)
    if loop:
        text = ", ".join(f"{names[cons[j].source]}.{outputs[cons[j].source][cons[j].output]} -> "
                         f"{names[cons[j].target]}.{inputs[cons[j].target][cons[j].input]}" for j in loop)  # fmt: skip
        raise SceneError(f"{scene.path}: connections: an algebraic loop (each input feeds an output of its unit "
                         f"directly, by the units' ModelStructure): {text}; a run solves it at each point, "
                         "but --predict has no recurrence of the units' steps with a loop solved to give")  # fmt: skip
    seconds = float(scene.data.get("limits", {}).get("identify_seconds", IDENTIFY_SECONDS))

    def identified(i: int, h: float) -> dict:
        """Unit ``i`` opened at its start, identified with the macro step ``h``, closed."""
        keys = {key: v for key, v in ((INPUTS, inputs[i]), (OUTPUTS, outputs[i])) if v}
        unit = _open(scene, names[i], keys)
        try:
            if isinstance(unit, ExchangeUnit):
                return identify_exchange(unit, inputs[i], outputs[i])
            return identify_stepped(unit, inputs[i], outputs[i], h, limit=seconds)
        finally:
            unit.close()

    def model(u: dict, h: float) -> StateSpaceUnit:
        return StateSpaceUnit(u["A"], u["B"], u["C"], u["D"], None if u["model"] == "continuous" else h)

    found, models = {}, []
    for i, name in enumerate(names):
        u = identified(i, H)
        found[name] = u | {"inputs": list(inputs[i]), "outputs": list(outputs[i])}
        models.append(None if "undecided" in u else model(u, H))
    mine, implicit = scene.scheme, bool(c.get("implicit"))
    order = list(range(1, len(names) + 1))
    candidates = [(mine, implicit), (JACOBI, False), (GaussSeidel(order), False), (GaussSeidel(order[::-1]), False)]
    schemes = list({(s.name, imp): (s, imp) for s, imp in candidates}.values())
    undecided = [(n, u["undecided"]) for n, u in found.items() if "undecided" in u]
    rows = []
    for scheme, imp in schemes:
        seq = getattr(scheme, "order", None)
        label = "Jacobi" if seq is None else "Gauss-Seidel " + " -> ".join(names[j - 1] for j in seq)
        row = {"scheme": scheme.name, "order": None if seq is None else [names[j - 1] for j in seq],
               "label": f"implicit {label}" if imp else label, "implicit": imp,
               "scene": (scheme.name, imp) == (mine.name, implicit)}  # fmt: skip
        if undecided:
            rows.append(row | {"rho": None, "verdict": "undecided", "reason": f"{undecided[0][0]}: {undecided[0][1]}"})
            continue
        try:
            rho, err = signal_radius(models, cons, k, H, scheme, implicit=imp)
        except ParameterError as exc:
            cs = [n for n, u in found.items() if u["model"] != "continuous"]
            why = f"{cs[0]} is a co-simulation unit: {exc}" if cs and k > 0 else str(exc)
            rows.append(row | {"rho": None, "verdict": "undecided", "reason": why})
            continue
        verdict = "stable" if rho + err < 1 else "unstable" if rho - err > 1 else "undecided"
        rows.append(row | {"rho": rho, "rho_error": err, "verdict": verdict})
    limit: dict = {"H_max": None}
    stepped = [i for i, u in enumerate(found.values()) if u["model"] != "continuous"]
    if undecided:
        limit["reason"] = f"{undecided[0][0]}: {undecided[0][1]}"
    elif stepped and k > 0:
        limit["reason"] = (f"{names[stepped[0]]} is a co-simulation unit: its one-step map over held inputs "
                           f"serves k = 0 only, not k = {k}")  # fmt: skip
    else:
        probes = [0]

        def at(h: float) -> list:
            """The units at the step ``h``: the co-simulation ones identified anew (their map is that of ``h``)."""
            out = list(models)
            for i in stepped:
                probes[0] += 1
                u = identified(i, h)
                if "undecided" in u:
                    raise SceneError(f"{names[i]}: --predict: at H = {h:g} s {u['undecided']}")
                out[i] = model(u, h)
            return out

        # a continuous model's radius is cheap at any H: a dense scan, so that a narrow band of instability is
        # not stepped over; a co-simulation unit is identified anew at every scan point
        per_decade = SCAN_PER_DECADE_STEPPED if stepped else SCAN_PER_DECADE
        lim = signal_limit(at if stepped else models, cons, k, H, mine, decades=2.0 if stepped else 3.0,
                           per_decade=per_decade, implicit=implicit)  # fmt: skip
        finite = lambda h: float(h) if np.isfinite(h) else None  # noqa: E731  (none found: the scan's cap)
        limit = {"H_max": finite(lim.H_max), "H_unstable": finite(lim.H_unstable), "status": lim.status,
                 "scan_ratio": float(10.0 ** (1.0 / per_decade))}  # fmt: skip
        if stepped:
            limit["identifications"] = probes[0]  # the co-simulation units identified anew at each step tried
        if limit["H_max"] is None:
            limit["reason"] = "every step size scanned is unstable"
    for u in found.values():
        for key in "ABCD":
            if key in u:
                u[key] = np.asarray(u[key]).tolist()
    return {"scene": str(scene.path), "units": found, "H": H, "k": k, "connections": len(cons),
            "coupling": f"{'implicit' if implicit else 'explicit'}, {rows[0]['label']}, k = {k}, H = {H:g} s",
            "schemes": rows,
            "largest_stable_H": limit}  # fmt: skip

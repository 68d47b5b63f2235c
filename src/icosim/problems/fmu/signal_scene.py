"""A scene of FMU units coupled by signal connections: checked, run by the one macro step, written as a dataset.

A YAML scene (or a system file whose connections are signals, :mod:`icosim.problems.fmu.systems.scene`)::

    subsystems:
      system1: {fmu: DualMassOscillator.System1.fmu, start: {x1_start: 0.0}}
      system2: {fmu: DualMassOscillator.System2.fmu, start: {x2_start: 0.5}, record: [mass2.s]}
    connections:
      - {from: system2.F, to: system1.F}
      - {from: system1.x1, to: system2.x1, factor: 1.0, offset: 0.0}
    coupling: {k: 0, scheme: jacobi, H: 1.0e-4}
    t_end: 10

An input may be fed by a table or a constant instead (``sources``: :mod:`icosim.problems.fmu.signal_sources`).

Coupling (:mod:`icosim.problems.fmu.signals`): ``k`` the order of the inputs' extrapolation (0: held), ``scheme``
jacobi or gauss-seidel with ``order`` (every subsystem once), ``implicit`` false (explicit coupling) or true: the
connections' conditions solved at ``T_N+1`` by Newton (:mod:`icosim.engine.connection_conditions`; with
gauss-seidel the same conditions, the order Newton's start only), at most ``iterations`` (default 10) iterations until no variable changes by more than ``tol (1 + |e|)`` (``tol``
default 1e-10); then every unit must save and restore its state (Model Exchange, or Co-Simulation with
``canGetAndSetFMUstate``), checked before any unit opens.  An algebraic loop is solved at each communication point
by Newton's method without a step (:mod:`icosim.problems.fmu.loops`; its ``loop_tolerance``, default 1e-10, and
``loop_iterations``, default 20), or refused naming the loop; coupled implicitly, at ``t0`` only (the corrector
closes it at every ``T_N+1``).  ``control`` sizes the macro steps as on a scene of joints (``H`` the first step's;
:mod:`icosim.problems.fmu.controlled`, docs/signals.md).  Bad input is refused naming the key and what is allowed,
before any unit is opened.
"""

from __future__ import annotations

import time as clock
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...engine.bounds import MAX_K
from ...engine.schemes import GaussSeidel, get_scheme
from .errors import SceneError

__all__ = ["SignalScene", "SignalRun", "signal_scene", "open_signal_unit", "signal_wiring", "run_signal_scene", "signal_dataset", "is_signal_scene",
           "SIGNAL_SCENE_KEYS", "SIGNAL_SUBSYSTEM_KEYS", "CONNECTION_KEYS", "SIGNAL_COUPLING_KEYS"]  # fmt: skip

#: Top-level keys of a signal scene.
SIGNAL_SCENE_KEYS = ("subsystems", "system", "connections", "sources", "coupling", "t_start", "t_end", "limits")
#: Keys of one subsystem.
SIGNAL_SUBSYSTEM_KEYS = ("fmu", "start", "interface", "tolerance", "record")
#: Keys of one connection.
CONNECTION_KEYS = ("from", "to", "factor", "offset")
#: Coupling keys and their defaults (``H`` required).
SIGNAL_COUPLING_KEYS = {"k": 0, "scheme": "jacobi", "order": None, "H": None, "implicit": False, "inputs": "auto",
                        "substeps": 1, "iterations": None, "tol": None, "loop_tolerance": 1e-10,
                        "loop_iterations": 20, "control": None}  # fmt: skip
#: Newton's iterations and tolerance of implicit coupling by default (docs/signals.md).
IMPLICIT_DEFAULTS = {"iterations": 10, "tol": 1e-10}
_INTERFACES = ("co-simulation", "model-exchange")


def is_signal_scene(data) -> bool:
    """A scene whose units are coupled by connections."""
    return isinstance(data, dict) and "connections" in data


def _fail(path, where, message):
    raise SceneError(f"{path}: {where}: {message}")


def _number(path, where, value, *, positive=False):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
        _fail(path, where, f"must be a finite number, got {value!r}")
    if positive and value <= 0:
        _fail(path, where, f"must be > 0, got {value!r}")
    return float(value)


@dataclass
class SignalScene:
    """A checked signal scene: ``connections`` as ``(source, output, target, input, factor, offset)`` by name."""

    path: Path
    data: dict
    subsystems: dict
    connections: list
    coupling: dict
    t0: float
    t_end: float
    system: object = None
    sources: list = field(default_factory=list)  # (unit, input, TableSource)

    @property
    def names(self) -> tuple:
        return tuple(self.subsystems)

    @property
    def n_steps(self) -> int:
        return int(round((self.t_end - self.t0) / self.coupling["H"]))

    @property
    def scheme(self):
        c = self.coupling
        if c["scheme"] == "gauss-seidel":
            return GaussSeidel([self.names.index(n) + 1 for n in c["order"]])
        return get_scheme("jacobi")


def signal_scene(path, data, system=None) -> SignalScene:
    """Check a signal scene's ``data`` (from ``path``): every key, unit, variable and number, before any unit is
    opened (the variables' causalities are checked when the units open)."""
    path = Path(path)
    for key in data:
        if key not in SIGNAL_SCENE_KEYS:
            allowed = ", ".join(SIGNAL_SCENE_KEYS)
            _fail(path, key, f"not a key of a scene with connections; allowed: {allowed}")
    subs = data.get("subsystems")
    if not isinstance(subs, dict) or len(subs) < 2:
        _fail(path, "subsystems", "must map at least two subsystem names to their settings")
    for name, sub in subs.items():
        check_signal_subsystem(path, name, sub)
    specs, fed = scene_connections(path, data["connections"], subs)
    from .signal_sources import sources_of

    sources = sources_of(path, data.get("sources", []), subs, fed)
    coupling = data.get("coupling")
    if not isinstance(coupling, dict):
        _fail(path, "coupling", "must be a mapping with H (and k, scheme, order)")
    for key in coupling:
        if key not in SIGNAL_COUPLING_KEYS:
            why = " (a method couples joints; connections are coupled explicitly)" if key == "method" else ""
            _fail(path, f"coupling.{key}", f"not a key of the coupling of connections{why}; allowed: "
                  f"{', '.join(SIGNAL_COUPLING_KEYS)}")  # fmt: skip
    c = {**SIGNAL_COUPLING_KEYS, **coupling}
    _implicit_keys(path, c)
    if isinstance(c["k"], bool) or not isinstance(c["k"], int) or not 0 <= c["k"] <= MAX_K:
        _fail(path, "coupling.k", f"must be an integer 0 .. {MAX_K}, got {c['k']!r}")
    if c["scheme"] not in ("jacobi", "gauss-seidel"):
        _fail(path, "coupling.scheme", f"{c['scheme']!r} is not allowed; allowed: jacobi, gauss-seidel (with order)")
    if c["scheme"] == "gauss-seidel":
        if not isinstance(c["order"], list) or sorted(map(str, c["order"])) != sorted(subs):
            _fail(path, "coupling.order", f"gauss-seidel needs every subsystem once, e.g. {list(subs)}; got "
                  f"{c['order']!r}")  # fmt: skip
    elif c["order"] is not None:
        _fail(path, "coupling.order", "an order belongs to scheme gauss-seidel")
    if c["inputs"] not in ("auto", "derivatives", "substeps"):
        _fail(path, "coupling.inputs", f"{c['inputs']!r} is not allowed; allowed: auto, derivatives, substeps")
    if isinstance(c["substeps"], bool) or not isinstance(c["substeps"], int) or c["substeps"] < 1:
        _fail(path, "coupling.substeps", f"must be an integer >= 1, got {c['substeps']!r}")
    from .loops import check_loop_keys

    check_loop_keys(lambda where, message: _fail(path, where, message), c)
    if c["H"] is None:
        _fail(path, "coupling.H", "required: the macro-step size (s)")
    c["H"] = _number(path, "coupling.H", c["H"], positive=True)
    t0 = _number(path, "t_start", data.get("t_start", 0.0))
    if "t_end" not in data:
        _fail(path, "t_end", "required: the end time (s)")
    t_end = _number(path, "t_end", data["t_end"])
    from .controlled import check_signal_control

    check_signal_control(path, c)  # controlled: H is the first step's size
    steps = (t_end - t0) / c["H"]
    if c["control"] is None and (not steps >= 1 or abs(steps - round(steps)) > 1e-6 * max(1.0, steps)):
        _fail(path, "t_end", f"t_end - t_start = {t_end - t0:g} s must be a whole number (>= 1) of macro steps "
              f"H = {c['H']:g} s")  # fmt: skip
    used = {u for s in specs for u in (s[0], s[2])} | {s[0] for s in sources}
    alone = [n for n in subs if n not in used]
    if alone:
        _fail(path, f"subsystems.{alone[0]}", "takes part in no connection")
    return SignalScene(path, data, dict(subs), specs, c, t0, t_end, system, sources)


def check_signal_subsystem(path, name, sub) -> None:
    """Subsystem ``name``'s settings ``sub`` as a unit coupled by connections only: its keys, interface and record."""
    if not isinstance(sub, dict) or "fmu" not in sub:
        _fail(path, f"subsystems.{name}", "must be a mapping with fmu (the unit's .fmu file)")
    for key in sub:
        if key not in SIGNAL_SUBSYSTEM_KEYS:
            _fail(path, f"subsystems.{name}.{key}", f"not a key of a subsystem coupled by connections; allowed: "
                  f"{', '.join(SIGNAL_SUBSYSTEM_KEYS)}")  # fmt: skip
    if sub.get("interface", "co-simulation") not in _INTERFACES + ("auto",):
        _fail(path, f"subsystems.{name}.interface", f"{sub['interface']!r} is not allowed; allowed: "
              f"{', '.join(_INTERFACES)}, auto")  # fmt: skip
    if not isinstance(sub.get("record", []), list) or not all(isinstance(r, str) for r in sub.get("record", [])):
        _fail(path, f"subsystems.{name}.record", "must be a list of variable names")


def scene_connections(path, cons, subs) -> tuple[list, dict]:
    """A scene's ``connections`` checked against its subsystems ``subs`` (names): ``(source, output, target, input,
    factor, offset)`` by name, and the inputs fed, ``(unit, input) -> connection``."""
    if not isinstance(cons, list) or not cons:
        _fail(path, "connections", "must be a non-empty list of {from: unit.output, to: unit.input}")
    specs, fed = [], {}
    for n, con in enumerate(cons):
        where = f"connections[{n}]"
        if not isinstance(con, dict) or not {"from", "to"} <= set(con):
            _fail(path, where, "must be a mapping with from (unit.output) and to (unit.input)")
        for key in con:
            if key not in CONNECTION_KEYS:
                _fail(path, f"{where}.{key}", f"not a key of a connection; allowed: {', '.join(CONNECTION_KEYS)}")
        ends = []
        for key in ("from", "to"):
            ref = con[key]
            unit, _, var = ref.partition(".") if isinstance(ref, str) else ("", "", "")
            if unit not in subs or not var:
                _fail(path, f"{where}.{key}", f"{ref!r} must be <subsystem>.<variable> with a subsystem of "
                      f"{', '.join(subs)}")  # fmt: skip
            ends.append((unit, var))
        if ends[0][0] == ends[1][0]:
            _fail(path, where, f"connects {ends[0][0]} to itself: a connection joins two subsystems")
        if ends[1] in fed:
            _fail(path, f"{where}.to", f"{'.'.join(ends[1])} is fed already by connections[{fed[ends[1]]}]; an input "
                  "takes one connection")  # fmt: skip
        fed[ends[1]] = n
        factor = _number(path, f"{where}.factor", con.get("factor", 1.0))
        offset = _number(path, f"{where}.offset", con.get("offset", 0.0))
        specs.append((ends[0][0], ends[0][1], ends[1][0], ends[1][1], factor, offset))
    return specs, fed


def _implicit_keys(path, c):
    """``implicit`` (true or false) and Newton's ``iterations`` (an integer >= 1) and ``tol`` (> 0: a variable's change
    at most ``tol (1 + |e|)``), which belong to implicit coupling; their defaults filled in."""
    if not isinstance(c["implicit"], bool):
        _fail(path, "coupling.implicit", f"must be true or false, got {c['implicit']!r}")
    for key in IMPLICIT_DEFAULTS:
        if c[key] is not None and not c["implicit"]:
            _fail(path, f"coupling.{key}", "Newton's iterations and tolerance belong to implicit: true")
    n = c["iterations"]
    if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < 1):
        _fail(path, "coupling.iterations", f"must be an integer >= 1 (Newton's iterations at most), got {n!r}")
    if c["tol"] is not None:
        c["tol"] = _number(path, "coupling.tol", c["tol"], positive=True)
    if c["implicit"]:
        c.update({key: value if c[key] is None else c[key] for key, value in IMPLICIT_DEFAULTS.items()})


@dataclass
class SignalRun:
    """A signal scene's run: the times, each unit's connected variables and recorded ones over them, its status."""

    scene: SignalScene
    times: list = field(default_factory=list)
    series: dict = field(default_factory=dict)  # "<unit>.<variable>" -> values over times
    units: dict = field(default_factory=dict)
    status: str = "completed"
    reason: str = ""
    wall_time: float = 0.0
    iterations: list = field(default_factory=list)  # implicit: Newton's iterations of each macro step
    jacobian_steps: int = 0  # implicit: the units' perturbed steps of the Jacobians
    loop: dict = field(default_factory=dict)  # the algebraic loop's solve (LoopSolver.info), empty without one
    steps: object = None  # a controlled run's accepted steps (icosim.engine.control.driver.AdaptiveSteps)


def _fmu_path(scene, sub) -> Path:
    p = Path(sub["fmu"])
    return p if p.is_absolute() else (scene.path.parent / p).resolve()


def open_signal_unit(scene: SignalScene, name, inputs, outputs, path=None):
    """Unit ``name`` opened with its connected ``inputs`` and ``outputs`` (variable names); co-simulation coupled
    explicitly is stepped forward only (no saved state), its orders of input derivatives checked before any step.
    ``path``: its ``.fmu`` (default: the scene's ``fmu``)."""
    from .exchange import open_fmu_unit
    from .input_orders import check_input_orders
    from .signals import INPUTS, OUTPUTS, ForwardUnit

    c, sub = scene.coupling, scene.subsystems[name]
    keys = {k: v for k, v in ((INPUTS, inputs), (OUTPUTS, outputs)) if v}
    start, path = dict(sub.get("start") or {}), path or _fmu_path(scene, sub)
    interface = sub.get("interface", "co-simulation")
    if interface == "co-simulation" and not c["implicit"] and c["control"] is None:  # no saved state
        unit = ForwardUnit(name, path, keys, start, inputs=c["inputs"], substeps=c["substeps"], t0=scene.t0)
        return check_input_orders(scene.path, unit, c["k"])
    unit = open_fmu_unit(name, path, keys, start, interface=interface, tolerance=sub.get("tolerance"),
                         inputs=c["inputs"], substeps=c["substeps"], t0=scene.t0)  # fmt: skip
    return check_input_orders(scene.path, unit, c["k"]) if interface == "co-simulation" else unit


def signal_wiring(scene: SignalScene):
    """The connections (:class:`~icosim.engine.graph.Connection` s), each unit's inputs (connected, then those a
    source feeds) and outputs by name, and each unit's sources; the sources' targets checked, and with implicit
    coupling that every unit saves its state."""
    from .signal_sources import check_targets
    from .signals import connections_of

    names = list(scene.names)
    check_targets(scene.path, scene.sources, {n: _fmu_path(scene, scene.subsystems[n]) for n in names})
    cons, inputs, outputs = connections_of(scene.connections, names)
    fed: list = [[] for _ in names]  # each unit's inputs fed by a source, after its connected ones
    for unit, var, source in scene.sources:
        inputs[names.index(unit)].append(var)
        fed[names.index(unit)].append(source)
    if scene.coupling["implicit"] or scene.coupling["control"] is not None:  # before any unit opens
        for name in names:
            _check_saves_state(scene, name, scene.subsystems[name], _fmu_path(scene, scene.subsystems[name]))
    return cons, inputs, outputs, fed


def run_signal_scene(scene: SignalScene, *, progress=None, history=None) -> SignalRun:
    """Open the units, run the macro steps (explicit or implicit coupling; an algebraic loop solved, or refused),
    close the units; ``progress(n_done)`` is called after each step.  ``history``: the connections' values at ``T_0, T_-1, ...
    T_-k`` (``(k + 1, connections)``, in the scene's order of the connections), else those at ``t_start`` at
    every point (a start from rest in the past)."""
    from ...engine.connection_conditions import NotConverged
    from ...engine.run import simulate
    from .controlled import controlled_steps, held_history
    from .signals import SignalCosimulation

    names, c = list(scene.names), scene.coupling
    want = (c["k"] + 1, len(scene.connections))
    if history is not None and np.shape(history) != want:
        raise SceneError(f"{scene.path}: the coupling history must be {want} (k + 1 points, one value per connection), "
                         f"got {np.shape(history)}")  # fmt: skip
    cons, inputs, outputs, fed = signal_wiring(scene)
    units = []
    run = SignalRun(scene)
    started = clock.perf_counter()
    try:
        for i, name in enumerate(names):
            units.append(open_signal_unit(scene, name, inputs[i], outputs[i]))
        problem = SignalCosimulation(units, inputs, outputs, cons, c["k"], c["H"], t0=scene.t0, sources=fed,
                                     implicit=c["implicit"], loop_tolerance=c["loop_tolerance"],
                                     loop_iterations=c["loop_iterations"])  # fmt: skip
        history = problem.initial_history(None if history is None else _history_rows(scene, problem, history))
        recorded = [
            (u, v) for u, sub in zip(units, (scene.subsystems[n] for n in names)) for v in sub.get("record", [])
        ]

        def observe(n, state, hist, y):
            run.times.append(problem.time)
            _append(run, problem, hist[0], recorded)
            if progress is not None:
                progress(n)

        run.times.append(scene.t0)
        _append(run, problem, history[0], recorded)
        newton = {"iterations": c["iterations"], "tol": c["tol"]} if c["implicit"] else {}
        if c["control"] is None:
            traj = simulate(problem, None, problem.initial_state(), history, scene.n_steps, scheme=scene.scheme,
                            observe=observe, record=False, **newton)  # fmt: skip
        else:  # the joint scenes' controlled run (icosim.problems.fmu.controlled)
            traj, _, run.steps = controlled_steps(scene, problem, problem.initial_state(), history, np.inf, observe,
                                                  restart=held_history(history), iterations=c["iterations"] or 1,
                                                  corrector_tol=c["tol"])  # fmt: skip
        run.iterations, run.jacobian_steps = problem.implicit_work.iterations, problem.implicit_work.perturbed_steps
        if traj.failed_at is not None and traj.error is not None:
            if isinstance(traj.error, NotConverged):  # where: the step and its time
                raise NotConverged(f"{scene.path}: macro step {traj.failed_at} (from t = {problem.time:.12g} s): "
                                   f"{traj.error}") from None  # fmt: skip
            raise traj.error  # a unit that refused a step: named, no dataset
        if traj.diverged_at is not None:
            run.status, run.reason = "diverged", f"macro step {traj.diverged_at}: {traj.reason}"
        run.units = {u.label: u.info() for u in units}
        run.loop = problem.loops.info() if problem.loops is not None else {}
    finally:
        for unit in units:
            unit.close()
    run.wall_time = clock.perf_counter() - started
    return run


def _check_saves_state(scene, name, sub, path):
    """Implicit coupling steps each unit again from ``T_N``, a controlled run retries a rejected step from there: a
    co-simulation unit must save and restore its state."""
    from .description import read_description

    interface = sub.get("interface", "co-simulation")
    md, _ = read_description(name, path)
    if interface == "model-exchange" or (interface == "auto" and md.modelExchange is not None):
        return
    if md.coSimulation is not None and md.coSimulation.canGetAndSetFMUstate:
        return
    flag = "canGetAndSetFMUState" if md.fmiVersion.startswith("3.") else "canGetAndSetFMUstate"
    fix = "interface: model-exchange (the unit has it), or" if md.modelExchange is not None else ""
    why, off = (("coupling.implicit: true steps each unit again from T_N", "implicit: false") if scene.coupling["implicit"]
                else ("coupling.control retries a rejected step from T_N", "fixed steps (no control)"))  # fmt: skip
    _fail(scene.path, f"subsystems.{name}", f"{path.name} declares {flag}=false, and {why}, restoring its state; use "
          f"{fix} {off}")  # fmt: skip


def _history_rows(scene, problem, history) -> np.ndarray:
    """``history`` (connections in the scene's order) as rows of the problem's coupling variables."""
    history = np.asarray(history, dtype=float)
    rows = np.zeros((history.shape[0], problem.n_coupling))
    for c in range(history.shape[1]):
        rows[:, problem.graph.connection_column(c)] = history[:, c]
    return rows


def _append(run, problem, e, recorded):
    """The connected variables at the point the problem stands (an input: the value its connection gives there,
    the sample it is held at over the next step with k 0) and the recorded ones."""
    graph = problem.graph
    for c, con in enumerate(graph.connections):
        src = f"{graph.names[con.source]}.{problem.output_names[con.source][con.output]}"
        dst = f"{graph.names[con.target]}.{problem.input_names[con.target][con.input]}"
        value = float(e[graph.connection_column(c)])
        raw = (value - con.offset) / con.factor if con.factor else np.nan
        run.series.setdefault(dst, []).append(value)
        if len(run.series.setdefault(src, [])) < len(run.series[dst]):
            run.series[src].append(raw if con.factor else float(problem.outputs(con.source)[con.output]))
    for i, sources in enumerate(problem.sources):  # the inputs fed by a table: its value just after the point
        for name, source in zip(problem.input_names[i][len(problem.input_names[i]) - len(sources) :], sources):
            run.series.setdefault(f"{graph.names[i]}.{name}", []).append(source.after(problem.time))
    for unit, name in recorded:
        run.series.setdefault(f"{unit.label}.{name}", []).append(unit.get_named(name))


def signal_dataset(run: SignalRun, *, command: str = ""):
    """The run as an :class:`xarray.Dataset`: ``<unit>.<variable>(time)`` for every connected and recorded
    variable, the scene and the units' counters as attributes."""
    from ...io.dataset import DatasetDict
    from ...io.netcdf import provenance_attrs
    from .controlled import controlled_entries

    data = {key: (("time",), np.asarray(values, dtype=float)) for key, values in run.series.items()}
    entries, controlled = controlled_entries(run)
    data |= entries
    ds = DatasetDict(data, coords={"time": ("time", np.asarray(run.times), {"units": "s"})})
    attrs = provenance_attrs(run.scene.data, title=f"FMU scene {run.scene.path.name}", command=command)
    attrs["scene_json"] = attrs["config_json"]
    c = run.scene.coupling
    attrs |= {"status": run.status, "reason": run.reason, "scheme": run.scene.scheme.name, "k": c["k"],
              "coupling": "implicit" if c["implicit"] else "explicit", "wall_time_s": run.wall_time}  # fmt: skip
    if c["implicit"]:
        its = np.asarray(run.iterations, dtype=float)
        attrs |= {
            "newton_tol": c["tol"],
            "newton_max_iterations": c["iterations"],
            "jacobian_steps": run.jacobian_steps,
            "iterations_max": int(its.max(initial=0)),
            "iterations_mean": float(its.mean()) if its.size else 0.0,
        }
    attrs |= run.loop | controlled
    for name, info in run.units.items():
        for key, value in info.items():
            attrs[f"{name}_{key}"] = value
    ds.attrs.update(attrs)
    return ds.to_xarray()

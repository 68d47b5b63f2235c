"""A scene of FMU units joined by joints beside units coupled by signal connections: checked, run by the one macro
step, written as one dataset.

::

    subsystems:
      body1: {fmu: ../../fmus/msd, start: {m: 1.0, c: 1000.0, d: 2.0, x0: 0.1},
              position: x, velocity: v, acceleration: a, force: lambda, force_sign: 1, mass: m, ...}
      body2: {fmu: ../../fmus/msd, start: {...}, position: x, ..., force_sign: 1}
      sensor: {fmu: ../../fmus/msd, start: {...}}
    joints:
      - {between: [body1, body2], decomposition: ff}
    connections:
      - {from: body1.x, to: sensor.lambda, factor: 200.0}
    coupling: {method: projection, k: 1, scheme: jacobi, H: 1.0e-3}
    t_end: 0.5

A unit in a joint has the keys of a scene of joints (:mod:`icosim.problems.fmu.scene`) and may give and take
connections' values through variables other than its joint's; a unit in no joint has those of a scene of connections
(:data:`~icosim.problems.fmu.signal_scene.SIGNAL_SUBSYSTEM_KEYS`) and takes part in a connection.  ``coupling``: the
keys of a scene of joints (the method closes the joints' conditions), ``scheme`` ``gauss-seidel`` with an ``order``
naming every unit (or ``gauss-seidel-<numbers>`` of every unit in file order), and ``implicit`` (default false: the
connections coupled explicitly, their inputs held or extrapolated with the joints' ``k``, :mod:`icosim.engine.macrostep`).
The part of the scene that the joints make is checked as a scene of joints (:attr:`JointSignalScene.joints`).
docs/signals.md, "Joints beside connections", has the details.
"""

from __future__ import annotations

import time as clock
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...engine.schemes import GaussSeidel, Scheme, get_scheme
from ...errors import ParameterError
from .errors import SceneError
from .joints import ORDERED_SCHEMES
from .scene import COUPLING_KEYS, SCENE_KEYS, SUBSYSTEM_KEYS, Scene, joint_scene
from .signal_scene import IMPLICIT_DEFAULTS, check_signal_subsystem, scene_connections

__all__ = ["JointSignalScene", "JointSignalRun", "joint_signal_scene", "run_joint_signal_scene",
           "joint_signal_dataset"]  # fmt: skip

#: Coupling keys of the connections beside the joints' (:data:`~icosim.problems.fmu.scene.COUPLING_KEYS`).
SIGNAL_KEYS = {"implicit": False, "tol": None}
#: A joint unit's keys that name its joint's variables (a connection may not feed or read them instead).
_JOINT_VARIABLES = ("force", "acceleration_input", "position_input", "velocity_input", "set_position", "set_velocity")


def _fail(path, where, message):
    raise SceneError(f"{path}: {where}: {message}")


@dataclass
class JointSignalScene:
    """A checked scene of joints and connections: ``joints`` the scene of the joint units alone (their
    :class:`~icosim.problems.fmu.scene.Scene`), ``connections`` as ``(source, output, target, input, factor, offset)``
    by name, ``coupling`` every coupling key with its default, ``scheme`` over every unit."""

    path: Path
    data: dict
    joints: Scene
    subsystems: dict
    connections: list
    coupling: dict
    scheme: Scheme
    t0: float
    t_end: float
    system: object = None

    @property
    def names(self) -> tuple:
        return tuple(self.subsystems)

    @property
    def n_steps(self) -> int:
        return self.joints.n_steps

    @property
    def method(self):
        return self.joints.method

    @property
    def signal_units(self) -> tuple:
        """The units in no joint."""
        return tuple(n for n in self.names if n not in self.joints.names)


def joint_signal_scene(path, data, system=None) -> JointSignalScene:
    """Check a scene of joints and connections (module docstring) before any unit is opened."""
    path = Path(path)
    allowed = (*SCENE_KEYS, "connections")
    for key in data:
        if key not in allowed:
            _fail(path, key, f"not a key of a scene of joints and connections; allowed: {', '.join(allowed)}")
    subs, joints = data.get("subsystems"), data.get("joints")
    if not isinstance(subs, dict) or len(subs) < 2:
        _fail(path, "subsystems", "must map at least two subsystem names to their settings")
    joined = (
        {n for j in joints if isinstance(j, dict) for n in j.get("between") or ()}
        if isinstance(joints, list)
        else set()
    )
    for name, sub in subs.items():
        if name not in joined:
            check_signal_subsystem(path, name, sub)
    coupling = data.get("coupling")
    if not isinstance(coupling, dict):
        _fail(path, "coupling", "must be a mapping with method, k and H")
    c = {**COUPLING_KEYS, **SIGNAL_KEYS, **coupling}
    if not isinstance(c["implicit"], bool):
        _fail(path, "coupling.implicit", f"must be true or false, got {c['implicit']!r}")
    if c["tol"] is not None and not c["implicit"]:
        _fail(path, "coupling.tol", "Newton's tolerance belongs to implicit: true")
    if c["implicit"]:  # Newton's iterations (at most) and tolerance
        c["iterations"] = coupling.get("iterations", IMPLICIT_DEFAULTS["iterations"])
        if c["tol"] is None:
            c["tol"] = IMPLICIT_DEFAULTS["tol"]
        elif isinstance(c["tol"], bool) or not isinstance(c["tol"], (int, float)) or not c["tol"] > 0:
            _fail(path, "coupling.tol", f"must be a number > 0, got {c['tol']!r}")
    if c["control"] is not None:
        _fail(path, "coupling.control", "controlled macro steps are for a scene of joints alone; beside connections "
              "the macro step is fixed (remove control)")  # fmt: skip
    names = list(subs)
    scheme, joint_scheme = _scheme(path, c, names, [n for n in names if n in joined])
    joint_data = {k: v for k, v in data.items() if k != "connections"}
    joint_data["subsystems"] = {n: s for n, s in subs.items() if n in joined}
    joint_data["coupling"] = {k: v for k, v in coupling.items() if k not in (*SIGNAL_KEYS, "scheme", "order")}
    joint_data["coupling"] |= joint_scheme
    scene = joint_scene(path, joint_data, system)
    specs, fed = scene_connections(path, data["connections"], subs)
    for n, (source, output, target, input_, _, _) in enumerate(specs):
        for who, var, end in ((source, output, "from"), (target, input_, "to")):
            sub = subs[who]
            taken = [k for k in (*_JOINT_VARIABLES, "position", "velocity", "acceleration", "reaction_force")
                     if who in joined and sub.get(k) == var]  # fmt: skip
            if end == "to" and taken:
                _fail(path, f"connections[{n}].to", f"{who}.{var} is {who}'s {taken[0]} ({SUBSYSTEM_KEYS[taken[0]]}): "
                      "its joint sets it; a connection feeds another input")  # fmt: skip
            if end == "to" and who in joined and ("position_input" in sub or "velocity_input" in sub):
                _fail(path, f"connections[{n}].to", f"{who} is a drive (its point's motion prescribed), which takes no "
                      "connection's input")  # fmt: skip
    used = {u for s in specs for u in (s[0], s[2])}
    alone = [n for n in names if n not in joined and n not in used]
    if alone:
        _fail(path, f"subsystems.{alone[0]}", "takes part in no joint or connection")
    t0 = float(data.get("t_start", 0.0))
    return JointSignalScene(path, data, scene, dict(subs), specs, c, scheme, t0, float(data["t_end"]), system)


def _scheme(path, c, names, joined) -> tuple[Scheme, dict]:
    """The scheme over every unit and the joint units' part of it (their order kept) for the scene of joints."""
    given = c["scheme"]
    if given in ORDERED_SCHEMES:
        order = c["order"]
        if not isinstance(order, list) or sorted(map(str, order)) != sorted(names):
            _fail(path, "coupling.order", f"{given} needs every subsystem once, those in joints and those in "
                  f"connections only, e.g. {names}; got {order!r}")  # fmt: skip
        leading = "as-integrated" if given.endswith("-as-integrated") else "reevaluated"
        scheme: Scheme = GaussSeidel([names.index(n) + 1 for n in order], leading)
    else:
        if c["order"] is not None:
            _fail(path, "coupling.order", f"only with scheme {' or '.join(ORDERED_SCHEMES)}")
        try:
            scheme = get_scheme(given)
        except ParameterError as exc:
            _fail(path, "coupling.scheme", f"{exc}; or gauss-seidel with order: {names}")
    numbers = getattr(scheme, "order", None)
    if numbers is None:
        return scheme, {"scheme": given}
    if len(numbers) != len(names):
        _fail(path, "coupling.scheme", f"{given} orders {len(numbers)} subsystems, the scene has {len(names)} "
              f"({', '.join(names)}, numbered in file order); or gauss-seidel with order: {names}")  # fmt: skip
    name = ORDERED_SCHEMES[1] if getattr(scheme, "leading_outputs", "") == "as-integrated" else ORDERED_SCHEMES[0]
    return scheme, {"scheme": name, "order": [names[i - 1] for i in numbers if names[i - 1] in joined]}


@dataclass
class JointSignalRun:
    """A run of joints and connections: the joint units' run as a scene of joints gives it (``joints``, a
    :class:`~icosim.problems.fmu.run.SceneRun`) and the connected and recorded variables as a scene of connections
    gives them (``signals``, a :class:`~icosim.problems.fmu.signal_scene.SignalRun`)."""

    scene: JointSignalScene
    joints: object
    signals: object
    status: str = "completed"
    reason: str = ""
    wall_time: float = 0.0
    units: dict = field(default_factory=dict)


def run_joint_signal_scene(scene: JointSignalScene, *, cache=None, progress=None) -> JointSignalRun:
    """Open the units (the joint units checked as in a scene of joints), run the macro steps, close the units;
    ``progress(n_done)`` after each step.  A unit's refused step raises; a divergence ends the run, said."""
    from ...engine.connection_conditions import NotConverged
    from ...engine.graph import Joint
    from ...engine.run import simulate
    from .joint_signals import JointSignalCosimulation
    from .run import SceneRun, consistent_start, divergence_bound, fmu_file, open_units
    from .signal_scene import SignalRun, _append, _check_saves_state, open_signal_unit
    from .signals import INPUTS, OUTPUTS, connections_of

    names, c, js = list(scene.names), scene.coupling, scene.joints
    cons, inputs, outputs = connections_of(scene.connections, names)
    keys = lambda i: {k: v for k, v in ((INPUTS, inputs[i]), (OUTPUTS, outputs[i])) if v}  # noqa: E731
    started = clock.perf_counter()
    paths = {n: fmu_file((scene.path.parent / scene.subsystems[n]["fmu"]).resolve(), cache) for n in scene.signal_units}
    for name, path in paths.items():  # coupled implicitly, stepped again from T_N: it must save its state
        if c["implicit"]:
            _check_saves_state(scene, name, scene.subsystems[name], path)
    opened, problem = {}, None
    try:
        units, couplings = open_units(js, cache=cache, signals={n: keys(names.index(n)) for n in js.names})
        opened |= dict(zip(js.names, units))
        for name, path in paths.items():
            i = names.index(name)
            opened[name] = open_signal_unit(scene, name, inputs[i], outputs[i], path)
        joints = [Joint(names.index(js.names[jt.first]), names.index(js.names[jt.second]), jt.decomposition)
                  for jt in js.graph().joints]  # fmt: skip
        try:
            problem = JointSignalCosimulation([opened[n] for n in names], couplings, joints, js.n_dim, inputs,
                                              outputs, cons, c["k"], c["H"], t0=scene.t0, implicit=c["implicit"],
                                              perturbation=c["perturbation"], sensitivities=c["sensitivities"],
                                              iterations=c["iterations"])  # fmt: skip
        except ParameterError as exc:
            raise SceneError(f"{scene.path}: connections: {exc}") from None
        start = consistent_start(js, problem.joints)
        state, history = problem.begin(start.state, start.history)
        signals = SignalRun(scene)  # type: ignore[arg-type]
        recorded = [(opened[n], v) for n in names for v in scene.subsystems[n].get("record", [])]
        nj = problem.joints.n_coupling

        def observe(n, state, hist, y):
            signals.times.append(problem.time)
            _append(signals, problem, hist[0], recorded)
            if progress is not None:
                progress(n)

        iterations = problem.implicit_work.iterations
        signals.times.append(scene.t0)
        _append(signals, problem, history[0], recorded)
        with np.errstate(over="ignore", invalid="ignore"):  # a diverging run is reported, not warned about
            traj = simulate(problem, scene.method, state, history, scene.n_steps, scheme=scene.scheme,
                            iterations=c["iterations"], bound=divergence_bound(js, start.state), observe=observe,
                            **({"tol": c["tol"]} if c["implicit"] else {}))  # fmt: skip
        if traj.failed_at is not None:
            if isinstance(traj.error, NotConverged):  # where: the step and its time
                raise NotConverged(f"{scene.path}: macro step {traj.failed_at} (from t = {problem.time:.12g} s): "
                                   f"{traj.error}") from None  # fmt: skip
            raise traj.error
        run = JointSignalRun(scene, None, signals)
        signals.iterations, signals.jacobian_steps = iterations, problem.implicit_work.perturbed_steps
        if traj.diverged_at is not None:
            run.status = "diverged"
            t_div = scene.t0 + traj.diverged_at * float(c["H"])
            run.reason = f"diverged at macro step {traj.diverged_at} (t = {t_div:.12g} s): {traj.reason}"
        size = problem.joints.n_dim * 2 * len(problem.joint_units)
        states = np.array([np.asarray(s)[:size].reshape(len(problem.joint_units), -1) for s in traj.states])
        nan_y = np.full((len(problem.joint_units), 4, problem.joints.n_dim), np.nan)
        outputs_ = np.array([nan_y if y is None else y for y in traj.outputs])
        run.units = {n: u.info() for n, u in opened.items()}
        for n, cp in zip(js.names, couplings):
            run.units[n]["feedthrough"] = "yes" if cp.feedthrough else "through a step only"
        times = scene.t0 + float(c["H"]) * np.arange(len(traj.states))
        run.joints = SceneRun(js, times, states, np.array(traj.coupling)[:, :nj], outputs_, run.units, run.status,
                              run.reason, 0.0, start, traj.diverged_at)  # fmt: skip
    finally:
        if problem is not None:
            problem.close()
        for unit in opened.values():
            unit.close()
    run.wall_time = run.joints.wall_time = clock.perf_counter() - started
    return run


def joint_signal_dataset(run: JointSignalRun, *, command: str = ""):
    """The run as an :class:`xarray.Dataset`: the joint units' variables as a scene of joints writes them
    (:func:`~icosim.problems.fmu.run.run_dataset_data`) and ``<unit>.<variable>(time)`` of every connected and recorded
    variable as a scene of connections writes them; the whole scene as provenance."""
    from ...io.dataset import DatasetDict
    from ...io.netcdf import provenance_attrs
    from .run import run_dataset_data

    ds = run_dataset_data(run.joints, command=command)
    series = DatasetDict({key: (("time",), np.asarray(v, dtype=float)) for key, v in run.signals.series.items()},
                         coords={"time": ("time", np.asarray(run.signals.times), {"units": "s"})})  # fmt: skip
    if series["dims"]["time"] != ds["dims"]["time"]:
        raise ValueError("the joints' and the connections' records have different times")
    ds["data_vars"].update(series["data_vars"])
    attrs = provenance_attrs(run.scene.data, title=f"FMU scene {run.scene.path.name}", command=command)
    ds.attrs.update(attrs | {"scene_json": attrs["config_json"], "scheme": run.scene.scheme.name,
                             "coupling": "implicit" if run.scene.coupling["implicit"] else "explicit",
                             "connections": len(run.scene.connections), "status": run.status,
                             "reason": run.reason})  # fmt: skip
    if run.scene.coupling["implicit"]:  # Newton's work, as a scene of connections says it
        its = np.asarray(run.signals.iterations, dtype=float)
        ds.attrs.update({"newton_tol": run.scene.coupling["tol"], "newton_max_iterations": run.scene.coupling["iterations"],
                         "jacobian_steps": run.signals.jacobian_steps, "iterations_max": int(its.max(initial=0)),
                         "iterations_mean": float(its.mean()) if its.size else 0.0})  # fmt: skip
    return ds.to_xarray()

"""A scene of joints beside connections (:mod:`icosim.problems.fmu.joint_signal_scene`) run by the one macro step
(:class:`~icosim.problems.fmu.joint_signals.JointSignalCosimulation`), and its dataset: the joint units' variables
as a scene of joints writes them, the connected and recorded ones as a scene of connections does."""

from __future__ import annotations

import time as clock
from dataclasses import dataclass, field

import numpy as np

from ...errors import ParameterError
from .errors import SceneError
from .joint_signal_scene import JointSignalScene

__all__ = ["JointSignalRun", "run_joint_signal_scene", "joint_signal_dataset"]


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

"""A scene run: its units opened, the macro steps of :func:`icosim.engine.macrostep.macro_step`, the dataset."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .build import build_unit, is_source_dir
from .controlled import controlled_entries, scene_steps
from .errors import FmuError
from .exchange import open_fmu_unit
from .initial import given_coupling_warning
from .input_orders import check_input_orders
from .inspection import inspect_unit, joint_direction, refuse, rollback_tolerance
from .joints import check_scheme
from .problem import Coupling, FmuCosimulation
from .record import Recorder, Recording, recorded_entries
from .scene import Scene, load_scene
from .units import ROLES, Unit

__all__ = ["run_scene", "open_units", "open_unit", "consistent_start", "SceneRun", "Start"]


@dataclass
class SceneRun:
    """What a run produced: times, states, coupling variables and outputs at ``T_0 ... T_n``; the units' info."""

    scene: Scene
    times: np.ndarray
    states: np.ndarray  # (n+1, N, 2 n_dim): positions, then velocities, per unit
    coupling: np.ndarray  # (n+1, n_e)
    outputs: np.ndarray  # (n+1, N, 4, n_dim); row 0 NaN (no step has produced it)
    units: dict = field(default_factory=dict)  # name -> Unit.info()
    status: str = "completed"
    reason: str = ""
    wall_time: float = 0.0
    start: object = None  # the run's Start (consistent_start)
    diverged_at: int | None = None
    recorded: dict = field(default_factory=dict)  # subsystem -> (names, units, values (n+1, names)): record
    steps: object = None  # a controlled run's macro steps (AdaptiveSteps; coupling.control), else None

    @property
    def n_dim(self) -> int:
        """Components of a joint point's position (1 on a line, 2 in the plane)."""
        return self.outputs.shape[-1]

    @property
    def positions(self) -> np.ndarray:
        """``(n+1, N, n_dim)``."""
        return self.states[..., : self.n_dim]

    @property
    def velocities(self) -> np.ndarray:
        """``(n+1, N, n_dim)``."""
        return self.states[..., self.n_dim :]

    def joint_gaps(self) -> np.ndarray:
        """Per joint, the position of its first unit minus its second's, ``(n+1, M, n_dim)``."""
        graph = self.scene.graph(self.n_dim)
        first = [jt.first for jt in graph.joints]
        second = [jt.second for jt in graph.joints]
        return self.positions[:, first] - self.positions[:, second]

    def joint_forces(self) -> np.ndarray:
        """Per joint, the force it exerts on its first unit (on the second the opposite), ``(n+1, M, n_dim)``:
        the joint's multiplier ``lambda_j`` where its first side is force driven (corrected, the run's coupling
        variables), else the force the first unit's drive exerts (its output at the end of each macro step; NaN
        at the start)."""
        graph = self.scene.graph(self.n_dim)
        out = np.empty((len(self.times), graph.n_joints, self.n_dim))
        for j, jt in enumerate(graph.joints):
            d = jt.decomposition
            if d.kinds[0] == "force":
                v = next(v for v in range(d.n_coupling) if d.variable_kind(v) == "force")
                first = graph.columns(j)[v * self.n_dim]
                out[:, j] = self.coupling[:, first : first + self.n_dim]
            else:
                out[:, j] = self.outputs[:, jt.first, 3, :]
        return out


def fmu_file(path, cache=None):
    """The ``.fmu`` of a scene's ``fmu`` entry: the file itself, or the unit built from a source directory."""
    return build_unit(path, cache) if is_source_dir(path) else path


def _needed(kind, projects):
    keys = {"position", "velocity", "acceleration"}
    keys |= (
        {"force"} if kind == "force" else {"acceleration_input", "reaction_force", "position_input", "velocity_input"}
    )
    return keys | ({"set_position", "set_velocity"} if projects else set())


def open_unit(scene: Scene, name: str, kind: str, *, cache=None, signals=None) -> Unit:
    """The scene's unit ``name`` (driven as ``kind``), opened with its start values at ``t_start``; ``signals``: the
    variables of its connections by unit key (``signal_input``, ``signal_output``), beside its joint's."""
    c, sub = scene.coupling, scene.data["subsystems"][name]
    projects = scene.method.projection or scene.data.get("initial") == "project"
    names = {k: sub[k] for k in ROLES if k in sub and k in _needed(kind, projects)} | dict(signals or {})
    unit = open_fmu_unit(name, fmu_file(scene.fmus[name], cache), names, sub.get("start", {}),
                         interface=sub.get("interface", "auto"), tolerance=sub.get("tolerance"), inputs=c["inputs"],
                         substeps=c["substeps"], t0=float(scene.data.get("t_start", 0.0)))  # fmt: skip
    return check_input_orders(scene.path, unit, c["k"])  # the orders of input derivatives it takes, before any step


def open_units(scene: Scene, *, cache=None, inspect=True, signals=None):
    """The scene's units, opened with their start values at ``t_start``, checked
    (:func:`icosim.problems.fmu.inspection.inspect_unit` per unit, :func:`~icosim.problems.fmu.inspection.joint_direction`
    for the joints, :func:`check_scheme`; a refusal raises :class:`~icosim.problems.fmu.errors.FmuError`), and their
    couplings.  ``inspect=False`` skips the measured checks (every unit is taken to have feedthrough).  ``signals``:
    unit name -> the variables of its connections (:func:`open_unit`)."""
    graph = scene.graph()
    kinds = [graph.port_kind(i, 0) for i in range(graph.n_subsystems)]
    signs = scene.graph_signs()
    units, couplings = [], []
    try:
        for (name, sub), kind in zip(scene.data["subsystems"].items(), kinds):
            unit = open_unit(scene, name, kind, cache=cache, signals=(signals or {}).get(name))
            units.append(unit)
            Recorder(unit, sub.get("record", []))  # the names to record checked before any step
            mass = sub.get("mass")
            if isinstance(mass, str):
                mass = unit.get_named(mass)
            feedthrough, gain = True, float("nan")
            if inspect:
                found = inspect_unit(
                    unit,
                    kind=kind,
                    force_sign=sub["force_sign"],
                    H=float(scene.coupling["H"]),
                    t0=unit.t,
                    rollback_tolerance=rollback_tolerance(sub),
                )
                refuse(found)
                feedthrough, gain = found.feedthrough, found.gain
                unit.checked()
            couplings.append(Coupling(kind, signs[len(couplings)], mass, feedthrough, gain))
        if inspect:
            joint = joint_direction(
                scene.names, kinds, signs, [c.gain for c in couplings],
                [-int(sub["force_sign"]) for sub in scene.data["subsystems"].values()],
            )  # fmt: skip
            if joint.verdict == "refused":
                raise FmuError(f"{scene.path}: {joint.key}: {joint.detail}; {joint.fix}")
        check_scheme(scene, units, couplings, graph)
    except BaseException:
        for unit in units:
            unit.close()
        raise
    return units, couplings


@dataclass
class Start:
    """How a run starts: the state and coupling history, where the coupling variables came from, and the gap of
    the joint's positions and velocities at ``t_start`` (before a projection)."""

    state: np.ndarray
    history: np.ndarray
    coupling_source: str  # "scene" or "computed"
    position_gap: float
    velocity_gap: float
    initial: str  # "check", "project" or "as-is"
    warning: str = ""  # initial_coupling given in the scene that the units do not meet


def consistent_start(scene: Scene, problem: FmuCosimulation) -> Start:
    """The run's start: every joint's positions (and velocities, where the method enforces them) consistent at
    ``t_start`` (``initial: check`` refuses a gap beyond ``initial_tolerance``, ``project`` projects the units onto
    the joints, ``as-is`` accepts it and reports it), and the coupling variables the scene gives or, by default,
    those the units need at ``t_start`` (:meth:`FmuCosimulation.consistent_coupling`)."""
    state = problem.initial_state()
    n = problem.n_dim
    joints = problem.graph.joints
    gaps_x = [state[jt.first, :n] - state[jt.second, :n] for jt in joints]
    gaps_v = [state[jt.first, n:] - state[jt.second, n:] for jt in joints]
    size_x = max(1.0, float(np.max(np.abs(state[:, :n]))))
    size_v = max(1.0, float(np.max(np.abs(state[:, n:]))))
    tol = float(scene.data.get("initial_tolerance", 1e-9))
    mode = scene.data.get("initial", "check")
    method = scene.method
    velocity_level = method.projection or any(w != 0 and levels[1] != 0 for w, levels in method.solves)
    checks = [("position", gaps_x, size_x, "m")] + ([("velocity", gaps_v, size_v, "m/s")] if velocity_level else [])
    for what, gaps, size, unit in checks:
        for j, (jt, gap) in enumerate(zip(joints, gaps)):
            worst = float(np.max(np.abs(gap)))
            if mode == "check" and worst > tol * size:
                a, b = scene.names[jt.first], scene.names[jt.second]
                whose = "the joint's" if not scene.has_joints else f"{scene.joint_label(j)}:"
                raise FmuError(
                    f"{scene.path}: initial: {whose} {what.replace('y', 'ie')}s differ at t_start: {a} "  # velocities
                    f"{_text(state[jt.first], what, n)} {unit}, {b} {_text(state[jt.second], what, n)} {unit} (gap "
                    f"{worst:.3g} {unit} > initial_tolerance {tol:g} x {size:g}); set consistent start values, or "
                    "initial: project (units that can be set) or initial: as-is (the gap is reported)"
                )
    position_gap = max(float(np.max(np.abs(g))) for g in gaps_x)
    velocity_gap = max(float(np.max(np.abs(g))) for g in gaps_v)
    if mode == "project":
        state = problem.project(state)
    given = scene.data.get("initial_coupling")
    if given is not None:
        e0, source = np.asarray(given, dtype=float), "scene"
    else:
        e0, source = problem.consistent_coupling(), "computed"
    warning = "" if given is None else given_coupling_warning(scene.path, e0, problem.consistent_coupling())
    return Start(state, problem.initial_history(e0), source, position_gap, velocity_gap, mode, warning)


def _text(row, what, n) -> str:
    values = row[:n] if what == "position" else row[n:]
    return f"{float(values[0]):.12g}" if n == 1 else "(" + ", ".join(f"{float(v):.12g}" for v in values) + ")"


def divergence_bound(scene: Scene, state) -> float:
    """The magnitude of the state (SI) beyond which a run has diverged: the scene's ``divergence_bound``, else
    ``1e10 (1 + |state at t_start|)``."""
    given = scene.data.get("divergence_bound")
    return float(given) if given is not None else 1e10 * (1.0 + float(np.max(np.abs(state))))


def run_scene(scene, *, cache=None, progress=None, opened=None) -> SceneRun:
    """Run a scene (a :class:`~icosim.problems.fmu.scene.Scene` or a path) to ``t_end``.

    The units are opened and checked (:func:`open_units`), the start made consistent (:func:`consistent_start`),
    then the engine's run loop (:func:`icosim.engine.run.simulate`) takes the macro steps.  A unit's
    refused step or an output that is not finite raises :class:`~icosim.problems.fmu.errors.UnitStepError` (nothing is
    returned); a state that is not finite or beyond :func:`divergence_bound` ends the run with
    ``status = "diverged"`` and the step.  ``progress(n_done)`` is called after each step.  ``opened``: the units
    and couplings :func:`open_units` returned, at their start (the caller closes them), else they are opened here."""
    scene = scene if isinstance(scene, Scene) else load_scene(scene)
    c = scene.coupling
    clock = time.perf_counter()
    units, couplings = open_units(scene, cache=cache) if opened is None else opened
    problem = None
    try:
        problem = FmuCosimulation(
            units,
            couplings,
            scene.graph(),
            c["k"],
            c["H"],
            t0=float(scene.data.get("t_start", 0.0)),
            perturbation=c["perturbation"],
            sensitivities=c["sensitivities"],
            iterations=c["iterations"],
        )
        start = consistent_start(scene, problem)
        recording = Recording(problem, units, scene, start.history[..., 0, :])

        def step_done(n, state, history, y):
            recording.read(history[..., 0, :])
            if progress is not None:
                progress(n)

        with np.errstate(over="ignore", invalid="ignore"):  # a diverging run is reported, not warned about
            traj, times, steps = scene_steps(scene, problem, start, divergence_bound(scene, start.state), step_done)
        if traj.failed_at is not None:
            raise traj.error
        status, reason = "completed", ""
        if traj.diverged_at is not None:
            t_div = times[-1] + steps.rejected_H[-1] if steps else problem.t0 + traj.diverged_at * float(c["H"])
            status = "diverged"
            reason = f"diverged at macro step {traj.diverged_at} (t = {t_div:.12g} s): {traj.reason}"
        nan_y = np.full((len(units), 4, problem.n_dim), np.nan)
        outputs = [nan_y if y is None else y for y in traj.outputs]
        info = {u.label: u.info() for u in units}
        for u, cp in zip(units, couplings):
            info[u.label]["feedthrough"] = "yes" if cp.feedthrough else "through a step only"
        return SceneRun(
            scene,
            times,
            np.array(traj.states),
            np.array(traj.coupling),
            np.array(outputs),
            info,
            status,
            reason,
            time.perf_counter() - clock,
            start,
            traj.diverged_at,
            recording.result(len(traj.states)),
            steps,
        )
    finally:
        if problem is not None:
            problem.close()
        for unit in units if opened is None else ():
            unit.close()


def run_dataset(run: SceneRun, *, command: str = ""):
    """:func:`run_dataset_data` as an :class:`xarray.Dataset`."""
    return run_dataset_data(run, command=command).to_xarray()


def run_dataset_data(run: SceneRun, *, command: str = ""):
    """The run as a :class:`~icosim.io.dataset.DatasetDict`: ``position``/``velocity``/``acceleration`` (subsystem,
    time), the coupling variables, per joint the force on its first unit and the gap -- ``multiplier`` and ``gap``
    (time) for a scene without joints, ``joint_force`` and ``joint_gap`` (joint, time) with ``joint_first``,
    ``joint_second`` and ``joint_decomposition`` along ``joint`` for a scene with joints -- and the scene and the
    units' provenance as attributes."""
    import json

    from ...io.dataset import DatasetDict
    from ...io.netcdf import provenance_attrs

    scene = run.scene
    names = list(scene.names)
    graph = scene.graph(run.n_dim)
    n = run.n_dim
    # one component: (subsystem, time) as the scalar test model; more: a trailing component axis
    comp = () if n == 1 else ("component",)
    squeeze = (lambda a: a[..., 0]) if n == 1 else (lambda a: a)
    sub_time = lambda a: squeeze(np.moveaxis(a, 0, 1))  # (time, subsystem, n) -> (subsystem, time[, n])
    if scene.has_joints:
        variables = list(graph.variable_names())
    else:
        dec = graph.joints[0].decomposition
        variables = list(dec.variables) if n == 1 else [f"{v}_{c}" for v in dec.variables for c in "xyz"[:n]]
    per_unit = {
        "position": (("subsystem", "time") + comp, sub_time(run.positions), {"units": "m"}),
        "velocity": (("subsystem", "time") + comp, sub_time(run.velocities), {"units": "m s-1"}),
        "acceleration": (
            ("subsystem", "time") + comp,
            sub_time(run.outputs[:, :, 2, :]),
            {"units": "m s-2", "comment": "output at the end of each macro step; NaN at the start"},
        ),
    }
    coupling = {
        "coupling": (
            ("time", "coupling_variable"),
            run.coupling,
            {"comment": "coupling variables e (N for lambda_c, m s-2 for a_tilde)"},
        )
    }
    coords = {
        "time": ("time", run.times, {"units": "s"}),
        "subsystem": ("subsystem", names),
        "coupling_variable": ("coupling_variable", variables),
    } | ({} if n == 1 else {"component": ("component", list("xyz"[:n]))})
    if scene.has_joints:
        joint_time = lambda a: squeeze(np.moveaxis(a, 0, 1))  # (time, joint, n) -> (joint, time[, n])
        per_joint = {
            "joint_force": (
                ("joint", "time") + comp,
                joint_time(run.joint_forces()),
                {
                    "units": "N",
                    "long_name": "force of the joint on its first subsystem (on the second the opposite)",
                    "comment": "the joint's multiplier lambda_j where its first side is force driven, else the "
                    "force the first subsystem's drive exerts (NaN at the start)",
                },
            ),
            "joint_gap": (
                ("joint", "time") + comp,
                joint_time(run.joint_gaps()),
                {"units": "m", "long_name": "position of the joint's first subsystem minus its second's"},
            ),
        }
        coords |= {
            "joint": ("joint", np.arange(1, graph.n_joints + 1)),
            "joint_first": ("joint", [names[jt.first] for jt in graph.joints]),
            "joint_second": ("joint", [names[jt.second] for jt in graph.joints]),
            "joint_decomposition": ("joint", [jt.decomposition.name for jt in graph.joints]),
        }
    else:
        per_joint = {
            "multiplier": (
                ("time",) + comp,
                squeeze(run.outputs[:, 0, 3, :]),
                {
                    "units": "N",
                    "long_name": "coupling force lambda_c on the first subsystem (force_sign 1)",
                    "comment": "as the first subsystem sees it at the end of each macro step; NaN at the start",
                },
            ),
            "gap": (
                ("time",) + comp,
                squeeze(run.positions[:, 0] - run.positions[:, 1]),
                {"units": "m", "long_name": "position of the first subsystem minus the second's"},
            ),
        }
    controlled, control_attrs = controlled_entries(run)
    ds = DatasetDict(per_unit | per_joint | coupling | recorded_entries(run.recorded) | controlled, coords=coords)
    attrs = provenance_attrs(scene.data, title=f"FMU scene {scene.path.name}", command=command)
    attrs["scene_json"] = attrs["config_json"]
    if scene.system is not None:  # the system file read: what it gave, including what icosim keeps but does not use
        attrs["system_json"] = json.dumps(scene.system.summary(), sort_keys=True)
    attrs["status"] = run.status
    attrs["reason"] = run.reason
    attrs["diverged_at"] = -1 if run.diverged_at is None else int(run.diverged_at)
    if run.start is not None:
        attrs["initial"] = run.start.initial
        attrs["initial_position_gap"] = run.start.position_gap
        attrs["initial_velocity_gap"] = run.start.velocity_gap
        attrs["initial_coupling_source"] = run.start.coupling_source
        attrs["initial_coupling_warning"] = run.start.warning
    attrs["scheme"] = scene.scheme.name
    attrs["method_engine_parameters"] = json.dumps(scene.method.params, sort_keys=True)
    attrs["wall_time_s"] = run.wall_time
    for name, info in run.units.items():
        for key, value in info.items():
            attrs[f"{name}_{key}"] = value
    attrs["do_step_calls"] = sum(i["do_step_calls"] for i in run.units.values())
    attrs["states_saved"] = sum(i["states_saved"] for i in run.units.values())
    attrs["states_restored"] = sum(i["states_restored"] for i in run.units.values())
    ds.attrs.update(attrs | control_attrs)
    return ds


def run_summary(run: SceneRun) -> dict:
    """A JSON-ready summary of a run: status, steps, counters, final positions and gap."""
    steps = len(run.times) - 1
    return {
        "scene": str(run.scene.path),
        "status": run.status,
        "reason": run.reason or None,
        "macro_steps": steps,
        "t_end": float(run.times[-1]),
        "coupling": {k: v for k, v in run.scene.coupling.items()},
        "described": run.scene.describe(),
        "units": run.units,
        "do_step_calls_per_macro_step": (sum(i["do_step_calls"] for i in run.units.values()) / steps)
        if steps
        else None,
        "final_position": {
            name: (float(p[0]) if run.n_dim == 1 else [float(v) for v in p])
            for name, p in zip(run.scene.names, run.positions[-1])
        },
        "max_abs_gap": float(np.max(np.abs(run.joint_gaps()))),  # every joint, the largest component
        "diverged_at": run.diverged_at,
        "initial": None
        if run.start is None
        else {
            "mode": run.start.initial,
            "position_gap": run.start.position_gap,
            "velocity_gap": run.start.velocity_gap,
            "coupling": run.start.coupling_source,
            "coupling_values": [float(v) for v in run.coupling[0]],
            "warning": run.start.warning or None,
        },
        "wall_time_s": run.wall_time,
    }

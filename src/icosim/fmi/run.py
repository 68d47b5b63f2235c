"""A scene run: its units opened, the macro steps of :func:`icosim.engine.macrostep.macro_step`, the dataset."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..engine.decompositions import get_decomposition
from ..engine.macrostep import macro_step
from .build import build_unit, is_source_dir
from .problem import Coupling, FmuCosimulation
from .scene import Scene, load_scene
from .units import ROLES, Unit, _variable

__all__ = ["run_scene", "open_units", "SceneRun"]


@dataclass
class SceneRun:
    """What a run produced: times, states, coupling variables and outputs at ``T_0 ... T_n``; the units' info."""

    scene: Scene
    times: np.ndarray
    states: np.ndarray  # (n+1, 2, 2 n_dim): positions, then velocities
    coupling: np.ndarray  # (n+1, n_e)
    outputs: np.ndarray  # (n+1, 2, 4, n_dim); row 0 NaN (no step has produced it)
    units: dict = field(default_factory=dict)  # name -> Unit.info()
    status: str = "completed"
    reason: str = ""
    wall_time: float = 0.0

    @property
    def n_dim(self) -> int:
        """Components of a joint point's position (1 on a line, 2 in the plane)."""
        return self.outputs.shape[-1]

    @property
    def positions(self) -> np.ndarray:
        """``(n+1, 2, n_dim)``."""
        return self.states[..., : self.n_dim]

    @property
    def velocities(self) -> np.ndarray:
        """``(n+1, 2, n_dim)``."""
        return self.states[..., self.n_dim :]


def fmu_file(path, cache=None):
    """The ``.fmu`` of a scene's ``fmu`` entry: the file itself, or the unit built from a source directory."""
    return build_unit(path, cache) if is_source_dir(path) else path


def open_units(scene: Scene, *, cache=None):
    """The scene's two units, opened with their start values at ``t_start``, and their couplings."""
    c = scene.coupling
    kinds = get_decomposition(c["decomposition"]).kinds
    units, couplings = [], []
    t0 = float(scene.data.get("t_start", 0.0))
    try:
        for (name, sub), kind in zip(scene.data["subsystems"].items(), kinds):
            names = {k: sub[k] for k in ROLES if k in sub and k in _needed(kind, scene.method.projection)}
            unit = Unit(
                name,
                fmu_file(scene.fmus[name], cache),
                names,
                sub.get("start", {}),
                inputs=c["inputs"],
                substeps=c["substeps"],
                t0=t0,
            )
            units.append(unit)
            mass = sub.get("mass")
            if isinstance(mass, str):
                _variable(name, "mass", mass, {v.name: v for v in unit.md.modelVariables})
                mass = unit.get_named(mass)
            couplings.append(Coupling(kind, sub["force_sign"], mass))
    except BaseException:
        for unit in units:
            unit.close()
        raise
    return units, couplings


def _needed(kind, projects):
    keys = {"position", "velocity", "acceleration"}
    keys |= {"force"} if kind == "force" else {"acceleration_input", "reaction_force"}
    return keys | ({"set_position", "set_velocity"} if projects else set())


def run_scene(scene, *, cache=None, progress=None) -> SceneRun:
    """Run a scene (a :class:`~icosim.fmi.scene.Scene` or a path) to ``t_end``.

    A unit's refused step raises :class:`~icosim.fmi.errors.UnitStepError` (nothing is returned); a state that
    is no longer finite ends the run with ``status = "diverged"``.  ``progress(n_done)`` is called after each step.
    """
    scene = scene if isinstance(scene, Scene) else load_scene(scene)
    c = scene.coupling
    start = time.perf_counter()
    units, couplings = open_units(scene, cache=cache)
    problem = None
    try:
        problem = FmuCosimulation(
            units,
            couplings,
            c["decomposition"],
            c["k"],
            c["H"],
            t0=float(scene.data.get("t_start", 0.0)),
            perturbation=c["perturbation"],
            sensitivities=c["sensitivities"],
        )
        state = problem.initial_state()
        history = problem.initial_history(scene.data.get("initial_coupling"))
        states, coupling, outputs = [state], [history[0]], [np.full((2, 4, problem.n_dim), np.nan)]
        status, reason = "completed", ""
        for n in range(1, scene.n_steps + 1):
            with np.errstate(over="ignore", invalid="ignore"):  # a diverging run is reported below
                state, history, y = macro_step(
                    problem, scene.method, state, history, scheme=c["scheme"], iterations=c["iterations"]
                )
            if not np.all(np.isfinite(state)):
                status, reason = "diverged", f"state not finite at macro step {n} (t = {problem.time:.12g} s)"
                break
            states.append(state)
            coupling.append(history[0])
            outputs.append(y)
            if progress is not None:
                progress(n)
        t0 = problem.t0
        times = t0 + c["H"] * np.arange(len(states))
        info = {u.label: u.info() for u in units}
        return SceneRun(
            scene,
            times,
            np.array(states),
            np.array(coupling),
            np.array(outputs),
            info,
            status,
            reason,
            time.perf_counter() - start,
        )
    finally:
        if problem is not None:
            problem.close()
        for unit in units:
            unit.close()


def run_dataset(run: SceneRun, *, command: str = ""):
    """:func:`run_dataset_data` as an :class:`xarray.Dataset`."""
    return run_dataset_data(run, command=command).to_xarray()


def run_dataset_data(run: SceneRun, *, command: str = ""):
    """The run as a :class:`~icosim.io.dataset.DatasetDict`: ``position``/``velocity``/``acceleration`` (subsystem, time),
    ``multiplier`` and ``gap`` (time), the coupling variables, the scene and the units' provenance as attributes."""
    import json

    from ..io.dataset import DatasetDict
    from ..io.netcdf import provenance_attrs

    scene = run.scene
    names = list(scene.names)
    dec = get_decomposition(scene.coupling["decomposition"])
    n = run.n_dim
    # one component: (subsystem, time) as the scalar test model; more: a trailing component axis
    comp = () if n == 1 else ("component",)
    squeeze = (lambda a: a[..., 0]) if n == 1 else (lambda a: a)
    sub_time = lambda a: squeeze(np.moveaxis(a, 0, 1))  # (time, subsystem, n) -> (subsystem, time[, n])
    variables = list(dec.variables) if n == 1 else [f"{v}_{c}" for v in dec.variables for c in "xyz"[:n]]
    ds = DatasetDict(
        {
            "position": (("subsystem", "time") + comp, sub_time(run.positions), {"units": "m"}),
            "velocity": (("subsystem", "time") + comp, sub_time(run.velocities), {"units": "m s-1"}),
            "acceleration": (
                ("subsystem", "time") + comp,
                sub_time(run.outputs[:, :, 2, :]),
                {"units": "m s-2", "comment": "output at the end of each macro step; NaN at the start"},
            ),
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
            "coupling": (
                ("time", "coupling_variable"),
                run.coupling,
                {"comment": "coupling variables e (N for lambda_c, m s-2 for a_tilde)"},
            ),
        },
        coords={
            "time": ("time", run.times, {"units": "s"}),
            "subsystem": ("subsystem", names),
            "coupling_variable": ("coupling_variable", variables),
        }
        | ({} if n == 1 else {"component": ("component", list("xyz"[:n]))}),
    )
    attrs = provenance_attrs(scene.data, title=f"FMU scene {scene.path.name}", command=command)
    attrs["scene_json"] = attrs["config_json"]
    attrs["status"] = run.status
    attrs["reason"] = run.reason
    attrs["method_engine_parameters"] = json.dumps(scene.method.params, sort_keys=True)
    attrs["wall_time_s"] = run.wall_time
    for name, info in run.units.items():
        for key, value in info.items():
            attrs[f"{name}_{key}"] = value
    attrs["do_step_calls"] = sum(i["do_step_calls"] for i in run.units.values())
    attrs["states_saved"] = sum(i["states_saved"] for i in run.units.values())
    attrs["states_restored"] = sum(i["states_restored"] for i in run.units.values())
    ds.attrs.update(attrs)
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
        "units": run.units,
        "do_step_calls_per_macro_step": (sum(i["do_step_calls"] for i in run.units.values()) / steps)
        if steps
        else None,
        "final_position": {
            name: (float(p[0]) if run.n_dim == 1 else [float(v) for v in p])
            for name, p in zip(run.scene.names, run.positions[-1])
        },
        "max_abs_gap": float(np.max(np.abs(run.positions[:, 0] - run.positions[:, 1]))),  # largest component
        "wall_time_s": run.wall_time,
    }

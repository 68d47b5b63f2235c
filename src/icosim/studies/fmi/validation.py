"""FMU scenes checked against the built-in models: the datasets of the workflow's FMU part (docs/fmi.md).

Three checks, each a dataset that the claims (``config/claims/fmi.yaml``) and the report read:

* :func:`scene_validation` -- one scene's run next to the built-in model from the same start at the same
  dimensionless point (:func:`linear_builtin` for the two-mass units, :func:`pendulum_builtin` for the double
  pendulum's links), the spectral radius predicted before the run (:func:`icosim.problems.fmu.predict.predict_scene`)
  and the growth per macro step measured on the run (:func:`measured_growth`);
* :func:`scene_job` -- the workflow's job of one scene: the run and its check written, under the supervisor.

The orders of convergence on the units: :mod:`icosim.studies.fmi.orders`.

The scene's units are built into ``cache`` (:func:`icosim.problems.fmu.build.build_unit`), as the scene runs are.
"""

from __future__ import annotations

import json
import os
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ...engine.decompositions import get_decomposition
from ...engine.methods import make_method
from ...engine.run import simulate
from ...io.dataset import DatasetDict
from ...problems.fmu.errors import SceneError
from ...problems.fmu.scene import COUPLING_KEYS, load_scene
from ...problems.linear.model import PhysicalModel
from ...problems.linear.problem import LinearCosimulation
from .config import case_label

__all__ = [
    "BUILTINS",
    "linear_builtin",
    "pendulum_builtin",
    "measured_growth",
    "builtin_difference",
    "scene_validation",
    "scene_validation_data",
    "scene_job",
    "case_label",
]

#: The built-in model a scene is compared with (``config/fmi.yaml``, ``scenes.<name>.builtin``).
BUILTINS = ("linear", "pendulum", "none")


@contextmanager
def fmu_cache(cache):
    """``$ICOSIM_FMU_CACHE`` set to ``cache`` for the block (the units built by the workflow's build job)."""
    if cache is None:
        yield
        return
    old = os.environ.get("ICOSIM_FMU_CACHE")
    os.environ["ICOSIM_FMU_CACHE"] = str(cache)
    try:
        yield
    finally:
        if old is None:
            del os.environ["ICOSIM_FMU_CACHE"]
        else:
            os.environ["ICOSIM_FMU_CACHE"] = old


def _method_params(scene) -> dict:
    """The method's parameters as the scene gives them (dimensional)."""
    return {k: v for k, v in scene.data["coupling"].items() if k not in COUPLING_KEYS}


def _history(scene, e0) -> np.ndarray:
    """The coupling history at ``T_0`` (SI): ``e0`` at every past node."""
    return np.tile(np.asarray(e0, dtype=float), (int(scene.coupling["k"]) + 1, 1))


def linear_builtin(scene, e0):
    """The built-in linear model (:class:`~icosim.problems.linear.problem.LinearCosimulation`) at the scene's
    dimensionless point: masses, stiffnesses, dampings and start ``x0, v0`` from the units' start values, the
    scene's method, ``k``, scheme and corrector passes, the coupling variables ``e0`` at ``T_0`` (SI: a run's
    first, :func:`icosim.problems.fmu.run.consistent_start`).  Returns positions and velocities (SI), each
    ``(n + 1, 2)``."""
    subs = list(scene.data["subsystems"].values())
    start = [s.get("start", {}) for s in subs]
    for name, st in zip(scene.names, start):
        missing = [key for key in ("m", "c", "d") if key not in st]
        if missing or float(st.get("c3", 0.0)) != 0.0:
            raise SceneError(f"{scene.path}: {name}: not a linear single-mass unit with start m, c, d: {missing}")
    if [s["force_sign"] for s in subs] != [1, -1]:
        raise SceneError(f"{scene.path}: the built-in model has force_sign 1 on the first unit, -1 on the second")
    c = scene.coupling
    H, k = float(c["H"]), int(c["k"])
    model = PhysicalModel(
        m1=float(start[0]["m"]),
        m2=float(start[1]["m"]),
        c1=float(start[0]["c"]),
        c2=float(start[1]["c"]),
        d1=float(start[0]["d"]),
        d2=float(start[1]["d"]),
        H=H,
    )
    dec = get_decomposition(c["decomposition"])
    problem = LinearCosimulation(model.coefficients(), dec.name, k)
    state = np.array([[float(st.get("x0", 0.0)), float(st.get("v0", 0.0)) * H] for st in start])
    # SI -> dimensionless coupling variables: lambda_bar = lambda H^2 / m1, a_bar = a H^2
    scale = np.array([H**2 / model.m1 if name == "lambda_c" else H**2 for name in dec.variables])
    history = _history(scene, e0) * scale
    with np.errstate(over="ignore", invalid="ignore"):
        traj = simulate(
            problem, scene.method, state, history, scene.n_steps, scheme=c["scheme"], iterations=c["iterations"]
        )
    s = np.array(traj.states)
    return s[..., 0], s[..., 1] / H


def pendulum_builtin(scene, e0):
    """The built-in double pendulum (:class:`~icosim.problems.pendulum.problem.PendulumCosimulation`, Radau IIA at
    1e-10) from the links' start values, with the scene's method, ``k``, scheme and the coupling variables ``e0``
    at ``T_0`` (SI).
    Returns the joint point of each link ``(n, 2, 2)`` and the coupling force on link 1 ``(n, 2)`` at
    ``T_1 ... T_n``."""
    from ...problems.pendulum.model import PendulumParameters
    from ...problems.pendulum.problem import PendulumCosimulation

    s1, s2 = (sub.get("start", {}) for sub in scene.data["subsystems"].values())
    p = PendulumParameters(
        m1=s1["m"], m2=s2["m"], J1=s1["J"], J2=s2["J"], l1=s1["l"], l2=s2["l"], g=s1["g"], d=s1["d"],
        phi1_0=s1["phi0"], phi2_0=s2["phi0"],
    )  # fmt: skip
    c = scene.coupling
    dec = get_decomposition(c["decomposition"])
    problem = PendulumCosimulation(p, dec.name, int(c["k"]), float(c["H"]), rtol=1e-10, atol=1e-10)
    method = make_method(c["method"], **_method_params(scene))
    history = _history(scene, e0)
    traj = simulate(
        problem, method, p.initial_state(), history, scene.n_steps, scheme=c["scheme"], iterations=c["iterations"]
    )
    y = np.array(traj.outputs[1:])  # (n, 2, 4, 2): x, v, a, f per link
    return y[:, :, 0, :], y[:, 0, 3, :]


def _array(run, name) -> np.ndarray:
    """A variable of a run's dataset (:func:`icosim.problems.fmu.run.run_dataset_data` or an :class:`xarray.Dataset`)."""
    return run.array(name) if isinstance(run, DatasetDict) else run[name].values


def measured_growth(run) -> float:
    """Growth per macro step measured on a run of a scalar joint: the largest amplitude
    ``max_i sqrt(x_i^2 + (v_i/omega)^2)`` (``omega^2 = (c1 + c2)/(m1 + m2)``, the coupled oscillation) over
    the last eighth of the run against that over the eighth after its middle, per step between them.
    NaN for a joint in the plane (its equilibrium is not the origin) or a run too short to measure."""
    if "component" in run.dims:
        return float("nan")
    subs = json.loads(run.attrs["scene_json"])["subsystems"].values()
    st = [s.get("start", {}) for s in subs]
    try:
        omega = np.sqrt((float(st[0]["c"]) + float(st[1]["c"])) / (float(st[0]["m"]) + float(st[1]["m"])))
    except KeyError:
        omega = 1.0 / float(_array(run, "time")[1] - _array(run, "time")[0])
    x, v = _array(run, "position"), _array(run, "velocity")  # (subsystem, time)
    with np.errstate(over="ignore", invalid="ignore"):
        amp = np.max(np.sqrt(x**2 + (v / omega) ** 2), axis=0)
    n = amp.size - 1
    w = n // 8
    if w < 1:
        return float("nan")
    early, late = amp[n // 2 : n // 2 + w], amp[n - w + 1 :]
    steps = (n - w + 1) - n // 2
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return float((np.max(late) / np.max(early)) ** (1.0 / steps))


def builtin_difference(scene, run, builtin) -> dict:
    """The run against the built-in model: ``difference`` (linear: largest position or velocity difference
    relative to the largest value, as ``tests/problems/fmu/test_linear_scenes.py`` measures; pendulum: largest
    joint point difference in m) and, for the pendulum, ``force_difference`` (relative to the largest joint
    force)."""
    nan = float("nan")
    e0 = _array(run, "coupling")[0]
    if builtin == "linear":
        x, v = linear_builtin(scene, e0)
        n = min(len(x), run.sizes["time"])
        got_x, got_v = _array(run, "position").T[:n], _array(run, "velocity").T[:n]
        with np.errstate(over="ignore", invalid="ignore"):
            dx = np.max(np.abs(got_x - x[:n])) / max(1.0, np.max(np.abs(x[:n])))
            dv = np.max(np.abs(got_v - v[:n])) / max(1.0, np.max(np.abs(v[:n])))
        return {"difference": float(max(dx, dv)), "force_difference": nan}
    if builtin == "pendulum":
        joint, force = pendulum_builtin(scene, e0)
        n = min(len(joint), run.sizes["time"] - 1)
        got = np.moveaxis(_array(run, "position"), 0, 1)[1 : n + 1]  # (time, subsystem, component)
        dp = np.max(np.abs(got - joint[:n]))
        df = np.max(np.abs(_array(run, "multiplier")[1 : n + 1] - force[:n])) / np.max(np.abs(force[:n]))
        return {"difference": float(dp), "force_difference": float(df)}
    return {"difference": nan, "force_difference": nan}


def scene_validation(scene, run, *, name: str, builtin: str = "none", cache=None, prediction=None):
    """:func:`scene_validation_data` as an :class:`xarray.Dataset`."""
    return scene_validation_data(scene, run, name=name, builtin=builtin, cache=cache, prediction=prediction).to_xarray()


def scene_validation_data(scene, run, *, name: str, builtin: str = "none", cache=None, prediction=None) -> DatasetDict:
    """One scene's validation dataset: the prediction before the run, the growth measured on it, the
    difference to the built-in model.  ``run``: the scene's dataset (:func:`icosim.problems.fmu.run.run_dataset_data`
    or :func:`~icosim.problems.fmu.run.run_dataset`).  ``prediction``: what
    :func:`~icosim.problems.fmu.predict.predict_scene` returned (or the :class:`SceneError` it raised) for the
    scene, else it is made here."""
    from ...io.netcdf import provenance_attrs
    from ...problems.fmu.predict import predict_scene

    if builtin not in BUILTINS:
        raise SceneError(f"{name}: builtin must be one of {BUILTINS}, got {builtin!r}")
    scene = scene if hasattr(scene, "data") else load_scene(scene)
    c = scene.coupling
    nan = float("nan")
    schemes, rhos, errs, verdicts = [], [], [], []
    try:
        if prediction is None:
            with fmu_cache(cache):
                prediction = predict_scene(scene)
        if isinstance(prediction, SceneError):
            raise prediction
        for row in prediction["schemes"]:
            schemes.append(row["scheme"])
            rhos.append(nan if row["rho"] is None else row["rho"])
            errs.append(row.get("rho_error", nan))
            verdicts.append(row["verdict"])
        mine = next(row for row in prediction["schemes"] if row["scene"])
        predicted, predicted_verdict, why_not = mine["rho"], mine["verdict"], ""
        identified = {
            u: {k: v for k, v in p.items() if k != "probe_do_step_calls"} for u, p in prediction["units"].items()
        }
    except SceneError as exc:  # a joint in the plane: no single-mass units to identify
        predicted, predicted_verdict, why_not, identified = nan, "not predicted", str(exc), {}
    growth = measured_growth(run)
    diff = builtin_difference(scene, run, builtin)
    with np.errstate(invalid="ignore", divide="ignore"):
        deviation = abs(growth / predicted - 1.0) if predicted and np.isfinite(predicted) else nan
    names = list(scene.names)
    units = "; ".join(
        f"{u}: {run.attrs[f'{u}_model_name']} (FMI {run.attrs[f'{u}_fmi_version']}, inputs by "
        f"{run.attrs[f'{u}_inputs']})"
        for u in names
    )
    exact = all(run.attrs[f"{u}_inputs"] == "derivatives" for u in names)
    ds = DatasetDict(
        {
            "predicted_rho": ((), float(predicted if predicted is not None else nan)),
            "measured_growth": (
                (),
                growth,
                {"comment": "per macro step (icosim.studies.fmi.validation.measured_growth)"},
            ),
            "growth_deviation": ((), float(deviation), {"comment": "|measured growth / predicted rho - 1|"}),
            "builtin_difference": ((), diff["difference"], {"comment": _DIFFERENCE_TEXT[builtin]}),
            "builtin_force_difference": ((), diff["force_difference"]),
            "scheme_rho": (("predicted_for",), np.array(rhos, dtype=float)),
            "scheme_rho_error": (("predicted_for",), np.array(errs, dtype=float)),
            "scheme_verdict": (("predicted_for",), np.array(verdicts, dtype=str)),
        },
        coords={"predicted_for": ("predicted_for", np.array(schemes, dtype=str))},
    )
    attrs = provenance_attrs(scene.data, title=f"FMU scene {name}: validation")
    attrs.update(
        part="fmi",
        dataset="scene",
        scene=name,
        method=scene.method.name,
        decomposition=c["decomposition"],
        k=int(c["k"]),
        scheme=c["scheme"],
        H=float(c["H"]),
        t_end=float(scene.data["t_end"]),
        macro_steps=int(run.sizes["time"] - 1),
        status=run.attrs["status"],
        builtin=builtin,
        units=units,
        exact_inputs="yes" if exact else "no",
        predicted_verdict=predicted_verdict,
        prediction_note=why_not,
        identified_json=json.dumps(identified, sort_keys=True),
        do_step_calls=int(run.attrs["do_step_calls"]),
        wall_time_s=float(run.attrs["wall_time_s"]),
    )
    ds.attrs.update(attrs)
    return ds


def scene_job(scene, *, name: str, builtin: str, cache, run_path, validation_path, command: str = "") -> str:
    """The workflow's job of one scene: its run written to ``run_path`` and its check to ``validation_path``, in a
    child process under :func:`icosim.problems.fmu.guard.supervised` (a unit that hangs or crashes is named).  Returns a
    line for the job's log; raises :class:`SceneError` with the supervisor's message when the run was stopped,
    and :class:`~icosim.problems.fmu.errors.UnitStepError` when a unit refused a step."""
    import logging

    from ...io.netcdf import write_netcdf
    from ...problems.fmu.guard import CALL_SECONDS, supervised
    from ...problems.fmu.predict import predict_scene
    from ...problems.fmu.run import open_units, run_dataset_data, run_scene

    def work():
        # each unit opened once: predicted from its start (left there), then run
        with fmu_cache(cache):
            opened = open_units(scene, cache=cache)
        try:
            try:
                with fmu_cache(cache):
                    prediction = predict_scene(scene, opened=opened)
            except SceneError as exc:  # a joint in the plane: no single-mass units to identify
                prediction = exc
            run = run_scene(scene, cache=cache, opened=opened)
        finally:
            for unit in opened[0]:
                unit.close()
        # the DatasetDict forms: the job writes the same files without importing xarray
        ds = run_dataset_data(run, command=command)
        write_netcdf(ds, run_path)
        checked = scene_validation_data(scene, ds, name=name, builtin=builtin, cache=cache, prediction=prediction)
        write_netcdf(checked, validation_path)
        logging.info(
            "%s: %s after %d macro steps, %.2f s %s; predicted rho %s (%s), measured growth %s, difference to the "
            "built-in model (%s) %s",
            name, run.status, len(run.times) - 1, run.wall_time, run.reason, float(checked.array("predicted_rho")),
            checked.attrs["predicted_verdict"], float(checked.array("measured_growth")), builtin,
            float(checked.array("builtin_difference")),
        )  # fmt: skip

    outputs = [Path(run_path), Path(validation_path)]
    outcome = supervised(
        work,
        call_seconds=float(scene.data.get("limits", {}).get("call_seconds", CALL_SECONDS)),
        leftovers=[p.parent / f".{p.name}*.part" for p in outputs],
    )
    if outcome.message:
        raise SceneError(f"scene {name}: {outcome.message}")
    if outcome.status:
        raise SceneError(f"scene {name}: the run ended with status {outcome.status} (its log says why)")
    return f"{name}: run and checked ({run_path}, {validation_path})"


_DIFFERENCE_TEXT = {
    "linear": "largest position or velocity difference to the built-in linear model, relative to the largest value",
    "pendulum": "largest joint point difference to the built-in pendulum (m)",
    "none": "no built-in model",
}

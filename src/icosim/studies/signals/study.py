"""One case of the signal-coupling study (:mod:`icosim.studies.signals.config`): OMSimulator's DualMassOscillator
on its Model Exchange units over a list of ``H``, coupled by its signal connections or by a joint, against the
exact solution (:mod:`icosim.problems.fmu.dual_mass`); and for the connections the spectral radius predicted from
the identified units at every ``H`` and, at the case's ``growth_H``, the growth per macro step measured on a run.
A dataset of the workflow's ``signals`` part, read by its claims (:mod:`icosim.studies.signals.checks`), figure
and report section.

* error: the largest displacement error of either mass over the communication points of ``[0, t_end]``, relative
  to the amplitude (the largest start displacement); the run starts from the exact solution's coupling values at
  ``T_0, T_-1, ... T_-k`` (a start from rest in the past would add an error of its own at ``k > 0``);
* order: :func:`icosim.order_fit.asymptotic_order` of the errors over ``H`` (the convergence study's rule);
* prediction: the units identified once (:func:`~icosim.problems.fmu.predict_signals.predict_signal_scene`: a Model
  Exchange unit's continuous model does not depend on ``H``), the recurrence's spectral radius at each ``H``
  (:func:`~icosim.problems.linear.signals.signal_radius`) with its float64 error estimate, "stable" where
  ``rho + error < 1``, "unstable" where ``rho - error > 1``;
* measured growth: :func:`measured_growth` of mass 1's displacement over ``growth_steps`` macro steps from the
  units' start.
"""

from __future__ import annotations

import tempfile
import time

import numpy as np

from ...engine.run import simulate
from ...errors import ParameterError
from ...io.dataset import DatasetDict
from ...order_fit import asymptotic_order
from ...problems.fmu.dual_mass import DualMass
from ...problems.fmu.errors import SceneError
from ...problems.fmu.problem import FmuCosimulation
from ...problems.fmu.run import open_units
from ...problems.fmu.scene import load_scene
from ...problems.fmu.signal_scene import run_signal_scene
from .config import CONNECTIONS, case_label, scene_data, unit_paths, write_scene

__all__ = ["case_data", "case_dataset", "measured_growth", "signal_errors", "joint_errors", "Prediction"]


def measured_growth(x) -> float:
    """Growth per macro step of a displacement ``x`` over ``n`` steps (``n + 1`` points): the largest ``|x|`` over
    the last sixth of the run against that over the sixth from its middle, per step between the two windows.
    For ``x_N = r^N cos(N theta)`` it is ``r`` up to the phase of the maxima (``(1 +- 1/w)`` over ``w`` steps)."""
    x = np.abs(np.asarray(x, dtype=float))
    n = len(x) - 1
    w = n // 6
    if w < 2 or not np.all(np.isfinite(x)):
        return float("nan")
    late, middle = np.max(x[n - w + 1 :]), np.max(x[n // 2 : n // 2 + w])
    return float((late / middle) ** (1.0 / (n - w + 1 - n // 2)))


def _error(times, x1, x2, dmo: DualMass) -> tuple[float, float]:
    """The largest and the final displacement error of either mass, relative to the amplitude."""
    z = dmo.exact(times)
    dev = np.maximum(np.abs(np.asarray(x1) - z[:, 0]), np.abs(np.asarray(x2) - z[:, 1])) / dmo.amplitude
    return float(np.max(dev)), float(dev[-1])


def signal_errors(scene, dmo: DualMass) -> tuple[float, float]:
    """The run of a signal scene from the exact coupling history: its errors (:func:`_error`), NaN if it
    diverged."""
    k, H = scene.coupling["k"], scene.coupling["H"]
    rows = [[dmo.outputs(-j * H)[f"{a}.{y}"] for a, y, _, _ in CONNECTIONS] for j in range(k + 1)]
    with np.errstate(over="ignore", invalid="ignore"):
        run = run_signal_scene(scene, history=rows)
    if run.status != "completed":
        return float("nan"), float("nan")
    return _error(run.times, run.series["system1.x1"], run.series["system2.mass2.s"], dmo)


def joint_errors(scene, dmo: DualMass) -> tuple[float, float]:
    """The run of a joint scene (fd: System1 force-driven, System2 driven by mass 1's motion) from the exact
    coupling history (the force on mass 1, its acceleration): its errors, NaN if it diverged."""
    c = scene.coupling
    k, H = c["k"], c["H"]
    history = []
    for j in range(k + 1):
        out = dmo.outputs(-j * H)
        history.append([out["system2.F"], out["system1.a1"]])
    units, couplings = open_units(scene)
    problem = None
    x2 = [units[1].get_named("mass2.s")]
    try:
        problem = FmuCosimulation(units, couplings, c["decomposition"], k, H, perturbation=c["perturbation"])

        def observe(n, state, hist, y):
            x2.append(units[1].get_named("mass2.s"))

        with np.errstate(over="ignore", invalid="ignore"):
            traj = simulate(problem, scene.method, problem.initial_state(), np.array(history), scene.n_steps,
                            scheme=c["scheme"], observe=observe)  # fmt: skip
        if traj.failed_at is not None:
            raise traj.error
    finally:
        if problem is not None:
            problem.close()
        for unit in units:
            unit.close()
    x1 = np.array(traj.states)[:, 0, 0]
    if len(x1) != scene.n_steps + 1:
        return float("nan"), float("nan")
    return _error(H * np.arange(len(x1)), x1, x2, dmo)


class Prediction:
    """The spectral radius of a signal scene's coupling at any ``H`` from its units identified once, or the
    reason there is none (``reason``)."""

    def __init__(self, scene):
        from ...problems.fmu.predict_signals import predict_signal_scene
        from ...problems.fmu.signals import connections_of
        from ...problems.linear.signals import StateSpaceUnit

        self.reason, self.H_max, self.models = "", float("nan"), None
        try:
            answer = predict_signal_scene(scene)
        except (SceneError, ParameterError) as exc:
            self.reason = str(exc)
            return
        units = [answer["units"][n] for n in scene.names]
        stepped = [n for n, u in zip(scene.names, units) if u.get("model") != "continuous"]
        if stepped or any("undecided" in u for u in units):
            self.reason = f"{stepped[0] if stepped else scene.names[0]}: not identified as a continuous model"
            return
        self.models = [StateSpaceUnit(*(np.array(u[key]) for key in "ABCD"), None) for u in units]
        self.cons = connections_of(scene.connections, list(scene.names))[0]
        self.k, self.scheme = scene.coupling["k"], scene.scheme
        self.implicit = bool(scene.coupling.get("implicit"))
        if self.implicit and not answer["coupling"].startswith("implicit"):
            self.reason, self.models = f"the prediction is of {answer['coupling'].split(',')[0]} coupling", None
            return
        self.H_max = float(answer["largest_stable_H"].get("H_max") or np.nan)
        self.misfit = max(float(u["misfit"]) for u in units)

    def at(self, H: float) -> tuple[float, float, str]:
        """``(rho, its error estimate, verdict)`` at ``H``."""
        from ...problems.linear.signals import signal_radius

        if self.models is None:
            return float("nan"), float("nan"), "undecided"
        implicit = {"implicit": True} if self.implicit else {}  # the implicit recurrence, where the library has it
        rho, err = signal_radius(self.models, self.cons, self.k, float(H), self.scheme, **implicit)
        verdict = "stable" if rho + err < 1 else "unstable" if rho - err > 1 else "undecided"
        return float(rho), float(err), verdict


def case_data(cfg: dict, case: dict, *, root=".") -> DatasetDict:
    """One case over its ``H`` (module docstring); ``cfg``: the part's configuration (``units_dir``, ``units``,
    ``start``, ``tolerance``, ``t_end``, ``fit``, ``growth_steps``)."""
    started = time.process_time()
    paths = unit_paths(cfg, root)
    for name, path in paths.items():
        if not path.is_file():
            raise SceneError(f"signals.units.{name}: no unit {path} (signals.units_dir: the other tools' units, "
                             "../shared/outside/README.md)")  # fmt: skip
    dmo = DualMass.from_units(paths["system1"], paths["system2"], cfg["start"])
    t_end, steps = float(cfg["t_end"]), int(cfg["growth_steps"])
    by_connections = case["by"] == "connections"
    label = case_label(case)
    runs: dict = {key: [] for key in ("error", "error_end", "predicted_rho", "rho_error", "predicted_verdict")}
    growth: dict = {key: [] for key in ("growth_rho", "growth_rho_error", "growth_verdict", "measured_growth")}
    prediction = None
    with tempfile.TemporaryDirectory(prefix="icosim-signals-") as tmp:
        for h in case["H"]:
            scene = load_scene(write_scene(tmp, scene_data(cfg, case, h, t_end, root=root), f"{label}_{h:.6e}"))
            e, e_end = (signal_errors if by_connections else joint_errors)(scene, dmo)
            if by_connections:
                prediction = prediction or Prediction(scene)
            rho = prediction.at(h) if prediction is not None else (float("nan"), float("nan"), "undecided")
            for key, value in zip(runs, (e, e_end, *rho)):
                runs[key].append(value)
        for h in case.get("growth_H", []):
            scene = load_scene(write_scene(tmp, scene_data(cfg, case, h, steps * h, root=root), f"{label}_g{h:.6e}"))
            prediction = prediction or Prediction(scene)
            with np.errstate(over="ignore", invalid="ignore"):
                run = run_signal_scene(scene)
            x = run.series["system1.x1"] if run.status == "completed" else [np.nan]
            for key, value in zip(growth, (*prediction.at(h), measured_growth(x))):
                growth[key].append(value)
    info = {
        "scheme": scene.scheme.name,
        "amplitude": dmo.amplitude,
        "prediction_reason": prediction.reason if prediction is not None else (
            "the joint's spectral radius is not predicted here (--predict identifies single-mass oscillators; "
            "System2 is a drive by position, velocity and acceleration)"),
        "predicted_H_max": prediction.H_max if prediction is not None else float("nan"),
        "cpu_seconds": time.process_time() - started,
        **{f"dmo_{key}": value for key, value in vars(dmo).items()},
    }  # fmt: skip
    config = {key: cfg[key] for key in ("units", "start", "tolerance", "t_end", "fit", "growth_steps")}
    return case_dataset(case, runs, growth, info, fit=cfg["fit"], t_end=t_end, growth_steps=steps, config=config)


def case_dataset(case: dict, runs: dict, growth: dict, info: dict, *, fit: dict, t_end: float, growth_steps: int,
                 config: dict | None = None) -> DatasetDict:  # fmt: skip
    """The dataset of one case from its numbers: ``runs`` over ``case["H"]`` (``error``, ``error_end``,
    ``predicted_rho``, ``rho_error``, ``predicted_verdict``), ``growth`` over ``case["growth_H"]``
    (``growth_rho``, ``growth_rho_error``, ``growth_verdict``, ``measured_growth``), ``info`` attributes
    (``scheme``, ``amplitude``, ``prediction_reason``, ``predicted_H_max``, ...); the order fitted here."""
    from ...io.netcdf import provenance_attrs

    H = np.array(case["H"], dtype=float)
    fitted = asymptotic_order(H, runs["error"], **dict(fit))
    long = {
        "error": "largest displacement error over the run / amplitude",
        "error_end": "displacement error at t_end / amplitude",
        "predicted_rho": "spectral radius predicted from the units",
        "rho_error": "float64 error estimate of predicted_rho",
        "growth_rho": "spectral radius predicted from the units",
        "measured_growth": "growth per macro step measured on a run",
    }

    def var(dim, key, values):
        strings = key.endswith("verdict")
        array = np.array(values, dtype=str if strings else float)
        return ((dim,), array, {} if strings else {"long_name": long.get(key, key)})

    data = {key: var("H", key, values) for key, values in runs.items()}
    coords = {"H": ("H", H, {"units": "s"})}
    growth_H = np.array(case.get("growth_H", []), dtype=float)
    if growth_H.size:
        data |= {key: var("growth_H", key, values) for key, values in growth.items()}
        coords["growth_H"] = ("growth_H", growth_H, {"units": "s"})
    ds = DatasetDict(data, coords=coords)
    label = case_label(case)
    attrs = provenance_attrs({"case": case, **(config or {})}, title=f"DualMassOscillator: {label}")
    attrs.update(
        part="signals",
        dataset="case",
        case=label,
        by=case["by"],
        k=int(case["k"]),
        implicit="yes" if case.get("implicit") else "no",
        method=case.get("method", "none"),
        t_end=float(t_end),
        growth_steps=int(growth_steps),
        order=float(fitted.order),
        order_status=fitted.status,
        order_spread=float(fitted.spread),
        **info,
    )
    attrs.update({f"param_{key}": value for key, value in case.get("params", {}).items()})
    ds.attrs.update(attrs)
    return ds

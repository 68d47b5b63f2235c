"""The linear convergence study (Sect. 3.7) on the FMU units: one configuration over a list of ``H``, the error
against the exact monolithic solution of the FMU run and of the built-in model, both from the exact start (the
coupling history at ``T_0 ... T_-k`` too), and the asymptotic order of each (:func:`icosim.order_fit.asymptotic_order`,
the linear study's rule).  A dataset of the workflow's FMU part (``fmi_orders``), read by the claims."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from ...engine.decompositions import get_decomposition
from ...engine.methods import engine_method, make_method
from ...engine.run import simulate
from ...io.dataset import DatasetDict
from ...order_fit import asymptotic_order
from ...problems.fmu.problem import FmuCosimulation
from ...problems.fmu.run import open_units
from ...problems.fmu.scene import load_scene
from ...problems.linear.exact import MonolithicSolution, consistent_start
from ...problems.linear.model import PhysicalModel
from ...problems.linear.problem import LinearCosimulation
from .config import case_label

__all__ = ["order_scene", "order_case", "order_case_data"]


def order_scene(tmp: Path, units_dir: Path, model: dict, x0: float, case: dict, H: float, t_end: float) -> Path:
    """The two-mass scene of one configuration at step ``H`` on the msd units (kinematic ones where the
    decomposition says), written into ``tmp``; ``case["scene"]`` adds top-level keys."""
    import yaml

    kinds = get_decomposition(case["decomposition"]).kinds

    def unit(i, kind):
        sub = {
            "start": {"m": model[f"m{i}"], "c": model[f"c{i}"], "d": model[f"d{i}"], "x0": x0},
            "position": "x",
            "velocity": "v",
            "acceleration": "a",
            "force_sign": 1 if i == 1 else -1,
            "mass": "m",
            "set_position": "x_set",
            "set_velocity": "v_set",
        }
        if kind == "force":
            return sub | {"fmu": str(units_dir / "msd"), "force": "lambda"}
        return sub | {"fmu": str(units_dir / "msd_kinematic"), "acceleration_input": "a_in", "reaction_force": "F"}

    coupling = {k: case[k] for k in ("method", "decomposition", "k")} | {"scheme": case.get("scheme", "jacobi")}
    scene = {
        "subsystems": {"body1": unit(1, kinds[0]), "body2": unit(2, kinds[1])},
        "coupling": coupling | {"H": float(H), "perturbation": 1.0} | dict(case.get("params", {})),
        "t_end": float(t_end),
    } | dict(case.get("scene", {}))
    path = tmp / f"order_{H:.6e}.yaml"
    path.write_text(yaml.safe_dump(scene))
    return path


def _fmu_states(scene, history, *, cache=None) -> np.ndarray:
    """The FMU run of ``scene`` from the given coupling history (SI): states ``(n + 1, 2, 2)``, SI, ending early
    where the run diverges."""
    c = scene.coupling
    units, couplings = open_units(scene, cache=cache)
    problem = None
    try:
        problem = FmuCosimulation(units, couplings, c["decomposition"], c["k"], c["H"], perturbation=c["perturbation"])
        with np.errstate(over="ignore", invalid="ignore"):
            traj = simulate(problem, scene.method, problem.initial_state(), history, scene.n_steps, scheme=c["scheme"])
        if traj.failed_at is not None:
            raise traj.error
        return np.array(traj.states)
    finally:
        if problem is not None:
            problem.close()
        for unit in units:
            unit.close()


def order_case(case: dict, **kwargs):
    """:func:`order_case_data` as an :class:`xarray.Dataset`."""
    return order_case_data(case, **kwargs).to_xarray()


def order_case_data(case: dict, *, H, t_end: float, model: dict, x0: float, units_dir, cache=None, fit=None):
    """Errors over ``H`` of one configuration of the linear convergence study on the FMU units and on the
    built-in model, both from the exact start, and the asymptotic order of each.

    ``case``: ``method``, ``decomposition``, ``k``, ``scheme`` (default Jacobi), ``params`` (the method's,
    dimensional).  The error is the largest position error of either body against the exact monolithic
    solution over ``[0, t_end]`` (m).  ``fit``: :func:`~icosim.order_fit.asymptotic_order`'s options."""
    from ...io.netcdf import provenance_attrs

    fit = dict(fit or {})
    H = np.asarray(sorted(float(h) for h in H), dtype=float)
    err_fmu, err_builtin, diff = [], [], []
    with tempfile.TemporaryDirectory(prefix="icosim-orders-") as tmp:
        for h in H:
            scene = load_scene(order_scene(Path(tmp), Path(units_dir).resolve(), model, x0, case, h, t_end))
            coeffs = PhysicalModel(H=h, **model).coefficients()
            problem = LinearCosimulation(coeffs, case["decomposition"], case["k"])
            solution = MonolithicSolution(coeffs, x0, 0.0)
            state, history = consistent_start(problem, solution)
            method = engine_method(make_method(case["method"], **case.get("params", {})), h)
            traj = simulate(problem, method, state, history, scene.n_steps, scheme=scene.coupling["scheme"])
            builtin = np.array(traj.states)[..., 0]  # (n + 1, 2)
            dec = get_decomposition(case["decomposition"])
            scale = np.array([model["m1"] / h**2 if v == "lambda_c" else 1 / h**2 for v in dec.variables])
            fmu = _fmu_states(scene, np.asarray(history) * scale, cache=cache)[..., 0]
            exact = solution.state(np.arange(scene.n_steps + 1, dtype=float))[:, :1]
            with np.errstate(invalid="ignore", over="ignore"):
                err_fmu.append(float(np.max(np.abs(fmu - exact[: len(fmu)]))) if len(fmu) == len(exact) else np.nan)
                err_builtin.append(float(np.max(np.abs(builtin - exact))))
                diff.append(float(np.max(np.abs(fmu - builtin[: len(fmu)])) / max(1.0, np.max(np.abs(builtin)))))
    f_fmu, f_builtin = asymptotic_order(H, err_fmu, **fit), asymptotic_order(H, err_builtin, **fit)
    ds = DatasetDict(
        {
            "error_fmu": (("H",), np.array(err_fmu), {"units": "m", "long_name": "largest position error, FMU run"}),
            "error_builtin": (("H",), np.array(err_builtin), {"units": "m", "long_name": "the same, built-in model"}),
            "difference": (("H",), np.array(diff), {"comment": "FMU minus built-in positions, relative"}),
        },
        coords={"H": ("H", H, {"units": "s"})},
    )
    attrs = provenance_attrs(
        {"case": case, "H": H.tolist(), "t_end": t_end, "model": model, "x0": x0, "fit": fit},
        title=f"FMU units: convergence order of {case_label(case)}",
    )
    params = {k: v for k, v in case.get("params", {}).items()}
    attrs.update(
        part="fmi",
        dataset="orders",
        case=case_label(case),
        method=case["method"],
        decomposition=case["decomposition"],
        k=int(case["k"]),
        scheme=case.get("scheme", "jacobi"),
        **params,
        t_end=float(t_end),
        order_fmu=float(f_fmu.order),
        order_builtin=float(f_builtin.order),
        status_fmu=f_fmu.status,
        status_builtin=f_builtin.status,
    )
    ds.attrs.update(attrs)
    return ds

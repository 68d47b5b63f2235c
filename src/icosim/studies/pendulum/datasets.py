"""The NetCDF contract of the pendulum's runs and of the monolithic reference.

Series over ``t`` (:data:`~icosim.problems.pendulum.names.VARIABLES`) with the run's
status, method, decomposition, ``k``, settings and counts as attributes.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ...engine.methods import CouplingMethod, make_method, parameter_units
from ...engine.schemes import get_scheme
from ...io.dataset import DatasetDict
from ...io.netcdf import provenance_attrs
from ...problems.pendulum.model import PendulumParameters, joint_constraint
from ...problems.pendulum.names import VARIABLES
from ...problems.pendulum.reference import Monolithic, reference_solution
from ...problems.pendulum.runs import RunResult, run_cosimulation

__all__ = [
    "run_dataset",
    "run_dataset_data",
    "reference_dataset",
    "reference_dataset_data",
    "run_job",
    "run_job_data",
]


def _series_dataset(t, series, attrs) -> DatasetDict:
    data_vars = {}
    for name, values in series.items():
        if name in VARIABLES:
            units, long_name = VARIABLES[name]
        else:  # the constraint after the corrector, before a projection
            units, long_name = (
                "m",
                VARIABLES[name.replace("_corrector", "")][1] + " after the corrector (before projection)",
            )
        data_vars[name] = ("t", np.asarray(values, dtype=float), {"units": units, "long_name": long_name})
    coords = {"t": ("t", np.asarray(t, dtype=float), {"units": "s", "long_name": "time", "standard_name": "time"})}
    return DatasetDict(data_vars, coords=coords, attrs=attrs)


def run_dataset(
    result: RunResult, method: CouplingMethod, decomposition: str, k: int, settings, provenance, scheme="jacobi"
):
    """:func:`run_dataset_data` as an :class:`xarray.Dataset`."""
    return run_dataset_data(result, method, decomposition, k, settings, provenance, scheme).to_xarray()


def run_dataset_data(
    result: RunResult,
    method: CouplingMethod,
    decomposition: str,
    k: int,
    settings: dict,
    provenance: dict,
    scheme: str = "jacobi",
) -> DatasetDict:
    """The NetCDF contract of a co-simulation run (README, the pendulum's datasets): series over ``t`` and attributes.

    ``scheme`` is the coupling scheme's name (attribute ``scheme``).

    ``settings`` (H, t_end, tolerances, ...) are copied into the attributes; ``None`` values are
    written as the string ``"none"`` (NetCDF attributes cannot be empty).
    """
    attrs = dict(provenance)
    attrs.update(
        method=method.name,
        decomposition=decomposition,
        k=int(k),
        scheme=get_scheme(scheme).name,
        status=result.status,
        reason=result.reason or "none",
        diverged=int(result.diverged),
        t_diverged=float(result.t_diverged),
        failed=int(result.failed),
        t_failed=float(result.t_failed),
        wall_time_s=float(result.wall_time),
        sensitivities=(
            "forward differences w.r.t. e_N+1, step fd_step * max(1, |e_j|), in one batched Radau call per link "
            "(shared step sequence); the corrector "
            "integrates alone with its own step sequence, which differs from the batch's only in the "
            f"n_split = {int(result.stats.get('split', 0))} integrations that took more than one step "
            "(then an O(rtol) mismatch between linearisation and corrector)"
        ),
    )
    units = parameter_units()  # of the registered methods' parameters, not of the index
    for key, value in method.params.items():
        attrs[f"method_{key}"] = value
        if key in units:  # SI units: unlike the stability datasets' dimensionless mu_bar = mu/H
            attrs[f"method_{key}_units"] = units[key]
    for key, value in settings.items():
        attrs[key] = "none" if value is None else value
    for key, value in result.stats.items():
        attrs[f"n_{key}"] = int(value)
    return _series_dataset(result.t, result.series, attrs)


def reference_dataset(params: PendulumParameters, H: float, t_end: float, provenance: dict, **solver):
    """:func:`reference_dataset_data` as an :class:`xarray.Dataset`."""
    return reference_dataset_data(params, H, t_end, provenance, **solver).to_xarray()


def reference_dataset_data(
    params: PendulumParameters, H: float, t_end: float, provenance: dict, *, method="DOP853", rtol=1e-12, atol=1e-12
) -> DatasetDict:
    """The monolithic reference on the macro-time grid, stored like a run (``method = "monolithic"``)."""
    n = int(round(t_end / H))
    t = H * np.arange(n + 1)
    t0 = time.perf_counter()
    ref = reference_solution(params, t, method=method, rtol=rtol, atol=atol)
    wall = time.perf_counter() - t0
    mono = Monolithic(params)
    states = np.array(
        [mono.cosim_state(Y) for Y in np.stack([ref["phi1"], ref["phi2"], ref["omega1"], ref["omega2"]], axis=-1)]
    )
    g = joint_constraint(params, states)
    series = {
        "phi1": ref["phi1"],
        "phi2": ref["phi2"],
        "g_cax": g[:, 0],
        "g_cay": g[:, 1],
        "lambda_cax": ref["lambda_cax"],
        "lambda_cay": ref["lambda_cay"],
    }
    attrs = dict(provenance)
    attrs.update(
        method="monolithic",
        decomposition="none",
        k=-1,
        status="stable",
        diverged=0,
        t_diverged=math.nan,
        failed=0,
        t_failed=math.nan,
        integrator=f"scipy solve_ivp {method}",
        rtol=rtol,
        atol=atol,
        H=H,
        t_end=t_end,
        formulation="minimal coordinates phi1, phi2 (joint constraint satisfied exactly)",  # not "coordinates": CF reserves it
        wall_time_s=wall,
    )
    return _series_dataset(t, series, attrs)


def run_job(job: dict, *, command: str = ""):
    """:func:`run_job_data` with the dataset as an :class:`xarray.Dataset`."""
    result, data = run_job_data(job, command=command)
    return result, data.to_xarray()


def run_job_data(job: dict, *, command: str = "") -> tuple[RunResult, DatasetDict]:
    """One run as the workflow describes it (``job``: method, decomposition, k, method_params, model, H,
    t_end, integrator, sensitivities, corrector, divergence) -> ``(RunResult, dataset)``.

    The dataset's provenance holds ``job`` itself, so the file can be traced to it.
    """
    method = make_method(job["method"], **job["method_params"])
    integ, sens, corr, div = (job[key] for key in ("integrator", "sensitivities", "corrector", "divergence"))
    result = run_cosimulation(
        PendulumParameters(**job["model"]),
        method,
        job["decomposition"],
        job["k"],
        H=job["H"],
        t_end=job["t_end"],
        **integ,
        **sens,
        **corr,
        **div,
        scheme=job.get("scheme", "jacobi"),
    )
    settings = {
        "H": job["H"],
        "t_end": job["t_end"],
        "integrator": "Radau IIA (3 stages, order 5), icosim.problems.pendulum.integrator.compiled, batched",
        "rtol": integ["rtol"],
        "atol": integ["atol"],
        "newton_tol": integ["newton_tol"],
        "fd_step": sens["fd_step"],
        "corrector_iterations": corr["iterations"],
        "corrector_tol": corr["tol"],
        **{f"bound_{key}": value for key, value in div.items()},
    }
    scheme = get_scheme(job.get("scheme", "jacobi"))
    title = f"Double pendulum (Sect. 4): {job['method']} {job['decomposition']} k = {job['k']}"
    if scheme.name != "jacobi":
        title += f", {scheme.label}"
    provenance = provenance_attrs(job, title=title, command=command)
    return result, run_dataset_data(result, method, job["decomposition"], job["k"], settings, provenance, scheme.name)

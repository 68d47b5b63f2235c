"""Baselines of the work-precision comparison: the monolithic pendulum over tolerances, and the linear
test model's errors over H for every configuration (for the orders).

* :func:`monolithic_baselines` -- the monolithic pendulum (minimal
  coordinates, :class:`~.reference.Monolithic`) over tolerances with the
  links' integrator (Radau IIA, :func:`icosim.problems.pendulum.integrator.systems.monolithic_radau`, one
  call over ``[0, T]``) and with scipy's DOP853; error at the integrator's own
  accepted steps (as a co-simulation's at its macro nodes), CPU seconds the
  least of ``repeats`` runs after a warm-up.
* :func:`linear_orders_dataset` -- :func:`.linear_study.linear_errors` for
  every configuration.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ...io.dataset import DatasetDict
from ...io.netcdf import provenance_attrs
from ...problems.pendulum.integrator.systems import monolithic_radau
from ...problems.pendulum.model import PendulumParameters
from ...problems.pendulum.reference import Monolithic, reference_solution
from .measures import angle_errors

__all__ = [
    "monolithic_run",
    "monolithic_baselines",
    "monolithic_baselines_data",
    "linear_orders_dataset",
    "linear_orders_dataset_data",
    "reference_accuracy",
    "INTEGRATORS",
]

#: Monolithic integrators of the baseline: the links' own Radau IIA and scipy's DOP853.
INTEGRATORS = ("Radau", "DOP853")


def reference_accuracy(params: PendulumParameters, t_end: float, reference: dict, n: int = 201) -> float:
    """Estimated error of the reference: ``max |phi - phi'|`` over ``n`` times in ``[0, t_end]``, where
    ``phi'`` is the same integrator at the same tolerances forced to at least 100 steps (``max_step``).

    A second step sequence at the same tolerance measures the error the
    reference actually has (for DOP853 at 3e-14: about 2e-14 rad, the plateau
    the co-simulation errors reach); a ten times looser tolerance would
    measure its own, ten times larger error instead.
    """
    import warnings

    from scipy.integrate import solve_ivp

    mono = Monolithic(params)
    t = np.linspace(0.0, t_end, n)
    kw = dict(method=reference["method"], rtol=reference["rtol"], atol=reference["atol"], t_eval=t)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # scipy clips rtol below 100 eps and says so
        a = solve_ivp(mono.rhs, (0.0, t_end), mono.initial_state(), **kw)
        b = solve_ivp(mono.rhs, (0.0, t_end), mono.initial_state(), max_step=t_end / 100, **kw)
    return float(np.max(np.abs(a.y[:2] - b.y[:2])))


def monolithic_run(params: PendulumParameters, integrator: str, tol: float, t_end: float) -> dict:
    """One monolithic solve over ``[0, t_end]`` at ``rtol = atol = tol``: ``t, phi1, phi2`` at the accepted
    steps and the counts (``n_steps``, ``n_rhs_evaluations``, ``n_jacobian_evaluations``)."""
    mono = Monolithic(params)
    y0 = mono.initial_state()
    if integrator == "Radau":
        r = monolithic_radau(params, 0.0, t_end, y0, rtol=tol, atol=tol, record_steps=True)
        Y = r.y_steps[:, 0, :]
        return dict(
            t=r.t_steps,
            phi1=Y[:, 0],
            phi2=Y[:, 1],
            n_steps=r.n_steps,
            n_rhs_evaluations=r.n_fev,
            n_jacobian_evaluations=r.n_jev,
        )
    if integrator == "DOP853":
        from scipy.integrate import solve_ivp

        sol = solve_ivp(mono.rhs, (0.0, t_end), y0, method="DOP853", rtol=tol, atol=tol)
        if not sol.success:
            raise RuntimeError(f"DOP853 failed: {sol.message}")
        return dict(
            t=sol.t,
            phi1=sol.y[0],
            phi2=sol.y[1],
            n_steps=sol.t.size - 1,
            n_rhs_evaluations=sol.nfev,
            n_jacobian_evaluations=sol.njev,
        )
    raise ValueError(f"integrator must be one of {', '.join(INTEGRATORS)}, got {integrator!r}")


def monolithic_baselines(*args, **kwargs):
    """:func:`monolithic_baselines_data` as an :class:`xarray.Dataset`."""
    return monolithic_baselines_data(*args, **kwargs).to_xarray()


def monolithic_baselines_data(
    params: PendulumParameters, tolerances, t_end: float, *, reference: dict, repeats: int = 3, command=""
) -> DatasetDict:
    """Every integrator of :data:`INTEGRATORS` at every tolerance -> dataset over ``(integrator, tol)``."""
    import warnings

    tols = sorted((float(t) for t in tolerances), reverse=True)
    names = ("error_max", "error_rms", "cpu_seconds", "n_steps", "n_rhs_evaluations", "n_jacobian_evaluations")
    data = {name: np.full((len(INTEGRATORS), len(tols)), np.nan) for name in names}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # scipy clips rtol below 100 eps and says so
        for i, integ in enumerate(INTEGRATORS):
            for j, tol in enumerate(tols):
                out = monolithic_run(params, integ, tol, t_end)  # warm-up, and the result
                best = math.inf
                for _ in range(max(1, repeats)):
                    c0 = time.process_time()
                    monolithic_run(params, integ, tol, t_end)
                    best = min(best, time.process_time() - c0)
                ref = reference_solution(params, out["t"], **reference)
                data["error_max"][i, j], data["error_rms"][i, j] = angle_errors(out["t"], out["phi1"], out["phi2"], ref)
                data["cpu_seconds"][i, j] = best
                for name in names[3:]:
                    data[name][i, j] = out[name]
    units = {"error_max": "rad", "error_rms": "rad", "cpu_seconds": "s"}
    long = {
        "error_max": "max |phi_i - phi_i,ref| at the integrator's accepted steps",
        "error_rms": "time-weighted RMS of phi1, phi2 errors at the accepted steps",
        "cpu_seconds": "CPU seconds of one solve (least of repeats after a warm-up)",
        "n_steps": "accepted steps",
        "n_rhs_evaluations": "right-hand side evaluations",
        "n_jacobian_evaluations": "Jacobian evaluations",
    }
    variables = {
        name: (("integrator", "tol"), arr, {"units": units.get(name, "1"), "long_name": long[name]})
        for name, arr in data.items()
    }
    job = {"tolerances": tols, "t_end": t_end, "reference": reference, "repeats": repeats}
    attrs = provenance_attrs(job, title="Double pendulum: monolithic baselines", command=command)
    attrs.update(
        t_end=float(t_end),
        radau="icosim.problems.pendulum.integrator.systems.monolithic_radau (the links' integrator)",
        dop853="scipy solve_ivp",
        reference_method=reference["method"],
        reference_rtol=float(reference["rtol"]),
        reference_accuracy=reference_accuracy(params, t_end, reference),
    )
    return DatasetDict(
        variables, coords={"integrator": ("integrator", list(INTEGRATORS)), "tol": ("tol", tols)}, attrs=attrs
    )


def linear_orders_dataset(*args, **kwargs):
    """:func:`linear_orders_dataset_data` as an :class:`xarray.Dataset`."""
    return linear_orders_dataset_data(*args, **kwargs).to_xarray()


def linear_orders_dataset_data(
    settings: dict, configurations, H_values, *, model: dict, x0: float, t_end: float, command=""
) -> DatasetDict:
    """Errors of the linear test model (:func:`.linear_study.linear_errors`) for every configuration -> dataset.

    ``configurations``: ``(label, scheme, method, decomposition, k)`` (as :func:`~.config.trade_plan` gives them);
    the linear model is co-simulated with the same scheme."""
    from ...engine.methods import make_method
    from .linear_study import linear_errors

    labels, err, unst, rho, nsteps = [], [], [], [], []
    H_values = [float(h) for h in H_values]
    for label, scheme, method, decomposition, k in configurations:
        e, u, r = linear_errors(
            model,
            make_method(method, **settings["methods"][method]),
            decomposition,
            k,
            H_values,
            t_end,
            x0,
            scheme=scheme,
        )
        labels.append(label)
        err.append(e)
        unst.append(u)
        rho.append(r)
        nsteps.append([max(1, math.ceil(t_end / h - 1e-9)) for h in H_values])
    job = {"configurations": [list(c) for c in configurations], "H": H_values, "model": model, "x0": x0, "t_end": t_end}
    attrs = provenance_attrs(job, title="Linear test model (Sect. 3.7) at the pendulum's step sizes", command=command)
    attrs.update(model_json=str(model), x0=float(x0), t_end=float(t_end))
    dims = ("config", "H")
    return DatasetDict(
        {
            "error_linear": (
                dims,
                np.array(err),
                {"units": "1", "long_name": "max |x_i - x| / x0 of the linear test model (Sect. 3.7), same scheme"},
            ),
            "unstable_linear": (
                dims,
                np.array(unst).astype("int8"),
                {
                    "long_name": "1 where the verdict is not stable (unstable, marginal or undecided) or the run not finite"
                },
            ),
            "rho_linear": (dims, np.array(rho), {"long_name": "spectral radius of the linear test model (Sect. 3.7)"}),
            "n_steps_linear": (dims, np.array(nsteps), {"long_name": "macro steps over t_end"}),
        },
        coords={"config": ("config", labels), "H": ("H", H_values, {"units": "s"})},
        attrs=attrs,
    )

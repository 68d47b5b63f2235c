"""Adaptive against fixed macro steps at equal error (the study around :func:`icosim.problems.pendulum.runs.run_adaptive`).

For each configured configuration, adaptive runs over a list of tolerances
and fixed-H runs over a list of step sizes cover the same horizon
(:func:`adaptive_study`).  :func:`fixed_at_error` reads off the fixed-H curve
how many macro steps (and CPU seconds) a fixed ``H`` needs for the error an
adaptive run reached: log-log interpolation between the two neighbouring
stable step sizes that bracket that error, never extrapolated (outside the
bracket the result says ``"not bracketed"``).  The adaptive run's cost in
macro steps counts its rejected attempts too.
"""

from __future__ import annotations

import math

import numpy as np

from ...engine.methods import make_method
from ...io.dataset import DatasetDict
from ...io.netcdf import provenance_attrs
from ...problems.pendulum.model import PendulumParameters
from ...problems.pendulum.reference import reference_solution
from ...problems.pendulum.runs import run_adaptive
from .measures import RECORD, angle_errors, check_scheme, config_label, measured_run

__all__ = ["adaptive_record", "fixed_at_error", "adaptive_study", "adaptive_study_data"]


def adaptive_record(result, reference) -> dict:
    """The :data:`~.measures.RECORD` of an adaptive run plus its step statistics."""
    s = result.series
    err_max, err_rms = angle_errors(result.t, s["phi1"], s["phi2"], reference)
    st, jac = result.stats, result.jacobian_stats
    H = result.H if result.H.size else np.array([math.nan])
    return {
        "status": result.status,
        "reason": result.reason,
        "error_max": err_max,
        "error_rms": err_rms,
        "drift_max": float(np.max(np.hypot(s["g_cax"], s["g_cay"]))),
        "drift_corrector_max": float(np.max(np.hypot(s["g_cax_corrector"], s["g_cay_corrector"]))),
        "cpu_seconds": float(result.cpu_seconds),
        "n_macro_steps": int(result.H.size),
        "n_subsystem_steps": int(st["steps"]),
        "n_rhs_evaluations": int(st["fev"] + jac.get("fev", 0)),
        "n_jacobian_evaluations": int(jac.get("jev", 0)),
        "n_integrations": int(st["integrations"]),
        "n_rejected": int(st["rejected"]),
        "t_last": float(result.t[-1]),
        "n_rejected_macro_steps": int(result.n_rejected),
        "H_min_used": float(np.min(H)),
        "H_median_used": float(np.median(H)),
        "H_max_used": float(np.max(H)),
    }


def fixed_at_error(H, error, n_steps, cpu, target: float):
    """Macro steps and CPU seconds of a fixed ``H`` at the error ``target`` (module docstring).

    Returns ``(n, cpu, how)``: ``how`` is ``"interpolated"``, ``"not bracketed"``
    (``target`` outside the stable errors of the curve: ``n``, ``cpu`` NaN).
    """
    H, e, n, c = (np.asarray(a, float) for a in (H, error, n_steps, cpu))
    ok = np.isfinite(e) & (e > 0)
    if not (np.isfinite(target) and target > 0) or ok.sum() < 2:
        return math.nan, math.nan, "not bracketed"
    order = np.argsort(H[ok])[::-1]  # largest H (cheapest) first
    He, ee, ne, ce = H[ok][order], e[ok][order], n[ok][order], c[ok][order]
    for i in range(len(He) - 1):
        lo, hi = ee[i + 1], ee[i]  # smaller H has the smaller error (if the curve is monotone here)
        if lo <= target <= hi and hi > lo:
            w = (math.log(target) - math.log(hi)) / (math.log(lo) - math.log(hi))
            n_t = math.exp(math.log(ne[i]) + w * (math.log(ne[i + 1]) - math.log(ne[i])))
            c_t = math.exp(math.log(ce[i]) + w * (math.log(ce[i + 1]) - math.log(ce[i])))
            return n_t, c_t, "interpolated"
    return math.nan, math.nan, "not bracketed"


def adaptive_study(settings: dict, study: dict, *, reference: dict, command: str = "", log=None):
    """:func:`adaptive_study_data` as an :class:`xarray.Dataset`."""
    return adaptive_study_data(settings, study, reference=reference, command=command, log=log).to_xarray()


def adaptive_study_data(settings: dict, study: dict, *, reference: dict, command: str = "", log=None) -> DatasetDict:
    """Adaptive and fixed-H runs of every configuration of ``study`` -> the ``adaptive.nc`` dataset.

    ``study``: ``t_end``, ``drift_tol``, ``H0``, ``controller`` (settings of
    :class:`~icosim.engine.control.controller.StepController`), ``H_fixed`` (list) and
    ``configurations`` (each ``method``, ``decomposition``, ``k``, ``tol``
    list, optional ``scheme``).
    """
    params = PendulumParameters(**settings["model"])
    T = float(study["t_end"])
    confs = study["configurations"]
    tols = sorted({float(t) for c in confs for t in c["tol"]}, reverse=True)
    H_fixed = sorted(float(h) for h in study["H_fixed"])
    labels = []
    adaptive = {}
    fixed = {}
    steps = {}
    for c in confs:
        scheme = check_scheme(c.get("scheme", "jacobi"))
        label = config_label(scheme, c["method"], c["decomposition"], c["k"])
        labels.append(label)
        method = make_method(c["method"], **settings["methods"][c["method"]])
        for tol in c["tol"]:
            res = run_adaptive(
                params,
                method,
                c["decomposition"],
                int(c["k"]),
                t_end=T,
                tol=float(tol),
                drift_tol=float(study["drift_tol"]),
                H0=float(study["H0"]),
                controller=study["controller"],
                **settings["integrator"],
                **settings["sensitivities"],
                iterations=settings["corrector"]["iterations"],
                corrector_tol=settings["corrector"]["tol"],
                **settings["divergence"],
                scheme=scheme,
            )
            rec = adaptive_record(res, reference_solution(params, res.t, **reference))
            adaptive[(label, float(tol))] = rec
            steps[(label, float(tol))] = (res.t[1:], res.H)
            if log:
                log("adaptive", label, tol, rec)
        for H in H_fixed:
            rec = measured_run(
                settings, scheme, c["method"], c["decomposition"], int(c["k"]), H, T, reference=reference, repeats=1
            )
            fixed[(label, H)] = rec
            if log:
                log("fixed", label, H, rec)
    n_max = max((len(v[1]) for v in steps.values()), default=0)
    shape = (len(labels), len(tols))
    data = {}
    names = list(RECORD) + ["n_rejected_macro_steps", "H_min_used", "H_median_used", "H_max_used"]
    extra = {
        "n_rejected_macro_steps": ("1", "rejected macro steps (retried with a smaller H)"),
        "H_min_used": ("s", "smallest accepted macro step"),
        "H_median_used": ("s", "median accepted macro step"),
        "H_max_used": ("s", "largest accepted macro step"),
    }
    for name in names:
        arr = np.full(shape, np.nan)
        for i, lab in enumerate(labels):
            for j, tol in enumerate(tols):
                if (lab, tol) in adaptive:
                    arr[i, j] = adaptive[(lab, tol)][name]
        units, long_name = RECORD.get(name) or extra[name]
        data[name] = (("config", "tol"), arr, {"units": units, "long_name": long_name})
    data["n_macro_steps"][2]["long_name"] = "accepted macro steps"
    data["status"] = (
        ("config", "tol"),
        np.array([[adaptive.get((lab, t), {}).get("status", "") for t in tols] for lab in labels], dtype=str),
        {"long_name": "stable, diverged or failed ('' where the tolerance is not configured)"},
    )
    step_t = np.full(shape + (n_max,), np.nan)
    step_H = np.full(shape + (n_max,), np.nan)
    for (lab, tol), (t, H) in steps.items():
        i, j = labels.index(lab), tols.index(tol)
        step_t[i, j, : len(t)] = t
        step_H[i, j, : len(H)] = H
    data["step_t"] = (("config", "tol", "step"), step_t, {"units": "s", "long_name": "end time of each accepted step"})
    data["step_H"] = (("config", "tol", "step"), step_H, {"units": "s", "long_name": "size of each accepted step"})
    for name in ("error_max", "error_rms", "cpu_seconds", "n_macro_steps", "drift_max"):
        arr = np.full((len(labels), len(H_fixed)), np.nan)
        for i, lab in enumerate(labels):
            for j, H in enumerate(H_fixed):
                arr[i, j] = fixed[(lab, H)][name]
        data[f"fixed_{name}"] = (
            ("config", "H_fixed"),
            arr,
            {"units": RECORD[name][0], "long_name": f"fixed H: {RECORD[name][1]}"},
        )
    data["fixed_status"] = (
        ("config", "H_fixed"),
        np.array([[fixed[(lab, H)]["status"] for H in H_fixed] for lab in labels], dtype=str),
        {"long_name": "fixed H: stable, diverged or failed"},
    )
    ds = DatasetDict(
        data,
        coords={
            "config": ("config", labels),
            "tol": ("tol", tols, {"long_name": "tolerance of the predictor-corrector estimate"}),
            "H_fixed": ("H_fixed", H_fixed, {"units": "s"}),
            "method": ("config", [c["method"] for c in confs]),
            "decomposition": ("config", [c["decomposition"] for c in confs]),
            "k": ("config", [int(c["k"]) for c in confs]),
            "scheme": ("config", [check_scheme(c.get("scheme", "jacobi")) for c in confs]),
        },
    )
    ds = add_equal_error(ds)
    job = {"study": study, "settings": settings, "reference": reference}
    ds.attrs.update(provenance_attrs(job, title="Double pendulum: adaptive macro-step control", command=command))
    ds.attrs.update(
        t_end=T,
        drift_tol=float(study["drift_tol"]),
        H0=float(study["H0"]),
        controller_json=str(study["controller"]),
        estimate="max_j |e_c,j - e_p,j| / (tol (1 + |e_c,j|)): predictor-corrector difference of the coupling variables",
    )
    return ds


def add_equal_error(ds: DatasetDict) -> DatasetDict:
    """``ds`` with the fixed-H macro steps and CPU seconds at each adaptive run's error (:func:`fixed_at_error`)."""
    v = ds.array
    n_eq = np.full((ds.sizes["config"], ds.sizes["tol"]), np.nan)
    c_eq = np.full_like(n_eq, np.nan)
    how = np.full(n_eq.shape, "", dtype=object)
    for i in range(ds.sizes["config"]):
        stable = v("fixed_status")[i] == "stable"
        e_fixed = np.where(stable, v("fixed_error_max")[i], np.nan)
        for j in range(ds.sizes["tol"]):
            if str(v("status")[i, j]) != "stable":
                continue
            n_eq[i, j], c_eq[i, j], how[i, j] = fixed_at_error(
                v("H_fixed"),
                e_fixed,
                v("fixed_n_macro_steps")[i],
                v("fixed_cpu_seconds")[i],
                float(v("error_max")[i, j]),
            )

    def specs(group):
        return {name: (var["dims"], var["data"], var["attrs"]) for name, var in ds[group].items()}

    data = specs("data_vars")
    data["n_macro_steps_fixed_equal_error"] = (
        ("config", "tol"),
        n_eq,
        {"long_name": "macro steps of a fixed H with the same error_max (log-log interpolation)"},
    )
    data["cpu_seconds_fixed_equal_error"] = (
        ("config", "tol"),
        c_eq,
        {"units": "s", "long_name": "CPU seconds of a fixed H with the same error_max (log-log interpolation)"},
    )
    data["equal_error_how"] = (("config", "tol"), how.astype(str), {"long_name": "interpolated or not bracketed"})
    return DatasetDict(data, coords=specs("coords"), attrs=ds.attrs)

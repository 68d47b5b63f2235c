"""A convergence panel as a NetCDF-ready dataset (dims ``index``, ``k``, ``H``, ``H_mid``).

Variables: ``nrmse`` (NaN where unstable) and its parts, ``unstable``,
``spectral_radius`` with the digits that decided it, ``diverged_at``, the
precision that proved each run's defect (``defect_bits``); the local slopes
between neighbouring step sizes over ``H_mid``; per curve the asymptotic
``order`` read off the smallest-H decade with its ``order_status``
(:mod:`icosim.order_fit`) and range (``fit_H_min``, ``fit_H_max``,
``fit_used``); the row parameters (dimensional) as coordinates along
``index``; the set-up, the method and the procedures as attributes.
"""

from __future__ import annotations

import time

import numpy as np

from ...engine.decompositions import get_decomposition
from ...engine.methods import get_spec, parameter_units, parameters
from ...io.dataset import DatasetDict
from ...order_fit import asymptotic_order, local_slopes
from .curves import curve_label
from .experiment import PAPER_MODEL, dimensional_method, units_description
from .panels import PanelSpec
from .study import Study

__all__ = ["run_panel", "run_panel_data", "curve_summaries"]


def run_panel(
    spec: PanelSpec, study: Study, fit: dict | None = None, *, stepping: str = "error", provenance: dict | None = None
):
    """Every curve of a panel as an :class:`xarray.Dataset` (dims ``index``, ``k``, ``H``; :func:`run_panel_data`)."""
    return run_panel_data(spec, study, fit, stepping=stepping, provenance=provenance).to_xarray()


def run_panel_data(
    spec: PanelSpec, study: Study, fit: dict | None = None, *, stepping: str = "error", provenance: dict | None = None
) -> DatasetDict:
    """Every curve of a panel as a :class:`~icosim.io.dataset.DatasetDict` (what :func:`run_panel` converts)."""
    fit = dict(fit or {})
    t0 = time.perf_counter()
    nI, nK, nH = len(spec.rows), len(spec.k), study.H.size
    names_f = (
        "nrmse",
        "nrmse_unfiltered",
        "nrmse_second_half",
        "nrmse_startup",
        "nrmse_x",
        "nrmse_v",
        "nrmse_lambda",
        "spectral_radius",
    )
    arr = {n: np.full((nI, nK, nH), np.nan) for n in names_f}
    arr["spectral_radius_digits"] = np.zeros((nI, nK, nH), dtype=np.int32)
    arr["spectral_verdict"] = np.full((nI, nK, nH), "", dtype=object)
    arr["diverged_at"] = np.full((nI, nK, nH), -1, dtype=np.int64)
    arr["unstable"] = np.zeros((nI, nK, nH), dtype=bool)
    arr["fit_used"] = np.zeros((nI, nK, nH), dtype=bool)
    arr["defect_bits"] = np.zeros((nI, nK, nH), dtype=np.int32)
    slopes = {n: np.full((nI, nK, nH - 1), np.nan) for n in ("local_slope", "local_slope_second_half")}
    fits = {
        n: np.full((nI, nK), np.nan)
        for n in ("order", "order_spread", "fit_H_min", "fit_H_max", "order_second_half", "order_startup")
    }
    status = {n: np.full((nI, nK), "", dtype=object) for n in ("order_status", "fit_note")}
    fit_n = np.zeros((nI, nK), dtype=np.int32)
    H_mid = None
    for j, k in enumerate(spec.k):
        # the rows of one k stepped together (Study.run_curves: the numbers of each curve alone)
        rows = study.run_curves(spec.method, spec.rows, spec.decomposition, k, stepping=stepping, scheme=spec.scheme)
        for i, r in enumerate(rows):
            for n in names_f + ("spectral_radius_digits", "spectral_verdict", "diverged_at", "unstable", "defect_bits"):
                arr[n][i, j] = getattr(r, n)
            f = asymptotic_order(r.H, r.nrmse, r.unstable, **fit)
            arr["fit_used"][i, j] = f.used
            fits["order"][i, j], fits["order_spread"][i, j] = f.order, f.spread
            fits["fit_H_min"][i, j], fits["fit_H_max"][i, j] = f.H_min, f.H_max
            fits["order_second_half"][i, j] = asymptotic_order(r.H, r.nrmse_second_half, r.unstable, **fit).order
            fits["order_startup"][i, j] = asymptotic_order(r.H, r.nrmse_startup, r.unstable, **fit).order
            status["order_status"][i, j], status["fit_note"][i, j] = f.status, f.reason
            fit_n[i, j] = f.n_points
            # local slopes in the dataset's H order (decreasing H), between neighbouring step sizes
            H_mid, s_all = local_slopes(r.H, r.nrmse)
            slopes["local_slope"][i, j] = s_all[::-1]
            slopes["local_slope_second_half"][i, j] = local_slopes(r.H, r.nrmse_second_half)[1][::-1]
    H_mid = H_mid[::-1]
    dims3, dims2, dims_mid = ("index", "k", "H"), ("index", "k"), ("index", "k", "H_mid")
    H_attrs = {"long_name": "macro-step size", "units": "s"}
    # row parameters (dimensional) as coordinates along index
    units = parameter_units(index=True)
    row_coords = {}
    for name in get_spec(spec.method).coordinates:
        vals = [dimensional_method(spec.method, 1.0, **r).params.get(name, np.nan) for r in spec.rows]
        row_coords[name] = ("index", np.array(vals, dtype=float), {"units": units[name]})
    ds = DatasetDict(
        {
            "nrmse": (
                dims3,
                arr["nrmse"],
                {"long_name": "normalised root-mean-square error of Eq. (72) (NaN where unstable)", "units": "1"},
            ),
            "nrmse_unfiltered": (
                dims3,
                arr["nrmse_unfiltered"],
                {"long_name": "Eq. (72) of every run that finished, unstable ones included", "units": "1"},
            ),
            "nrmse_second_half": (
                dims3,
                arr["nrmse_second_half"],
                {"long_name": "Eq. (72) over T_N in (T/2, T] (diagnostic: no start-up transient)", "units": "1"},
            ),
            "nrmse_startup": (
                dims3,
                arr["nrmse_startup"],
                {
                    "long_name": "the terms of Eq. (72)'s sums from the first startup_steps macro steps, over the "
                    "whole run's denominators (the start-up transient's share: nrmse^2 = startup^2 + rest^2)",
                    "units": "1",
                },
            ),
            "nrmse_x": (
                dims3,
                arr["nrmse_x"],
                {
                    "long_name": "position part of Eq. (72): sqrt of the sum of the x1 and x2 ratios (NaN where unstable)",
                    "units": "1",
                    "comment": "nrmse = sqrt(nrmse_x^2 + nrmse_v^2); the other reading of the garbled Eq. (72) is nrmse_x + nrmse_v",
                },
            ),
            "nrmse_v": (
                dims3,
                arr["nrmse_v"],
                {
                    "long_name": "velocity part of Eq. (72): sqrt of the sum of the v1 and v2 ratios (NaN where unstable)",
                    "units": "1",
                },
            ),
            "nrmse_lambda": (
                dims3,
                arr["nrmse_lambda"],
                {
                    "long_name": "Eq. (72)'s measure for the constraint force lambda_c (corrected coupling variable at T_N) against the exact multiplier (NaN where unstable, and for dd: no multiplier among the coupling variables)",
                    "units": "1",
                },
            ),
            "unstable": (
                dims3,
                arr["unstable"],
                {"long_name": "run unstable: diverged, or spectral radius above 1 at this H"},
            ),
            "spectral_radius": (
                dims3,
                arr["spectral_radius"],
                {"long_name": "spectral radius of the co-simulation recurrence at this H", "units": "1"},
            ),
            "spectral_radius_digits": (
                dims3,
                arr["spectral_radius_digits"],
                {
                    "long_name": "significant digits that decided the spectral radius (15: float64; for stepping "
                    "error the Arb precision of the certificate)"
                },
            ),
            "spectral_verdict": (
                dims3,
                arr["spectral_verdict"].astype(str),
                {
                    "long_name": "stable / unstable / marginal: for stepping error proven from the ball "
                    "amplification matrix of the defect (icosim.engine.spectral.certified); else from the precision policy"
                },
            ),
            "diverged_at": (
                dims3,
                arr["diverged_at"],
                {"long_name": "first macro step that left the growth bound or was not finite (-1: none)"},
            ),
            "fit_used": (
                dims3,
                arr["fit_used"],
                {"long_name": "step size in the smallest-H decade the order is read off"},
            ),
            "defect_bits": (
                dims3,
                arr["defect_bits"],
                {
                    "long_name": "Arb working precision (bits) that proved the one-step defect of this run "
                    "(stepping error; 0 for the float64 steppings)",
                    "units": "1",
                },
            ),
            "local_slope": (
                dims_mid,
                slopes["local_slope"],
                {"long_name": "local slope d log(nrmse) / d log(H) between neighbouring step sizes", "units": "1"},
            ),
            "local_slope_second_half": (
                dims_mid,
                slopes["local_slope_second_half"],
                {"long_name": "local slope of nrmse_second_half", "units": "1"},
            ),
            "order": (
                dims2,
                fits["order"],
                {
                    "long_name": "order of convergence of nrmse: least-squares slope over the smallest-H decade "
                    "(evidence only where order_status is asymptotic)",
                    "units": "1",
                },
            ),
            "order_status": (
                dims2,
                status["order_status"].astype(str),
                {
                    "long_name": "asymptotic (every local slope in the smallest-H decade within the tolerance of "
                    "the order), pre-asymptotic, unstable as H -> 0, unstable at every H, or too few points"
                },
            ),
            "order_spread": (
                dims2,
                fits["order_spread"],
                {
                    "long_name": "largest deviation of a local slope in the smallest-H decade from the order",
                    "units": "1",
                },
            ),
            "fit_H_min": (dims2, fits["fit_H_min"], {"long_name": "smallest H of the decade", "units": "s"}),
            "fit_H_max": (dims2, fits["fit_H_max"], {"long_name": "largest H of the decade", "units": "s"}),
            "fit_n_points": (dims2, fit_n, {"long_name": "number of step sizes in the decade"}),
            "fit_note": (
                dims2,
                status["fit_note"].astype(str),
                {"long_name": "why the order is not asymptotic (empty if it is)"},
            ),
            "order_second_half": (
                dims2,
                fits["order_second_half"],
                {"long_name": "order of nrmse_second_half over the smallest-H decade", "units": "1"},
            ),
            "order_startup": (
                dims2,
                fits["order_startup"],
                {"long_name": "order of nrmse_startup over the smallest-H decade", "units": "1"},
            ),
        },
        coords={
            "H": ("H", study.H, H_attrs),
            "n_steps": ("H", study.n_steps, {"long_name": "number of macro steps N_total = end_time / H"}),
            "H_mid": (
                "H_mid",
                H_mid,
                {
                    "long_name": "geometric mean of neighbouring macro-step sizes (where a local slope applies)",
                    "units": "s",
                },
            ),
            "index": (
                "index",
                np.array(spec.indices, dtype=np.int32),
                {"long_name": "index of the coupling formulation"},
            ),
            "k": ("k", np.array(spec.k, dtype=np.int32), {"long_name": "degree of the approximation polynomials"}),
            **row_coords,
        },
    )
    s = study.setup
    attrs = dict(provenance or {})
    attrs.update(
        figure=spec.figure,
        scheme=spec.scheme,
        method=spec.method,
        decomposition=spec.decomposition,
        decomposition_long_name=get_decomposition(spec.decomposition).long_name,
        panel=spec.panel,
        shared_across_columns=int(spec.shared),
        **{name: float(v) for name, v in spec.column.items() if name != "index"},
        **{f"model_{n}": float(getattr(s, n)) for n in PAPER_MODEL},
        x0=s.x0,
        v0=s.v0,
        end_time=s.end_time,
        growth_bound=s.growth_bound,
        initial_conditions=f"x1 = x2 = {s.x0:g} m, v1 = v2 = {s.v0:g} m/s at t = 0 (consistent with the rigid link)",
        history_initialisation="coupling variables at T_0, T_-1, ..., T_-k from the exact monolithic solution "
        "(icosim.problems.linear.exact.consistent_start)",
        nrmse_definition="Eq. (72) read as sqrt of the sum of the four normalised squared-error ratios "
        "(x1, x2, v1, v2), sums over N = 1..N_total; nrmse_x, nrmse_v hold the position and velocity parts "
        "(nrmse^2 = nrmse_x^2 + nrmse_v^2)",
        method_parameters_units=units_description(),
        stepping=stepping,
        spectral_policy=study.spectral_policy,
        fit_procedure="icosim.order_fit.asymptotic_order: " + ", ".join(f"{k}={v}" for k, v in sorted(fit.items())),
        startup_steps=study.startup_steps,
        defect_accuracy="stepping error: the one-step defect D = M W - W E is formed in Arb ball arithmetic until every "
        "row is proven to 2^-40 relative (icosim.studies.convergence.errors), then rounded to float64",
        seconds_total=time.perf_counter() - t0,
    )
    ds.attrs = attrs
    return ds


def curve_summaries(ds: DatasetDict) -> list[tuple]:
    """``(label, order, order_status, unstable step sizes)`` of each curve of a panel from :func:`run_panel_data`,
    labelled as :func:`~icosim.studies.convergence.curves.curves` labels the panel read back (for the job's log)."""
    a, v = ds.attrs, ds.array
    out = []
    for i, index in enumerate(v("index")):
        for j, k in enumerate(v("k")):
            rec = {"decomposition": a["decomposition"], "method": a["method"], "index": int(index), "k": int(k)}
            for name in parameters():
                if name in ds["coords"] or name in a:
                    rec[name] = float(v(name)[i] if name in ds["coords"] else a[name])
            out.append(
                (
                    curve_label(rec),
                    float(v("order")[i, j]),
                    str(v("order_status")[i, j]),
                    int(v("unstable")[i, j].sum()),
                )
            )
    return out

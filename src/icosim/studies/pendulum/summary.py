"""One row per pendulum run: status, errors against the reference, expected and observed behaviour."""

from __future__ import annotations

import math

import numpy as np

from ...engine.methods import make_method
from ...engine.schemes import get_scheme
from ...io.netcdf import config_json, provenance_attrs
from ...problems.pendulum.linearised import linear_test_model_rho
from ...problems.pendulum.model import PendulumParameters
from ...problems.pendulum.names import run_name
from .checks import expected_outcome, run_verdict

__all__ = ["summarize", "summary_dataset"]


def summarize(runs: list, reference, claims: list, rho_test_model: dict | None = None):
    """One row per run: status, errors against the reference, claim expectation and verdict.

    ``runs`` are run datasets, ``reference`` the monolithic one, ``claims`` the
    :class:`~icosim.verdicts.Claim` list of ``config/claims/pendulum.yaml`` (each
    ``pendulum_stability`` claim adds ``expected_<id>`` and ``verdict_<id>``, ``n/a`` for the runs
    of another coupling scheme than the claim's).  Errors are maxima over the
    computed part of the run (up to divergence or failure).  A run is observed
    ``unstable`` if it diverged, ``failed`` if a step could not be computed:
    its verdict is then ``undecided`` (a solver failure proves no instability).
    ``rho_test_model`` (run name -> spectral radius of the linear test model,
    :func:`linear_test_model_rho`) adds that column.
    """
    import xarray as xr

    rows = []
    for ds in runs:
        n = ds.sizes["t"]
        if not np.allclose(ds["t"].values, reference["t"].values[:n], rtol=0, atol=1e-12):
            raise ValueError(
                f"run {ds.attrs['method']}/{ds.attrs['decomposition']}/k={ds.attrs['k']} is not on the reference grid"
            )
        err = {
            name: float(np.max(np.abs(ds[name].values - reference[name].values[:n])))
            for name in ("phi1", "phi2", "lambda_cax", "lambda_cay")
        }
        g = np.hypot(ds["g_cax"].values, ds["g_cay"].values)
        g_corr = np.hypot(ds["g_cax_corrector"].values, ds["g_cay_corrector"].values)
        status = str(ds.attrs["status"])
        observed = {"stable": "stable", "diverged": "unstable", "failed": "failed"}[status]
        row = dict(
            method=ds.attrs["method"],
            decomposition=ds.attrs["decomposition"],
            k=int(ds.attrs["k"]),
            scheme=str(ds.attrs.get("scheme", "jacobi")),
            status=status,
            reason=str(ds.attrs.get("reason", "none")),
            diverged=int(ds.attrs["diverged"]),
            t_diverged=float(ds.attrs["t_diverged"]),
            failed=int(ds.attrs["failed"]),
            t_failed=float(ds.attrs["t_failed"]),
            t_last=float(ds["t"].values[-1]),
            err_phi1=err["phi1"],
            err_phi2=err["phi2"],
            err_lambda=max(err["lambda_cax"], err["lambda_cay"]),
            max_g=float(np.max(g)),
            max_g_corrector=float(np.max(g_corr)),
            wall_time_s=float(ds.attrs.get("wall_time_s", math.nan)),
            observed=observed,
        )
        if rho_test_model is not None:
            row["rho_test_model"] = float(rho_test_model[_name(row)])
        for claim in claims:
            if claim.check["kind"] != "pendulum_stability":
                continue
            if (
                get_scheme(claim.check.get("scheme", "jacobi")).name != row["scheme"]
            ):  # the claim is about another scheme's runs
                row[f"expected_{claim.id}"] = row[f"verdict_{claim.id}"] = "n/a"
                continue
            exp = expected_outcome(claim.check, row["method"], row["decomposition"], row["k"])
            row[f"expected_{claim.id}"] = exp
            row[f"verdict_{claim.id}"] = run_verdict(exp, observed)
        rows.append(row)
    names = [_name(r) for r in rows]
    coord_keys = ("method", "decomposition", "k", "scheme")
    data = {key: ("run", [r[key] for r in rows]) for key in rows[0] if key not in coord_keys}
    coords = {"run": ("run", names), **{key: ("run", [r[key] for r in rows]) for key in coord_keys}}
    units = {
        "t_diverged": "s",
        "t_failed": "s",
        "t_last": "s",
        "err_phi1": "rad",
        "err_phi2": "rad",
        "err_lambda": "N",
        "max_g": "m",
        "max_g_corrector": "m",
        "wall_time_s": "s",
    }
    ds = xr.Dataset(data, coords=coords)
    for key, u in units.items():
        ds[key].attrs["units"] = u
    ds["err_phi1"].attrs["long_name"] = "max |phi1 - phi1_ref| up to the end of the run"
    ds["err_phi2"].attrs["long_name"] = "max |phi2 - phi2_ref| up to the end of the run"
    ds["err_lambda"].attrs["long_name"] = "max |lambda_c - lambda_c_ref| (both components)"
    ds["max_g"].attrs["long_name"] = "max |g_c| of the stored states"
    ds["max_g_corrector"].attrs["long_name"] = "max |g_c| after the corrector, before any projection"
    if rho_test_model is not None:
        ds["rho_test_model"].attrs["long_name"] = (
            "largest spectral radius of the linear test model (Sect. 3) at the pendulum's points (lr1, li1)"
        )
        ds["rho_test_model"].attrs["units"] = "1"
    return ds


def _name(row) -> str:
    return run_name(row["method"], row["decomposition"], row["k"], row["scheme"])


def summary_dataset(runs, reference, claims, *, model: dict, H: float, methods: dict, run_files, command: str = ""):
    """:func:`summarize` with the linear test model's spectral radius per run and provenance (the summary job).

    ``model`` and ``methods`` are the configuration's (``pendulum.model``, ``pendulum.methods``),
    ``run_files`` the run datasets' paths (recorded).
    """
    params = PendulumParameters(**model)
    rho, point = {}, None
    for ds in runs:
        name, dec, k = ds.attrs["method"], ds.attrs["decomposition"], int(ds.attrs["k"])
        scheme = str(ds.attrs.get("scheme", "jacobi"))
        rho[run_name(name, dec, k, scheme)], point = linear_test_model_rho(
            params, H, make_method(name, **methods[name]), dec, k, scheme=scheme
        )
    ds = summarize(runs, reference, claims, rho_test_model=rho)
    job = {
        "claims": [c.as_dict() for c in claims],
        "runs": list(run_files),
        "model": dict(model),
        "H": H,
        "methods": methods,
    }
    ds.attrs.update(
        provenance_attrs(job, title="Double pendulum (Sect. 4): errors and claim verdicts", command=command)
    )
    ds.attrs["claims_json"] = config_json([c.as_dict() for c in claims])
    ds.attrs["test_model_lr1"] = [float(v) for v in point.lr1]
    ds.attrs["test_model_li1"] = [float(v) for v in point.li1]
    ds.attrs["test_model_ratios"] = f"am21 = {point.am21:g}, alr21 = {point.alr21:g}, ali21 = {point.ali21:g}"
    ds.attrs["test_model_point"] = (
        "lr1 = -d H / (2 m1); li1 = H omega for the modal frequencies of the pendulum linearised about its hanging "
        "rest (icosim.problems.pendulum.linearised.pendulum_test_model); rho_test_model is the larger spectral radius of the "
        "two points"
    )
    return ds

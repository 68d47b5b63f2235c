"""The largest stable macro step: measured by bisection on divergence, and predicted by the linear test model.

Both use one search (:func:`stability_limit`) on a predicate ``stable(H)``:

(the search itself: :mod:`icosim.step_limit`)

1. scan the step sizes ``scan`` in increasing order until the first stable
   one and, after it, the first unstable one (the scan stops there);
2. bisect (geometric midpoints) between the last stable and the first
   unstable scan point until their ratio is at most ``1 + resolution``.

``H_max`` is the last stable step size found: the upper edge of the first
stable band at or above ``scan[0]``.  If ``scan[0]`` is already unstable, the
band's lower edge lies above it (``H_band_low`` is its first stable scan
point; the weighted multiplier at ``k = 2`` is such a case).  If no scan point
is unstable, ``H_max`` is censored at the largest scan point.

* measured (:func:`measured_predicate`): a run over ``t_end`` (rounded up to
  whole macro steps) that neither diverges nor fails
  (:func:`icosim.problems.pendulum.runs.run_cosimulation`'s bounds); a failed run (a
  step that cannot be computed) counts as not stable and says so;
* predicted (:func:`linear_predicate`): the linear test model at the
  pendulum's points is stable by the precision policy's verdict
  (:func:`.linear_study.linear_stability`: float64 trusted or proven
  ``rho < 1``); a ``marginal`` or ``undecided`` step size counts as not
  stable, and the dataset records the verdict at the bracket's unstable end.

The measured limit is divergence *within* ``t_end``: where the growth per
step is only slightly above 1, a run may stay within the bounds over
``t_end`` although the step is unstable, so the measured ``H_max`` can exceed
the point where ``rho`` crosses 1.

>>> lim = stability_limit(lambda H: H <= 0.0123, [1e-3, 1e-2, 1e-1], resolution=0.02)
>>> lim.status, round(lim.H_max / 0.0123, 2) <= 1.0, lim.H_unstable / lim.H_max <= 1.02
('bisected', True, True)
"""

from __future__ import annotations

import math

import numpy as np

from ...engine.methods import make_method
from ...io.dataset import DatasetDict
from ...io.netcdf import provenance_attrs
from ...problems.pendulum.model import PendulumParameters
from ...step_limit import LIMIT_STATUSES, Limit, stability_limit
from .linear_study import linear_rho, linear_stability
from .measures import config_label, measured_run

__all__ = [
    "Limit",
    "stability_limit",
    "measured_predicate",
    "linear_predicate",
    "limits_group",
    "limits_dataset",
    "limits_study",
    "limits_study_data",
    "merge_limits",
    "limited_by",
    "LIMIT_STATUSES",
]


def measured_predicate(settings: dict, scheme: str, method: str, decomposition: str, k: int, t_end: float):
    """``stable(H)`` of the pendulum: a run over ``t_end`` that neither diverges nor fails."""

    def stable(H):
        # the search asks only whether the run stays within the bounds: no reference, no errors
        rec = measured_run(settings, scheme, method, decomposition, k, H, t_end, reference=None)
        return rec["status"] == "stable", rec

    return stable


def linear_predicate(settings: dict, method: str, decomposition: str, k: int, scheme="jacobi"):
    """``stable(H)`` of the linear test model at the pendulum's points: the verdict is ``stable``."""
    params = PendulumParameters(**settings["model"])
    m = make_method(method, **settings["methods"][method])

    def stable(H):
        rho, verdict = linear_stability(params, m, decomposition, k, H, scheme=scheme)
        return verdict == "stable", {"rho": rho, "verdict": verdict}

    return stable


def limits_group(settings, scheme, method, decomposition, ks, *, scan, t_end, resolution, log=None) -> dict:
    """Measured and predicted limits of one group: ``{label: (measured Limit, predicted Limit)}``."""
    out = {}
    for k in ks:
        label = config_label(scheme, method, decomposition, k)
        measured = stability_limit(
            measured_predicate(settings, scheme, method, decomposition, k, t_end), scan, resolution=resolution
        )
        predicted = stability_limit(
            linear_predicate(settings, method, decomposition, k, scheme), scan, resolution=resolution
        )
        # the linear model's rho where the measurement put the band's edges: how fast would it have grown there?
        params = PendulumParameters(**settings["model"])
        m = make_method(method, **settings["methods"][method])
        measured.rho_linear = {
            key: (linear_rho(params, m, decomposition, k, H, scheme=scheme) if math.isfinite(H) else math.nan)
            for key, H in (("H_max", measured.H_max), ("H_band_low", measured.H_band_low))
        }
        out[label] = (int(k), measured, predicted)
        if log:
            log(label, measured, predicted)
    return out


def limits_dataset(groups: dict, *, scheme, method, decomposition, scan, t_end, resolution, attrs) -> DatasetDict:
    """One group's limits as a dataset over ``config`` (the contract names ``H_max``, ``H_max_linear``)."""
    labels = list(groups)

    def col(fn, dtype=float):
        return np.array([fn(*groups[lab]) for lab in labels], dtype=dtype)

    def last_rho(lim):
        rhos = [info["rho"] for H, ok, info in lim.evaluations if H == lim.H_max and info]
        return rhos[0] if rhos else math.nan

    def verdict_at(lim, H):
        verdicts = [info["verdict"] for h, ok, info in lim.evaluations if h == H and info]
        return verdicts[0] if verdicts else ""

    data = {
        "H_max": ("config", col(lambda k, m, p: m.H_max), {"units": "s", "long_name": "largest stable H, measured"}),
        "H_max_linear": (
            "config",
            col(lambda k, m, p: p.H_max),
            {
                "units": "s",
                "long_name": "largest H with the linear test model stable at the pendulum's points (verdict)",
            },
        ),
        "H_unstable": (
            "config",
            col(lambda k, m, p: m.H_unstable),
            {"units": "s", "long_name": "smallest unstable H above H_max, measured (bracket)"},
        ),
        "H_unstable_linear": (
            "config",
            col(lambda k, m, p: p.H_unstable),
            {"units": "s", "long_name": "smallest H above H_max_linear not stable by the verdict (bracket)"},
        ),
        "H_band_low": (
            "config",
            col(lambda k, m, p: m.H_band_low),
            {"units": "s", "long_name": "first stable scan point (lower edge of the stable band), measured"},
        ),
        "H_band_low_linear": (
            "config",
            col(lambda k, m, p: p.H_band_low),
            {"units": "s", "long_name": "first scan point with the linear test model stable (verdict)"},
        ),
        "status": ("config", col(lambda k, m, p: m.status, str), {"long_name": "outcome of the measured search"}),
        "status_linear": (
            "config",
            col(lambda k, m, p: p.status, str),
            {"long_name": "outcome of the predicted search"},
        ),
        "n_runs": (
            "config",
            col(lambda k, m, p: m.n_evaluations, int),
            {"long_name": "co-simulation runs of the search"},
        ),
        "rho_at_H_max": (
            "config",
            col(lambda k, m, p: last_rho(p)),
            {"long_name": "linear test model's rho at H_max_linear"},
        ),
        "verdict_linear_unstable": (
            "config",
            col(lambda k, m, p: verdict_at(p, p.H_unstable), str),
            {
                "long_name": "precision policy's verdict of the linear test model at H_unstable_linear "
                "(unstable, or marginal / undecided: no proven crossing)"
            },
        ),
        "reason_unstable": (
            "config",
            col(lambda k, m, p: _reason_at(m, m.H_unstable), str),
            {"long_name": "why the run at H_unstable diverged or failed"},
        ),
        "limited_by": (
            "config",
            col(lambda k, m, p: limited_by(_reason_at(m, m.H_unstable)), str),
            {"long_name": "what ended the run at H_unstable: growth, the constraint bound |g_c|, or a failure"},
        ),
        "rho_linear_at_measured_H_max": (
            "config",
            col(lambda k, m, p: m.rho_linear.get("H_max", math.nan)),
            {"long_name": "linear test model's rho at the measured H_max"},
        ),
        "rho_linear_at_measured_band_low": (
            "config",
            col(lambda k, m, p: m.rho_linear.get("H_band_low", math.nan)),
            {"long_name": "linear test model's rho at the measured lower edge of the stable band"},
        ),
    }
    coords = {
        "config": ("config", labels),
        "scheme": ("config", [scheme] * len(labels)),
        "method": ("config", [method] * len(labels)),
        "decomposition": ("config", [decomposition] * len(labels)),
        "k": ("config", [groups[lab][0] for lab in labels]),
    }
    attrs = dict(attrs)
    attrs.update(t_end=float(t_end), resolution=float(resolution), scan=[float(h) for h in sorted(scan)])
    return DatasetDict(data, coords=coords, attrs=attrs)


def limits_study(settings, scheme, method, decomposition, ks, *, limits: dict, command: str = "", log=None):
    """:func:`limits_study_data` as an :class:`xarray.Dataset`."""
    return limits_study_data(
        settings, scheme, method, decomposition, ks, limits=limits, command=command, log=log
    ).to_xarray()


def limits_study_data(settings, scheme, method, decomposition, ks, *, limits: dict, command: str = "", log=None):
    """One group's limits (:func:`limits_group`) as a dataset (:func:`limits_dataset`) with its provenance.

    ``limits`` is the configuration's ``trade.stability_limit`` (``scan``, ``t_end``, ``resolution``);
    ``log(label, measured, predicted)`` is called after each ``k``.
    """
    groups = limits_group(
        settings,
        scheme,
        method,
        decomposition,
        list(ks),
        scan=list(limits["scan"]),
        t_end=limits["t_end"],
        resolution=limits["resolution"],
        log=log,
    )
    job = {
        "settings": settings,
        "scheme": scheme,
        "method": method,
        "decomposition": decomposition,
        "k": ks,
        "limits": limits,
    }
    attrs = provenance_attrs(job, title="Double pendulum: stability limit in H", command=command)
    return limits_dataset(
        groups,
        scheme=scheme,
        method=method,
        decomposition=decomposition,
        scan=limits["scan"],
        t_end=limits["t_end"],
        resolution=limits["resolution"],
        attrs=attrs,
    )


def limited_by(reason: str) -> str:
    """``growth`` (``|lambda_c|`` or ``|omega|`` beyond its bound, or not finite), ``constraint bound`` (``|g_c|`` beyond its
    bound: possibly an inaccurate rather than a growing run), ``failed`` or ``""`` (no unstable run)."""
    if not reason:
        return ""
    if reason.startswith("failed"):
        return "failed"
    return "constraint bound" if "|g_c|" in reason else "growth"


def _reason_at(lim: Limit, H) -> str:
    for h, ok, info in lim.evaluations:
        if h == H and not ok and info:
            return f"{info['status']}: {info['reason']}"
    return ""


def merge_limits(datasets: list):
    """The groups' limit datasets as one over ``config`` (``stability_limit.nc``); per-job provenance dropped."""
    import xarray as xr

    ds = xr.concat(
        datasets, dim="config", data_vars="all", coords="minimal", compat="override", combine_attrs="drop_conflicts"
    ).drop_encoding()  # the first file's fixed string widths would truncate longer labels when written
    for key in ("config_json", "config_sha256", "title", "history"):
        ds.attrs.pop(key, None)
    return ds

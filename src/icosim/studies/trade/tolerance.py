"""Subsystem tolerance: does the integration error of the links matter against the coupling error?

At fixed ``H``, a few configurations are co-simulated with Radau IIA at
``rtol = atol`` from loose to tight (:func:`tolerance_study`).  Two numbers per
run answer the question:

* ``error_max`` against the monolithic reference (coupling plus integration
  error);
* ``integration_effect`` = ``max |phi_i(rtol) - phi_i(rtol_min)|`` over the
  macro nodes: how far the run moves from the run with the tightest
  tolerance, i.e. the part of the error that the integration tolerance
  controls (the coupling error is the same for both).

The integration error stops mattering at the loosest ``rtol`` from which on
``integration_effect <= share * error_max(rtol_min)``
(:func:`icosim.studies.trade.conclusions.sufficient_rtol`, read from the dataset).
"""

from __future__ import annotations

import math

import numpy as np

from ...engine.methods import make_method
from ...io.dataset import DatasetDict
from ...io.netcdf import provenance_attrs
from ...problems.pendulum.model import PendulumParameters
from ...problems.pendulum.reference import reference_solution
from ...problems.pendulum.runs import run_cosimulation
from .baselines import reference_accuracy
from .measures import RECORD, check_scheme, config_label, run_record

__all__ = ["tolerance_study", "tolerance_study_data"]


def _run(settings, method, decomposition, k, H, t_end, rtol, scheme="jacobi"):
    params = PendulumParameters(**settings["model"])
    n = max(1, math.ceil(t_end / H - 1e-9))
    integ = dict(settings["integrator"], rtol=rtol, atol=rtol)
    return run_cosimulation(
        params,
        make_method(method, **settings["methods"][method]),
        decomposition,
        int(k),
        H=H,
        t_end=n * H,
        **integ,
        **settings["sensitivities"],
        **settings["corrector"],
        **settings["divergence"],
        scheme=scheme,
    )


def tolerance_study(*args, **kwargs):
    """:func:`tolerance_study_data` as an :class:`xarray.Dataset`."""
    return tolerance_study_data(*args, **kwargs).to_xarray()


def tolerance_study_data(
    settings: dict, configurations: list, H_values, rtols, t_end: float, *, reference: dict, command: str = "", log=None
) -> DatasetDict:
    """Error over the subsystem tolerance at each fixed ``H`` -> dataset over ``(config, H, rtol)``.

    ``configurations``: dicts with ``scheme`` (default ``jacobi``), ``method``,
    ``decomposition``, ``k``.
    """
    rtols = sorted((float(r) for r in rtols), reverse=True)  # loose to tight
    H_values = [float(h) for h in H_values]
    names = list(RECORD) + ["integration_effect"]
    data = {name: np.full((len(configurations), len(H_values), len(rtols)), np.nan) for name in names}
    status = np.full((len(configurations), len(H_values), len(rtols)), "", dtype=object)
    labels = []
    params = PendulumParameters(**settings["model"])
    for i, c in enumerate(configurations):
        scheme = check_scheme(c.get("scheme", "jacobi"))
        labels.append(config_label(scheme, c["method"], c["decomposition"], c["k"]))
        for j, H in enumerate(H_values):
            runs = [_run(settings, c["method"], c["decomposition"], c["k"], H, t_end, r, scheme) for r in rtols]
            ref = reference_solution(params, runs[-1].t, **reference)
            tight = runs[-1]
            for m, (rtol, res) in enumerate(zip(rtols, runs)):
                rec = run_record(
                    res, ref if res.t.size == tight.t.size else reference_solution(params, res.t, **reference)
                )
                for name in RECORD:
                    data[name][i, j, m] = rec[name]
                status[i, j, m] = rec["status"]
                n = min(res.t.size, tight.t.size)
                data["integration_effect"][i, j, m] = max(
                    float(np.max(np.abs(res.series[v][:n] - tight.series[v][:n]))) for v in ("phi1", "phi2")
                )
                if log:
                    log(labels[-1], H, rtol, rec, data["integration_effect"][i, j, m])
    dims = ("config", "H", "rtol")
    variables = {
        name: (dims, arr, {"units": RECORD[name][0], "long_name": RECORD[name][1]})
        for name, arr in data.items()
        if name in RECORD
    }
    variables["integration_effect"] = (
        dims,
        data["integration_effect"],
        {"units": "rad", "long_name": "max |phi_i(rtol) - phi_i(tightest rtol)| over the macro nodes"},
    )
    variables["status"] = (dims, status.astype(str), {"long_name": "stable, diverged or failed"})
    coords = {
        "config": ("config", labels),
        "H": ("H", H_values, {"units": "s"}),
        "rtol": ("rtol", rtols, {"long_name": "rtol = atol of the links' Radau IIA"}),
        "method": ("config", [c["method"] for c in configurations]),
        "decomposition": ("config", [c["decomposition"] for c in configurations]),
        "k": ("config", [int(c["k"]) for c in configurations]),
        "scheme": ("config", [check_scheme(c.get("scheme", "jacobi")) for c in configurations]),
    }
    job = {"configurations": configurations, "H": H_values, "rtol": rtols, "t_end": t_end, "settings": settings}
    attrs = provenance_attrs(job, title="Double pendulum: error over the subsystem tolerance", command=command)
    attrs.update(
        t_end=float(t_end),
        reference_method=reference["method"],
        reference_rtol=float(reference["rtol"]),
        reference_accuracy=reference_accuracy(params, t_end, reference),
    )
    return DatasetDict(variables, coords=coords, attrs=attrs)

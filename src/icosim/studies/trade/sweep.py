"""Error over the macro-step size H: every configuration at every H over the same end time.

One job runs one group -- a scheme, a method and a decomposition, every ``k``
and every ``H`` (:func:`sweep_group`) -- and writes its records
(:data:`icosim.studies.trade.measures.RECORD`) over ``(config, H)``.
The orders are fitted where the groups are assembled
(:func:`icosim.studies.trade.work_precision.orders`), so that a change of the fit
reruns no sweep.
"""

from __future__ import annotations

import numpy as np

from ...engine.methods import make_method
from ...io.dataset import DatasetDict
from ...io.netcdf import provenance_attrs
from .measures import RECORD, config_label, measured_run

__all__ = ["sweep_group", "sweep_group_data", "records_dataset"]


def records_dataset(records: dict, labels: list, H_values, coords: dict, attrs: dict, dim: str = "H") -> DatasetDict:
    """Records ``{(label, H): record}`` as a dataset over ``(config, dim)`` (NaN where none)."""
    H_values = [float(h) for h in H_values]
    data = {}
    for name, (units, long_name) in RECORD.items():
        arr = np.full((len(labels), len(H_values)), np.nan)
        for i, lab in enumerate(labels):
            for j, h in enumerate(H_values):
                rec = records.get((lab, h))
                if rec is not None:
                    arr[i, j] = rec[name]
        data[name] = (("config", dim), arr, {"units": units, "long_name": long_name})
    status = [[records[(lab, h)]["status"] if (lab, h) in records else "" for h in H_values] for lab in labels]
    reason = [[records[(lab, h)]["reason"] if (lab, h) in records else "" for h in H_values] for lab in labels]
    data["status"] = (("config", dim), np.array(status, dtype=str), {"long_name": "stable, diverged or failed"})
    data["reason"] = (("config", dim), np.array(reason, dtype=str), {"long_name": "why a run diverged or failed"})
    all_coords = {"config": ("config", list(labels)), dim: (dim, H_values, {"units": "s"})}
    all_coords.update({key: ("config", list(v)) for key, v in coords.items()})
    return DatasetDict(data, coords=all_coords, attrs=attrs)


def sweep_group(*args, **kwargs):
    """:func:`sweep_group_data` as an :class:`xarray.Dataset`."""
    return sweep_group_data(*args, **kwargs).to_xarray()


def sweep_group_data(
    settings: dict,
    scheme: str,
    method: str,
    decomposition: str,
    ks,
    H_values,
    t_end: float,
    *,
    reference: dict,
    integrator: dict | None = None,
    repeats: int = 3,
    repeat_below: float = 0.1,
    command: str = "",
    log=None,
):
    """Error over H of one group (scheme, method, decomposition; every ``k``) -> dataset over ``(config, H)``."""
    make_method(method, **settings["methods"][method])  # fails early on bad parameters
    labels, records = [], {}
    for k in ks:
        label = config_label(scheme, method, decomposition, k)
        labels.append(label)
        for H in H_values:
            rec = measured_run(
                settings,
                scheme,
                method,
                decomposition,
                k,
                H,
                t_end,
                reference=reference,
                repeats=repeats,
                repeat_below=repeat_below,
                integrator=integrator,
            )
            records[(label, float(H))] = rec
            if log:
                log(label, H, rec)
    job = {
        "scheme": scheme,
        "method": method,
        "decomposition": decomposition,
        "k": [int(k) for k in ks],
        "H": [float(h) for h in H_values],
        "t_end": t_end,
        "settings": settings,
        "integrator": integrator or {},
        "reference": reference,
    }
    attrs = provenance_attrs(
        job, title=f"Double pendulum: error over H, {scheme} {method} {decomposition}", command=command
    )
    attrs.update(
        t_end=float(t_end),
        reference_method=reference["method"],
        reference_rtol=float(reference["rtol"]),
        rtol=float(dict(settings["integrator"], **(integrator or {}))["rtol"]),
        atol=float(dict(settings["integrator"], **(integrator or {}))["atol"]),
    )
    coords = {
        "scheme": [scheme] * len(labels),
        "method": [method] * len(labels),
        "decomposition": [decomposition] * len(labels),
        "k": [int(k) for k in ks],
    }
    return records_dataset(records, labels, H_values, coords, attrs)

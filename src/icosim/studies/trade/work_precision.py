"""Work-precision of the pendulum: co-simulation against the monolithic pendulum, per accuracy level.

* the monolithic baselines and the linear model's errors come from
  :mod:`.baselines`;
* :func:`work_precision_dataset` -- the ``work_precision.nc`` contract:
  ``error_max``, ``error_rms``, ``cpu_seconds``, ``n_macro_steps`` (and the
  other counts) over ``(config, H)`` from the sweep groups, the order of each
  configuration and of the linear test model for the same scheme, the
  monolithic baselines over ``(integrator, tol)`` and, per accuracy level,
  the cheapest configuration (:func:`cheapest`).
"""

from __future__ import annotations

import math

import numpy as np

from ...io.netcdf import provenance_attrs
from .orders import error_floor, pendulum_order

__all__ = ["work_precision_dataset", "orders", "cheapest"]


def cheapest(wp, level: float):
    """The stable run with ``error_max <= level`` and the least CPU seconds: ``(config, H, cpu)`` or None."""
    ok = (wp["status"].values == "stable") & (wp["error_max"].values <= level)
    if not ok.any():
        return None
    cpu = np.where(ok, wp["cpu_seconds"].values, np.inf)
    i, j = np.unravel_index(np.argmin(cpu), cpu.shape)
    return str(wp["config"].values[i]), float(wp["H"].values[j]), float(cpu[i, j])


def _monolithic_at(mono, integrator, level):
    sel = mono.sel(integrator=integrator)
    ok = sel["error_max"].values <= level
    if not ok.any():
        return math.nan, math.nan
    cpu = np.where(ok, sel["cpu_seconds"].values, np.inf)
    j = int(np.argmin(cpu))
    return float(cpu[j]), float(sel["tol"].values[j])


def work_precision_dataset(sweeps: list, monolithic, linear, *, fit: dict, accuracy_levels, command=""):
    """The ``work_precision.nc`` contract from the sweep groups, the baselines and the linear orders (module docstring).

    ``linear`` is the linear orders dataset (``error_linear`` over ``(config, H)``,
    :func:`linear_orders_dataset`); ``fit``: ``floor_factor``, ``decades``,
    ``tolerance``, ``min_points``.
    """
    import xarray as xr

    wp = xr.concat(
        sweeps, dim="config", data_vars="all", coords="minimal", compat="override", combine_attrs="drop_conflicts"
    ).drop_encoding()  # the first file's fixed string widths would truncate longer labels when written
    for key in ("config_json", "config_sha256", "title", "history"):
        wp.attrs.pop(key, None)
    acc = float(monolithic.attrs["reference_accuracy"])  # the reference's own error (baselines job)
    wp.attrs["reference_accuracy"] = acc
    wp.attrs["reference_method"] = str(monolithic.attrs["reference_method"])
    wp.attrs["reference_rtol"] = float(monolithic.attrs["reference_rtol"])
    fits = orders(wp, **fit)
    labels = [str(c) for c in wp["config"].values]
    missing = sorted(set(labels) - {str(c) for c in linear["config"].values})
    if missing:  # reindex would fill them with NaN and the comparison would go quiet
        raise ValueError(f"the linear study has no configuration {', '.join(missing)} of the pendulum runs")
    lin = linear.reindex(config=labels)
    lin_fits = {}
    for lab in labels:
        row = lin.sel(config=lab)
        unstable = row["unstable_linear"].values.astype(bool)
        floor = error_floor(row["n_steps_linear"].values, factor=fit["floor_factor"], rounding="linear")
        lin_fits[lab] = pendulum_order(
            lin["H"].values,
            row["error_linear"].values,
            unstable,
            floor=floor,
            decades=fit["decades"],
            tolerance=fit["tolerance"],
            min_points=fit["min_points"],
        )
    for prefix, f in (("order", fits), ("order_linear", lin_fits)):
        wp[prefix] = ("config", [f[lab].order for lab in labels], {"long_name": "slope of log error over log H"})
        wp[f"{prefix}_status"] = ("config", np.array([f[lab].status for lab in labels], dtype=str))
        wp[f"{prefix}_spread"] = ("config", [f[lab].spread for lab in labels])
        wp[f"{prefix}_H_min"] = ("config", [f[lab].H_min for lab in labels], {"units": "s"})
        wp[f"{prefix}_H_max"] = ("config", [f[lab].H_max for lab in labels], {"units": "s"})
        wp[f"{prefix}_reason"] = ("config", np.array([f[lab].reason for lab in labels], dtype=str))
    wp["error_linear"] = (("config", "H"), lin["error_linear"].values, lin["error_linear"].attrs)
    wp["rho_linear"] = (("config", "H"), lin["rho_linear"].values, lin["rho_linear"].attrs)
    for name in monolithic.data_vars:
        wp[f"monolithic_{name}"] = (("integrator", "tol"), monolithic[name].values, monolithic[name].attrs)
    wp = wp.assign_coords(integrator=monolithic["integrator"].values, tol=monolithic["tol"].values)
    levels = sorted((float(v) for v in accuracy_levels), reverse=True)
    best = [cheapest(wp, lv) for lv in levels]
    wp = wp.assign_coords(accuracy_level=("accuracy_level", levels, {"units": "rad"}))
    wp["cheapest_config"] = ("accuracy_level", np.array([b[0] if b else "" for b in best], dtype=str))
    wp["cheapest_H"] = ("accuracy_level", [b[1] if b else math.nan for b in best], {"units": "s"})
    wp["cheapest_cpu_seconds"] = ("accuracy_level", [b[2] if b else math.nan for b in best], {"units": "s"})
    for integ in monolithic["integrator"].values:
        vals = [_monolithic_at(monolithic, integ, lv) for lv in levels]
        wp[f"monolithic_{integ}_cpu_at_level"] = ("accuracy_level", [v[0] for v in vals], {"units": "s"})
        wp[f"monolithic_{integ}_tol_at_level"] = ("accuracy_level", [v[1] for v in vals])
    job = {"fit": fit, "accuracy_levels": levels}
    wp.attrs.update(provenance_attrs(job, title="Double pendulum: error over H and work-precision", command=command))
    wp.attrs.update(
        fit_rule=(
            "order = least-squares slope of log error_max over log H on the smallest-H decade of stable step sizes "
            "above the error floor; asymptotic if every local slope there is within tolerance of it, else "
            "pre-asymptotic (icosim.studies.trade.orders.pendulum_order)"
        ),
        fit_tolerance=float(fit["tolerance"]),
        fit_floor_factor=float(fit["floor_factor"]),
        linear_model_json=str(linear.attrs.get("model_json", "")),
    )
    return wp


def orders(ds, *, floor_factor: float = 10.0, decades: float = 1.0, tolerance: float = 0.1, min_points: int = 3):
    """Order of every configuration of a sweep dataset: ``{label: AsymptoticOrder}``.

    Unstable: a run that diverged or failed.  The floor is
    :func:`.orders.error_floor` with the dataset's ``reference_accuracy``.
    """
    out = {}
    H = ds["H"].values
    acc = float(ds.attrs.get("reference_accuracy", 0.0))
    for i, label in enumerate(ds["config"].values):
        row = ds.isel(config=i)
        unstable = row["status"].values != "stable"
        floor = error_floor(row["n_macro_steps"].values, reference_accuracy=acc, factor=floor_factor)
        out[str(label)] = pendulum_order(
            H,
            np.where(unstable, np.nan, row["error_max"].values),
            unstable,
            floor=floor,
            decades=decades,
            tolerance=tolerance,
            min_points=min_points,
        )
    return out

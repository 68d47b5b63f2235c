"""Conclusions of the pendulum's speed-accuracy studies, read from their datasets.

The report (:mod:`icosim.report.pendulum_trade`) shows these rows and counts;
tests call the same functions on the same datasets, so every sentence of the
report is a computed statement about the data.

* :func:`order_rows`, :func:`order_summary` -- the pendulum's order against the
  linear model's per configuration (``work_precision.nc``);
* :func:`accuracy_rows` -- the cheapest co-simulation run per accuracy level and
  the monolithic baselines' cost;
* :func:`limit_rows`, :func:`limit_summary` -- measured against predicted
  stability limits (``stability_limit.nc``);
* :func:`tolerance_rows` -- the subsystem tolerance study (``tolerance.nc``), with
  :func:`sufficient_rtol`;
* :func:`adaptive_summary` -- adaptive against fixed H at equal error (``adaptive.nc``), with
  :func:`equal_error_table`.

The module reads datasets only (it imports no module that runs the pendulum): it is the
trade study's data contract for the report.
"""

from __future__ import annotations

import math

import numpy as np

from .orders import error_floor

__all__ = [
    "ORDER_AGREEMENT",
    "LIMIT_AGREEMENT",
    "order_rows",
    "order_summary",
    "accuracy_rows",
    "limit_rows",
    "limit_summary",
    "tolerance_rows",
    "adaptive_summary",
    "sufficient_rtol",
    "equal_error_table",
]

#: two asymptotic orders agree if they differ by at most this (the spread allowed within one decade is 0.1)
ORDER_AGREEMENT = 0.2
#: measured and predicted limits agree if their ratio lies within [1/LIMIT_AGREEMENT, LIMIT_AGREEMENT]
LIMIT_AGREEMENT = 1.25


def order_rows(wp) -> list[dict]:
    """One row per configuration: the pendulum's and the linear model's orders and whether they agree."""
    rows = []
    for i, lab in enumerate(wp["config"].values):
        r = wp.isel(config=i)
        o, s = float(r["order"]), str(r["order_status"].values)
        ol, sl = float(r["order_linear"]), str(r["order_linear_status"].values)
        both = s == "asymptotic" and sl == "asymptotic"
        rows.append(
            {
                "config": str(lab),
                "order": o,
                "status": s,
                "H_min": float(r["order_H_min"]),
                "H_max": float(r["order_H_max"]),
                "order_linear": ol,
                "status_linear": sl,
                "agree": (abs(o - ol) <= ORDER_AGREEMENT) if both else None,
                "reason": str(r["order_reason"].values),
            }
        )
    return rows


def order_summary(rows) -> dict:
    """Counts behind the order conclusion."""
    decided = [r for r in rows if r["status"] == "asymptotic"]
    compared = [r for r in rows if r["agree"] is not None]
    return {
        "n": len(rows),
        "asymptotic": len(decided),
        "compared": len(compared),
        "agree": sum(bool(r["agree"]) for r in compared),
        "disagree": [r["config"] for r in compared if not r["agree"]],
    }


def accuracy_rows(wp) -> list[dict]:
    """Per accuracy level: the cheapest co-simulation run and the monolithic baselines' cost."""
    rows = []
    for j, lv in enumerate(wp["accuracy_level"].values):
        row = {
            "level": float(lv),
            "config": str(wp["cheapest_config"].values[j]),
            "H": float(wp["cheapest_H"].values[j]),
            "cpu": float(wp["cheapest_cpu_seconds"].values[j]),
        }
        labels = [str(c) for c in wp["config"].values]
        row["unstable_small_H"] = bool(
            row["config"] in labels
            and str(wp["order_status"].values[labels.index(row["config"])]) == "unstable as H -> 0"
        )
        for integ in wp["integrator"].values:
            row[f"cpu_{integ}"] = float(wp[f"monolithic_{integ}_cpu_at_level"].values[j])
            row[f"tol_{integ}"] = float(wp[f"monolithic_{integ}_tol_at_level"].values[j])
        rows.append(row)
    return rows


def limit_rows(limits) -> list[dict]:
    rows = []
    for i, lab in enumerate(limits["config"].values):
        r = limits.isel(config=i)
        h, hl = float(r["H_max"]), float(r["H_max_linear"])
        ratio = h / hl if (math.isfinite(h) and math.isfinite(hl) and hl > 0) else math.nan
        rows.append(
            {
                "config": str(lab),
                "H_max": h,
                "status": str(r["status"].values),
                "H_band_low": float(r["H_band_low"]),
                "H_max_linear": hl,
                "status_linear": str(r["status_linear"].values),
                # the verdict at the linear bracket's upper end: "unstable", or marginal / undecided (no proven crossing)
                "verdict_linear": str(r["verdict_linear_unstable"].values) if "verdict_linear_unstable" in r else "",
                "H_band_low_linear": float(r["H_band_low_linear"]),
                "ratio": ratio,
                "n_runs": int(r["n_runs"]),
                "reason": str(r["reason_unstable"].values),
                "limited_by": str(r["limited_by"].values),
                "rho_at_H_max": float(r["rho_linear_at_measured_H_max"]),
                "rho_at_band_low": float(r["rho_linear_at_measured_band_low"]),
            }
        )
    return rows


def limit_summary(rows, scan0: float, t_end: float = math.nan) -> dict:
    """Counts behind the stability-limit conclusion: where the measured limit is set by growth and the linear
    model's by rho = 1, do they agree within LIMIT_AGREEMENT; which measured limits are the constraint bound;
    the growth rho^n the linear model allows over the horizon at the lower edge of a measured band."""
    growth = [r for r in rows if r["status"] == "bisected" and r["limited_by"] == "growth"]
    growth_both = [r for r in growth if r["status_linear"] == "bisected"]
    band_growth = {
        r["config"]: r["rho_at_band_low"] ** math.ceil(t_end / r["H_band_low"] - 1e-9)
        for r in rows
        if r["H_band_low"] > scan0 * (1 + 1e-9) and math.isfinite(r["rho_at_band_low"]) and math.isfinite(t_end)
    }
    both = [r for r in rows if r["status"] == "bisected" and r["status_linear"] == "bisected"]
    agree = [r for r in both if 1 / LIMIT_AGREEMENT <= r["ratio"] <= LIMIT_AGREEMENT]
    above = [r for r in both if r["ratio"] > LIMIT_AGREEMENT]
    below = [r for r in both if r["ratio"] < 1 / LIMIT_AGREEMENT]
    unstable_small = [
        r["config"] for r in rows if r["H_band_low"] > scan0 * (1 + 1e-9) or not math.isfinite(r["H_band_low"])
    ]
    unstable_small_lin = [
        r["config"]
        for r in rows
        if r["H_band_low_linear"] > scan0 * (1 + 1e-9) or not math.isfinite(r["H_band_low_linear"])
    ]
    return {
        "n": len(rows),
        "growth_limited": [r["config"] for r in growth],
        "growth_compared": [(r["config"], r["ratio"]) for r in growth_both],
        "growth_agree": [r["config"] for r in growth_both if 1 / LIMIT_AGREEMENT <= r["ratio"] <= LIMIT_AGREEMENT],
        "constraint_limited": [
            r["config"] for r in rows if r["status"] == "bisected" and r["limited_by"] == "constraint bound"
        ],
        "band_growth": band_growth,
        "both_bisected": len(both),
        "agree": [r["config"] for r in agree],
        "measured_above": [r["config"] for r in above],
        "measured_below": [r["config"] for r in below],
        "censored": [r["config"] for r in rows if r["status"] == "stable up to the cap"],
        "censored_linear": [r["config"] for r in rows if r["status_linear"] == "stable up to the cap"],
        "unstable_at_scan0": unstable_small,
        "unstable_at_scan0_linear": unstable_small_lin,
    }


def tolerance_rows(tol, floor_factor: float = 10.0) -> list[dict]:
    """Per configuration and H: errors, the largest integration effect, the loosest sufficient rtol, cost.

    Where the error at the tightest rtol is below the error floor (:func:`~icosim.studies.trade.orders.error_floor`)
    the comparison says nothing (both are rounding): ``at_floor`` is then True.
    """
    share = float(tol.attrs.get("share", 0.01))
    acc = float(tol.attrs.get("reference_accuracy", 0.0))
    rows = []
    for lab in tol["config"].values:
        for H in tol["H"].values:
            r = tol.sel(config=lab, H=H)
            floor = float(error_floor(r["n_macro_steps"].values[-1], reference_accuracy=acc, factor=floor_factor))
            rows.append(
                {
                    "config": str(lab),
                    "H": float(H),
                    "error_tight": float(r["error_max"].values[-1]),
                    "error_loose": float(r["error_max"].values[0]),
                    "effect_max": float(np.nanmax(r["integration_effect"].values[:-1])),
                    "rtol_loose": float(r["rtol"].values[0]),
                    "rtol_tight": float(r["rtol"].values[-1]),
                    "sufficient": sufficient_rtol(tol, lab, H, share=share),
                    "substeps_loose": float(r["n_subsystem_steps"].values[0] / r["n_integrations"].values[0]),
                    "substeps_tight": float(r["n_subsystem_steps"].values[-1] / r["n_integrations"].values[-1]),
                    "cpu_loose": float(r["cpu_seconds"].values[0]),
                    "cpu_tight": float(r["cpu_seconds"].values[-1]),
                    "at_floor": bool(float(r["error_max"].values[-1]) < floor),
                }
            )
    return rows


def adaptive_summary(adaptive, limits=None) -> dict:
    """Per configuration: at how many bracketed tolerances the adaptive run needs fewer macro steps
    (accepted + rejected) than a fixed H at equal error, the ratios, and the data an explanation needs.

    ``not_fewer`` lists the runs that are not cheaper or not bracketed, with their largest accepted
    step and rejected steps; ``H_limit`` is the configuration's measured stability limit from
    ``limits`` (``stability_limit.nc``), if given and listed there.
    """
    rows = equal_error_table(adaptive)
    drift_tol = float(adaptive.attrs.get("drift_tol", math.nan))
    limit_of = {}
    if limits is not None:
        limit_of = {str(c): float(h) for c, h in zip(limits["config"].values, limits["H_max"].values)}
    out = {}
    for lab in adaptive["config"].values:
        mine = [r for r in rows if r["config"] == str(lab)]
        compared = [r for r in mine if r["fewer"] is not None]
        ratios = [(r["n_accepted"] + r["n_rejected"]) / r["n_fixed"] for r in compared]
        row = adaptive.sel(config=lab)
        ok = row["status"].values == "stable"
        spread = row["H_max_used"].values[ok] / row["H_min_used"].values[ok]
        tols = [float(t) for t in row["tol"].values]
        not_fewer = [
            {
                "tol": r["tol"],
                "how": r["how"],
                "H_max_used": float(row["H_max_used"].values[tols.index(r["tol"])]),
                "n_rejected": r["n_rejected"],
            }
            for r in mine
            if r["status"] == "stable" and not r["fewer"]
        ]
        out[str(lab)] = {
            "runs": len(mine),
            "compared": len(compared),
            "fewer": sum(bool(r["fewer"]) for r in compared),
            "ratio_min": min(ratios) if ratios else math.nan,
            "ratio_max": max(ratios) if ratios else math.nan,
            "rejected": sum(r["n_rejected"] for r in mine),
            "drift_ok": all(r["drift_max"] <= drift_tol for r in mine if r["status"] == "stable"),
            "H_spread_max": float(np.max(spread)) if spread.size else math.nan,
            "not_fewer": not_fewer,
            "H_limit": limit_of.get(str(lab), math.nan),
        }
    return out


def sufficient_rtol(ds, config, H, *, share: float = 0.01) -> float:
    """Loosest ``rtol`` from which on (every tighter one included) the integration effect is at most
    ``share`` of the error at the tightest tolerance (the yardstick); NaN if not even the next-tightest."""
    row = ds.sel(config=config, H=H)
    rtols = row["rtol"].values  # loose to tight
    effect = row["integration_effect"].values
    limit = share * float(row["error_max"].values[-1])
    best = math.nan
    for r, e in zip(rtols[::-1][1:], effect[::-1][1:]):  # tight to loose, the yardstick left out
        if not e <= limit:
            break
        best = float(r)
    return best


def equal_error_table(ds) -> list[dict]:
    """One row per adaptive run: its cost against the fixed H at equal error (the report's comparison)."""
    rows = []
    for i, lab in enumerate(ds["config"].values):
        for j, tol in enumerate(ds["tol"].values):
            st = str(ds["status"].values[i, j])
            if not st:
                continue
            n_acc = float(ds["n_macro_steps"].values[i, j])
            n_rej = float(ds["n_rejected_macro_steps"].values[i, j])
            n_fix = float(ds["n_macro_steps_fixed_equal_error"].values[i, j])
            rows.append(
                {
                    "config": str(lab),
                    "tol": float(tol),
                    "status": st,
                    "error_max": float(ds["error_max"].values[i, j]),
                    "drift_max": float(ds["drift_max"].values[i, j]),
                    "n_accepted": n_acc,
                    "n_rejected": n_rej,
                    "n_fixed": n_fix,
                    "how": str(ds["equal_error_how"].values[i, j]),
                    "fewer": bool(n_acc + n_rej < n_fix) if math.isfinite(n_fix) else None,
                    "cpu": float(ds["cpu_seconds"].values[i, j]),
                    "cpu_fixed": float(ds["cpu_seconds_fixed_equal_error"].values[i, j]),
                }
            )
    return rows

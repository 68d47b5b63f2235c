"""The ``convergence_order`` check kind (config/claims/convergence.yaml).

A claim selects curves of the panel datasets (:func:`icosim.convergence.curves.curves`)
and expects, per ``k``, an order ``p`` (the fitted order within a tolerance) or
instability at every step size.
"""

from __future__ import annotations

import numpy as np

from ..claims import CheckKind, Outcome, combine_holds, matches
from ..methods import parameters
from ..model import ParameterError
from .curves import curve_label, curves, stable_span
from .fit import local_slopes

__all__ = ["CHECKS", "check_convergence_order", "SELECT_KEYS", "EXPECT_KEYS"]


#: Keys of a ``convergence_order`` check's ``select`` and of each ``expect`` entry.
SELECT_KEYS = {"figure", "scheme", "decomposition", "method", "panel", "index"} | set(parameters())


EXPECT_KEYS = {"k", "order", "unstable", "observed", "observed_tolerance", "observed_second_half"}


def _is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x)


def _validate_order_check(label: str, params: dict):
    """Parameters of a ``convergence_order`` check (read with the claims file; errors name claim and key)."""
    label = f"{label}: check"
    tol = params["tolerance"]
    if not _is_number(tol) or tol <= 0:
        raise ParameterError(f"{label}.tolerance must be a number > 0, got {tol!r}")
    select = params["select"]
    if not isinstance(select, dict) or not select:
        raise ParameterError(f"{label}.select must be a non-empty mapping of {sorted(SELECT_KEYS)}")
    unknown = sorted(set(select) - SELECT_KEYS)
    if unknown:
        raise ParameterError(f"{label}.select: unknown key(s) {unknown}; allowed: {sorted(SELECT_KEYS)}")
    expect = params["expect"]
    if not isinstance(expect, list) or not expect:
        raise ParameterError(f"{label}.expect must be a non-empty list of {{k: ..., order: p | unstable: true}}")
    for j, exp in enumerate(expect):
        elabel = f"{label}.expect[{j}]"
        if not isinstance(exp, dict):
            raise ParameterError(f"{elabel} must be a mapping")
        unknown = sorted(set(exp) - EXPECT_KEYS)
        if unknown:
            raise ParameterError(f"{elabel}: unknown key(s) {unknown}; allowed: {sorted(EXPECT_KEYS)}")
        if not isinstance(exp.get("k"), int) or isinstance(exp.get("k"), bool) or exp["k"] < 0:
            raise ParameterError(f"{elabel}.k must be an integer >= 0, got {exp.get('k')!r}")
        if ("order" in exp) == bool(exp.get("unstable")):
            raise ParameterError(f"{elabel}: give exactly one of order: p or unstable: true")
        if "unstable" in exp and exp["unstable"] is not True:
            raise ParameterError(f"{elabel}.unstable must be true (or left out), got {exp['unstable']!r}")
        for key in ("order", "observed", "observed_second_half", "observed_tolerance"):
            if key in exp and not _is_number(exp[key]):
                raise ParameterError(f"{elabel}.{key} must be a number, got {exp[key]!r}")
        if "observed_tolerance" in exp and exp["observed_tolerance"] <= 0:
            raise ParameterError(f"{elabel}.observed_tolerance must be > 0")


def check_convergence_order(datasets, *, select: dict, expect: list, tolerance: float):
    """The paper's convergence claims (config/claims/convergence.yaml) on the panel datasets.

    Each expectation is checked on every curve ``select`` picks with its ``k``:

    * ``order: p`` -- pass if the fitted order is within ``tolerance`` of
      ``p``, fail otherwise; undecided if no order could be fitted (too few
      stable step sizes: the claim cannot be checked there).
    * ``unstable: true`` -- pass if unstable at every step size, fail if
      stable at every one, undecided if stable at some.

    The claim fails if any curve fails, passes if all pass, else is undecided;
    ``numbers["rows"]`` holds one record per curve.
    """
    recs = curves(datasets)
    rows = []
    for exp in expect:
        sel = {**select, "k": exp["k"]}
        matched = [r for r in recs if matches(r, sel)]
        if not matched:
            raise ParameterError(f"convergence_order: no curve matches {sel}")
        for rec in matched:
            row = {
                "curve": curve_label(rec),
                "k": rec["k"],
                "order": rec["order"],
                "order_second_half": rec["order_second_half"],
                "fit_H_min": rec["fit_H_min"],
                "fit_H_max": rec["fit_H_max"],
                "stable_H": stable_span(rec),
                "observed": exp.get("observed"),
            }
            # local slopes of the stable points from the fitted range upward (round-off floor left out)
            keep = ~rec["unstable"] & (rec["H"] >= rec["fit_H_min"] if np.isfinite(rec["fit_H_min"]) else True)
            slopes = local_slopes(rec["H"][keep], rec["nrmse"][keep])
            slopes = slopes[np.isfinite(slopes)]
            row["local_slopes"] = (float(slopes.min()), float(slopes.max())) if slopes.size else None
            if exp.get("unstable"):
                row["claimed"] = "unstable"
                n_u = int(rec["unstable"].sum())
                holds = True if n_u == rec["unstable"].size else False if n_u == 0 else None
            else:
                p = float(exp["order"])
                row["claimed"] = f"O(H^{p:g})"
                holds = None if not np.isfinite(rec["order"]) else bool(abs(rec["order"] - p) <= tolerance)
            row["verdict"] = {True: "pass", False: "fail"}.get(holds, "undecided")
            row["holds"] = holds
            rows.append(row)
    measured = "; ".join(
        f"{r['curve']}: {r['claimed']}, "
        + (
            f"stable H {r['stable_H']}"
            if r["claimed"] == "unstable" or not np.isfinite(r["order"])
            else f"fitted order {r['order']:.2f}"
        )
        + f" -> {r['verdict']}"
        for r in rows
    )
    holds = combine_holds(r.pop("holds") for r in rows)
    return Outcome(holds, measured, {"rows": rows, "tolerance": tolerance})


#: The convergence check kinds (collected by :mod:`icosim.checks`).
CHECKS = {"convergence_order": CheckKind(check_convergence_order, _validate_order_check, selectors=("select",))}

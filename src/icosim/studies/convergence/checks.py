"""The ``convergence_order`` check kind (config/claims/convergence.yaml).

A claim selects curves of the panel datasets (:func:`icosim.studies.convergence.curves.curves`)
and expects, per ``k``, an order ``p`` or instability at every step size.  An
order decides only where it is asymptotic (:mod:`icosim.order_fit`):

* asymptotic -- pass if within ``tolerance`` of ``p``, else fail;
* pre-asymptotic, unstable as H -> 0, too few points -- undecided, with the reason;
* unstable at every step size -- not applicable (``n/a``): the claim is about
  the order of a convergent scheme, and this curve has none.  It is listed, and
  a claim whose every curve is ``n/a`` is undecided.
"""

from __future__ import annotations

import numpy as np

from ...engine.methods import parameters
from ...errors import ParameterError
from ...verdicts import CheckKind, Outcome, combine_holds, matches, selector_text
from .curves import curve_label, curves, stable_span

__all__ = ["CHECKS", "check_convergence_order", "SELECT_KEYS", "EXPECT_KEYS"]


#: Keys of a ``convergence_order`` check's ``select`` and of each ``expect`` entry.
SELECT_KEYS = {"figure", "scheme", "decomposition", "method", "panel", "index"} | set(parameters())


EXPECT_KEYS = {"k", "order", "unstable", "observed", "observed_tolerance", "observed_second_half", "observed_startup"}

#: Per-curve verdicts; ``n/a`` (an order claim on a curve unstable at every H) does not count.
NOT_APPLICABLE = "n/a"


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
        for key in ("order", "observed", "observed_second_half", "observed_startup", "observed_tolerance"):
            if key in exp and not _is_number(exp[key]):
                raise ParameterError(f"{elabel}.{key} must be a number, got {exp[key]!r}")
        if "observed_tolerance" in exp and exp["observed_tolerance"] <= 0:
            raise ParameterError(f"{elabel}.observed_tolerance must be > 0")


def check_convergence_order(datasets, *, select: dict, expect: list, tolerance: float):
    """The paper's convergence claims (config/claims/convergence.yaml) on the panel datasets.

    Each expectation is checked on every curve ``select`` picks with its ``k``
    (module docstring for the per-curve rules).  The claim fails if any curve
    fails, passes if every applicable curve passes, else is undecided;
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
                "curve": curve_label(rec) + ("" if rec["scheme"] == "jacobi" else f", {rec['scheme']}"),
                "k": rec["k"],
                "order": rec["order"],
                "order_status": rec["order_status"],
                "reason": rec["fit_note"],
                "order_spread": rec["order_spread"],
                "order_second_half": rec["order_second_half"],
                "order_startup": rec["order_startup"],
                "fit_H_min": rec["fit_H_min"],
                "fit_H_max": rec["fit_H_max"],
                "stable_H": stable_span(rec),
                "observed": exp.get("observed"),
            }
            finite = rec["local_slope"][np.isfinite(rec["local_slope"])]
            row["local_slopes"] = (float(finite.min()), float(finite.max())) if finite.size else None
            if exp.get("unstable"):
                row["claimed"] = "unstable"
                n_u = int(rec["unstable"].sum())
                verdict = "pass" if n_u == rec["unstable"].size else "fail" if n_u == 0 else "undecided"
            else:
                p = float(exp["order"])
                row["claimed"] = f"O(H^{p:g})"
                if rec["order_status"] == "asymptotic":
                    verdict = "pass" if abs(rec["order"] - p) <= tolerance else "fail"
                elif rec["order_status"] == "unstable at every H":
                    verdict = NOT_APPLICABLE
                else:
                    verdict = "undecided"
            row["verdict"] = verdict
            rows.append(row)
    measured = "; ".join(_describe(r) for r in rows)
    applicable = [r["verdict"] for r in rows if r["verdict"] != NOT_APPLICABLE]
    holds = combine_holds({"pass": True, "fail": False}.get(v) for v in applicable) if applicable else None
    return Outcome(holds, measured, {"rows": rows, "tolerance": tolerance})


def _describe(r) -> str:
    """One curve of a claim in words: what was claimed, what the data decide, why."""
    head = f"{r['curve']}: {r['claimed']}, "
    if r["claimed"] == "unstable" or r["order_status"] in ("unstable at every H", "unstable as H -> 0"):
        what = f"stable H {r['stable_H']}" + (f" ({r['reason']})" if r["reason"] else "")
    elif r["order_status"] == "asymptotic":
        what = f"asymptotic order {r['order']:.2f} on [{r['fit_H_min']:.2g}, {r['fit_H_max']:.2g}] s"
    else:
        what = f"{r['order_status']}: {r['reason']}"
    return head + what + f" -> {r['verdict']}"


def _describe_order(p):
    claimed = "; ".join(
        f"k = {e['k']}: "
        + ("unstable at every H" if e.get("unstable") else f"order {e['order']:g} ± {p['tolerance']:g}")
        for e in p["expect"]
    )
    what = f"asymptotic order of every curve with {selector_text(p['select'])} ({claimed})"
    fails = "a curve's asymptotic order lies outside the tolerance, or a curve claimed unstable is stable at every H"
    return what, fails


#: The convergence check kinds (collected by :mod:`icosim.claims.registry`).
CHECKS = {
    "convergence_order": CheckKind(
        check_convergence_order, _validate_order_check, selectors=("select",), describe=_describe_order
    )
}

"""The check kinds of the signal-coupling study (config/claims/signals.yaml), on the case datasets of
:mod:`icosim.studies.signals.study` (attribute ``dataset: case``).

* ``signals_order`` -- per ``expect`` entry ``{k, order}``, the asymptotic order over ``H`` of every case
  ``select`` picks at that ``k``: pass if each is within ``tolerance`` of ``order``, fail if one is not, undecided
  if an order is not asymptotic (pre-asymptotic, unstable) or no case is picked;
* ``signals_growth`` -- every growth run of the cases ``select`` picks whose predicted verdict is ``verdict``:
  ``unstable``: the measured growth per macro step within ``tolerance`` of the predicted rho, relative to
  ``|rho - 1|`` (the growth exponent, not rho itself: an error of 5 % of rho would pass any rho near 1);
  ``stable``: the measured growth below 1; ``any``: every run predicted stable or unstable within ``tolerance``
  as under ``unstable``.  Undecided if no run has that predicted verdict or a growth is not finite;
* ``signals_ratio`` -- the errors of the cases ``select`` picks against those of ``against`` at the same ``k``
  and ``H`` (the step sizes both measured): pass if every ratio is below ``value``, fail if one is not,
  undecided if no ``k`` and ``H`` are common to both.

Reads datasets only (no unit is loaded): the claims machinery imports this module.
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import ParameterError
from ...verdicts import CheckKind, Outcome, check_expected_orders, combine_holds, select, selector_text

__all__ = ["CHECKS", "check_order", "check_growth", "check_ratio"]

_VERDICT = {True: "pass", False: "fail", None: "undecided"}


def _cases(datasets, selector):
    return select(datasets, {"dataset": "case", **selector})


def check_order(datasets, *, select: dict, expect: list, tolerance: float):
    """Per ``{k, order}``: each picked case's asymptotic order within ``tolerance`` of ``order``."""
    rows, holds = [], []
    for exp in expect:
        picked = _cases(datasets, {**select, "k": exp["k"]})
        if not picked:
            rows.append({"case": f"k = {exp['k']}", "verdict": "undecided", "why": "no case"})
            holds.append(None)
        for ds in picked:
            a = ds.attrs
            row = {"case": a["case"], "claimed": exp["order"], "order": float(a["order"]), "status": a["order_status"]}
            ok = abs(row["order"] - exp["order"]) <= tolerance if a["order_status"] == "asymptotic" else None
            row["verdict"] = _VERDICT[ok]
            rows.append(row)
            holds.append(ok)
    measured = "; ".join(
        f"{r['case']}: order {r['order']:.3f} ({r['status']}, claimed {r['claimed']:g}) -> {r['verdict']}"
        if "order" in r
        else f"{r['case']}: {r['why']} -> undecided"
        for r in rows
    )
    return Outcome(combine_holds(holds), measured, {"rows": rows, "tolerance": tolerance})


def check_growth(datasets, *, select: dict, verdict: str, tolerance: float | None = None):
    """Growth runs predicted ``verdict``: grow by the predicted rho (unstable, any) or decay (stable)."""
    rows, holds = [], []
    picked = _cases(datasets, select)
    for ds in picked:
        if "growth_H" not in ds.coords:
            continue
        for h, rho, v, g in zip(*(ds[n].values for n in ("growth_H", "growth_rho", "growth_verdict",
                                                           "measured_growth"))):  # fmt: skip
            if str(v) != verdict and not (verdict == "any" and str(v) in ("stable", "unstable")):
                continue
            rho, g = float(rho), float(g)
            if not (math.isfinite(rho) and math.isfinite(g)):
                ok, dev = None, float("nan")
            elif verdict != "stable":
                dev = abs(g - rho) / abs(rho - 1)
                ok = dev <= tolerance
            else:
                dev, ok = float("nan"), g < 1
            rows.append({"case": ds.attrs["case"], "H": float(h), "rho": rho, "growth": g, "deviation": dev,
                         "holds": ok})  # fmt: skip
            holds.append(ok)
    if not rows:
        what = "with a predicted verdict" if verdict == "any" else f"predicted {verdict}"
        why = f"no growth run {what} among the cases with {selector_text(select)}"
        return Outcome(None, why + ("" if picked else " (no such case)"), {"rows": []})
    parts = []
    for r in rows:
        text = f"{r['case']} at H = {r['H']:g} s: rho {r['rho']:.6f}, measured {r['growth']:.6f}"
        if verdict != "stable":
            text += f" (|growth - rho| / |rho - 1| = {r['deviation']:.3g})"
        parts.append(text)
    return Outcome(combine_holds(holds), "; ".join(parts), {"rows": rows})


def check_ratio(datasets, *, select: dict, against: dict, value: float):
    """Errors of ``select``'s cases over those of ``against``'s at every common ``k`` and ``H``: below ``value``."""
    rows, holds = [], []
    mine, theirs = _cases(datasets, select), _cases(datasets, against)
    for a in mine:
        for b in theirs:
            if int(a.attrs["k"]) != int(b.attrs["k"]):
                continue
            Ha, Hb = a["H"].values, b["H"].values
            for h in sorted(set(Ha.tolist()) & set(Hb.tolist())):
                ea = float(a["error"].values[Ha.tolist().index(h)])
                eb = float(b["error"].values[Hb.tolist().index(h)])
                ratio = ea / eb if math.isfinite(ea) and math.isfinite(eb) and eb > 0 else float("nan")
                ok = bool(ratio < value) if math.isfinite(ratio) else None
                rows.append({"case": a.attrs["case"], "against": b.attrs["case"], "H": h, "ratio": ratio, "holds": ok})
                holds.append(ok)
    if not rows:
        return Outcome(None, f"no k and H common to the cases with {selector_text(select)} and with "
                       f"{selector_text(against)}", {"rows": []})  # fmt: skip
    measured = "; ".join(f"{r['case']} / {r['against']} at H = {r['H']:g} s: {r['ratio']:.3g}" for r in rows)
    worst = float(np.nanmax([r["ratio"] for r in rows])) if any(math.isfinite(r["ratio"]) for r in rows) else np.nan
    return Outcome(combine_holds(holds), measured + f" (largest {worst:.3g}, claimed < {value:g})", {"rows": rows})


def _positive(label, params, key):
    v = params.get(key)
    if not isinstance(v, (int, float)) or isinstance(v, bool) or not v > 0:
        raise ParameterError(f"{label}: check.{key} must be a number > 0, got {v!r}")


def _validate_order(label, params):
    _positive(label, params, "tolerance")
    check_expected_orders(label, params["expect"])


def _validate_growth(label, params):
    if params["verdict"] != "stable":
        _positive(label, params, "tolerance")


def _describe_order(p):
    claimed = "; ".join(f"k = {e['k']}: order {e['order']:g} ± {p['tolerance']:g}" for e in p["expect"])
    return f"asymptotic order over H of the cases with {selector_text(p['select'])} ({claimed})", (
        "an asymptotic order lies outside the tolerance"
    )


def _describe_growth(p):
    what = f"growth runs predicted {p['verdict']} of the cases with {selector_text(p['select'])}"
    if p["verdict"] != "stable":
        return what + ", measured growth against predicted rho", (
            f"|growth - rho| > {p['tolerance']:g} |rho - 1| for a run"
        )
    return what, "a run predicted stable grows"


def _describe_ratio(p):
    what = f"error of the cases with {selector_text(p['select'])} over that with {selector_text(p['against'])}"
    return what + " at every common k and H", f"a ratio is not below {p['value']:g}"


#: check kind -> :class:`~icosim.verdicts.CheckKind`, collected by :mod:`icosim.claims.registry`.
CHECKS = {
    "signals_order": CheckKind(check_order, validate=_validate_order, selectors=("select",), describe=_describe_order),
    "signals_growth": CheckKind(
        check_growth,
        validate=_validate_growth,
        choices={"verdict": ("unstable", "stable", "any")},
        selectors=("select",),
        describe=_describe_growth,
    ),
    "signals_ratio": CheckKind(
        check_ratio,
        validate=lambda label, params: _positive(label, params, "value"),
        selectors=("select", "against"),
        describe=_describe_ratio,
    ),
}

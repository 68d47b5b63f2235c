"""The check kinds of the FMU part (config/claims/fmi.yaml), on the datasets of :mod:`icosim.studies.fmi.validation`.

* ``fmi_bound`` -- a number of each scene dataset ``select`` picks (the difference to the built-in model, the
  measured growth, its deviation from the predicted spectral radius) against a bound: pass if every picked
  dataset is within it, fail if one is not, undecided if none is picked or a number is not finite;
* ``fmi_orders`` -- per ``k``, the asymptotic order over ``H`` of the FMU runs against the claimed order (the
  linear study's) and against the built-in model's order on the same step sizes: pass if both orders are
  asymptotic and within the tolerances, fail if one is not within them, undecided if an order is not
  asymptotic.

Reads datasets only (no unit is loaded): the claims machinery imports this module.
"""

from __future__ import annotations

import math

from ...errors import ParameterError
from ...verdicts import CheckKind, Outcome, check_expected_orders, combine_holds, select, selector_text

__all__ = ["CHECKS", "check_bound", "check_orders", "QUANTITIES"]

#: Scene-dataset numbers a ``fmi_bound`` check may bound, and what they are.
QUANTITIES = {
    "builtin_difference": "difference to the built-in model",
    "builtin_force_difference": "joint-force difference to the built-in pendulum (relative)",
    "measured_growth": "measured growth per macro step",
    "growth_deviation": "|measured growth / predicted rho - 1|",
}
OPS = {"<": lambda a, b: a < b, "<=": lambda a, b: a <= b}


def _value(ds, quantity) -> float:
    return float(ds[quantity].values)


def check_bound(datasets, *, select: dict, quantity: str, op: str, value: float):
    """Every scene dataset ``select`` picks has ``quantity op value``."""
    picked = _select(datasets, {"dataset": "scene", **select})
    if not picked:
        return Outcome(None, f"no scene dataset with {selector_text(select)}", {"rows": []})
    rows, holds = [], []
    for ds in picked:
        x = _value(ds, quantity)
        ok = OPS[op](x, value) if math.isfinite(x) else None
        rows.append({"scene": ds.attrs["scene"], quantity: x, "holds": ok})
        holds.append(ok)
    measured = "; ".join(f"{r['scene']}: {r[quantity]:.3g}" for r in rows) + f" ({QUANTITIES[quantity]} {op} {value:g})"
    return Outcome(combine_holds(holds), measured, {"rows": rows})


def check_orders(datasets, *, select: dict, expect: list, tolerance: float, match: float):
    """Per ``expect`` entry ``{k, order}``: the FMU runs' asymptotic order within ``tolerance`` of ``order``
    and within ``match`` of the built-in model's on the same step sizes."""
    rows, holds = [], []
    for exp in expect:
        picked = _select(datasets, {"dataset": "orders", **select, "k": exp["k"]})
        if not picked:
            rows.append({"case": f"k = {exp['k']}", "verdict": "undecided", "why": "no dataset"})
            holds.append(None)
        for ds in picked:
            a = ds.attrs
            fmu, builtin = float(a["order_fmu"]), float(a["order_builtin"])
            row = {"case": a["case"], "claimed": exp["order"], "order_fmu": fmu, "order_builtin": builtin}
            if a["status_fmu"] != "asymptotic" or a["status_builtin"] != "asymptotic":
                ok, row["why"] = None, f"FMU {a['status_fmu']}, built-in {a['status_builtin']}"
            else:
                ok = abs(fmu - exp["order"]) <= tolerance and abs(fmu - builtin) <= match
            row["verdict"] = {True: "pass", False: "fail", None: "undecided"}[ok]
            rows.append(row)
            holds.append(ok)
    measured = "; ".join(
        f"{r['case']}: order {r['order_fmu']:.2f} (built-in {r['order_builtin']:.2f}, claimed {r['claimed']:g})"
        + (f" [{r['why']}]" if r.get("why") else "")
        + f" -> {r['verdict']}"
        if "order_fmu" in r
        else f"{r['case']}: {r['why']} -> undecided"
        for r in rows
    )
    return Outcome(combine_holds(holds), measured, {"rows": rows, "tolerance": tolerance, "match": match})


def _select(datasets, selector):
    return select(datasets, selector)


def _validate_bound(label, params):
    if params["quantity"] not in QUANTITIES:
        raise ParameterError(f"{label}: check.quantity must be one of {sorted(QUANTITIES)}, got {params['quantity']!r}")
    if not isinstance(params["value"], (int, float)) or isinstance(params["value"], bool):
        raise ParameterError(f"{label}: check.value must be a number, got {params['value']!r}")


def _validate_orders(label, params):
    for key in ("tolerance", "match"):
        v = params[key]
        if not isinstance(v, (int, float)) or isinstance(v, bool) or not v > 0:
            raise ParameterError(f"{label}: check.{key} must be a number > 0, got {v!r}")
    check_expected_orders(label, params["expect"])


def _describe_bound(p):
    what = f"{QUANTITIES[p['quantity']]} of every scene with {selector_text(p['select'])}"
    return what, f"a scene's value is not {p['op']} {p['value']:g}"


def _describe_orders(p):
    claimed = "; ".join(f"k = {e['k']}: order {e['order']:g} ± {p['tolerance']:g}" for e in p["expect"])
    what = f"asymptotic order over H of the FMU runs with {selector_text(p['select'])} ({claimed})"
    fails = f"an asymptotic order lies outside the tolerance, or differs from the built-in model's by more than {p['match']:g}"
    return what, fails


#: check kind -> :class:`~icosim.verdicts.CheckKind`, collected by :mod:`icosim.claims.registry`.
CHECKS = {
    "fmi_bound": CheckKind(
        check_bound,
        validate=_validate_bound,
        choices={"op": tuple(OPS)},
        selectors=("select",),
        describe=_describe_bound,
    ),
    "fmi_orders": CheckKind(check_orders, validate=_validate_orders, selectors=("select",), describe=_describe_orders),
}

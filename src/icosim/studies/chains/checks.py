"""The check kinds of the chain study (config/claims/chains.yaml), on the datasets of
:mod:`icosim.studies.chains.stability`, :mod:`~icosim.studies.chains.convergence` and
:mod:`~icosim.studies.chains.placement`.  ``where`` picks coordinates of the dataset (a value or a list each).

* ``chain_two_unit`` -- ``rho`` of the two-unit chains against the paper's two-mass model at every scanned ``H``:
  pass if every pair agrees within ``rtol`` (relative to ``max(1, rho)``) plus the float64 error estimate, fail
  if one does not, undecided if the data hold no two-unit chain of single masses;
* ``chain_order`` -- the orders over ``H``: ``expect: k+1`` against ``k + 1``, ``expect: two-unit`` against the
  two-unit chain's order with the same method, ``k`` and scheme; pass if every order is within ``tolerance``,
  fail if an asymptotic one is not, undecided where an order is not asymptotic;
* ``chain_trend`` -- ``H_max`` over ``n_units`` for every other combination: ``nonincreasing`` fails where a
  larger chain is stable at a step at or above the smaller one's unstable step (``H_max(N') >= H_unstable(N)``),
  ``nondecreasing`` where a smaller chain is (so both hold within the bisection's resolution); undecided where a
  search was not bisected (censored at the scan's end, no stable step, not served);
* ``chain_placement`` -- ``H_max`` over the places of the changed unit (``none`` included): ``same`` passes if
  every place's stable step lies below every other's unstable step, fails if one is at or above it; undecided
  where a search was not bisected.

Reads datasets only: the claims machinery imports this module.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from ...errors import ParameterError
from ...verdicts import CheckKind, Outcome, combine_holds

__all__ = ["CHECKS", "check_two_unit", "check_order", "check_trend", "check_placement", "DIMENSIONS"]

#: dataset -> the coordinates ``where`` may pick.
DIMENSIONS = {
    "stability": ("unit", "pattern", "n_units", "method", "k", "scheme"),
    "convergence": ("n_units", "method", "k", "scheme"),
    "placement": ("variant", "position", "method", "k", "scheme"),
}


def _dataset(datasets, name):
    picked = [ds for ds in datasets if ds.attrs.get("part") == "chains" and ds.attrs.get("dataset") == name]
    return picked[0] if picked else None


def _where(ds, where: dict):
    """``ds`` restricted to ``where``'s values (those it holds); None if a coordinate keeps none."""
    for key, value in where.items():
        values = value if isinstance(value, list) else [value]
        kept = [v for v in ds[key].values.tolist() if any(str(v) == str(w) for w in values)]
        if not kept:
            return None
        ds = ds.sel({key: kept})
    return ds


def _combos(ds, dims):
    """Every combination of the coordinates ``dims`` of ``ds``, as ``{dim: value}``."""
    values = [ds[d].values.tolist() for d in dims]
    return [dict(zip(dims, c)) for c in itertools.product(*values)]


def _label(combo) -> str:
    return ", ".join(f"{k} {' or '.join(map(str, v)) if isinstance(v, list) else v}" for k, v in combo.items())


def check_two_unit(datasets, *, where: dict, rtol: float):
    ds = _dataset(datasets, "stability")
    sub = None if ds is None or 2 not in ds["n_units"].values else _where(ds, where)
    if sub is None or 2 not in sub["n_units"].values:
        return Outcome(None, "undecided, because the data hold no two-unit chain with " + _label(where), {})
    two = sub.sel({"n_units": 2})
    rho, err, paper = two["rho"].values, two["rho_error"].values, two["rho_two_mass"].values
    both = np.isfinite(rho) & np.isfinite(paper)
    if not both.any():
        return Outcome(None, "undecided, because no two-unit chain there is one of single masses", {})
    dev = np.abs(rho - paper)[both]
    bound = (rtol * np.maximum(1.0, np.abs(paper)) + err)[both]
    worst = float(np.max(dev / bound))
    measured = (
        f"{int(both.sum())} points, largest |rho - rho_two_mass| {float(dev.max()):.3g} ({worst:.3g} of its bound)"
    )
    return Outcome(bool(worst <= 1.0), measured, {"points": int(both.sum()), "max_deviation": float(dev.max())})


def check_order(datasets, *, where: dict, expect: str, tolerance: float):
    ds = _dataset(datasets, "convergence")
    sub = None if ds is None else _where(ds, where)
    if sub is None or (expect == "two-unit" and 2 not in ds["n_units"].values):
        return Outcome(None, "undecided, because the data hold no such convergence curves", {"rows": []})
    rows, holds = [], []
    for combo in _combos(sub, DIMENSIONS["convergence"]):
        if expect == "two-unit" and combo["n_units"] == 2:
            continue
        order, status = float(sub["order"].sel(combo)), str(sub["order_status"].sel(combo).values)
        if expect == "k+1":
            target, target_status = combo["k"] + 1.0, "asymptotic"
        else:
            pair = {**combo, "n_units": 2}
            target, target_status = float(ds["order"].sel(pair)), str(ds["order_status"].sel(pair).values)
        ok = None if "asymptotic" != status or target_status != "asymptotic" else abs(order - target) <= tolerance
        rows.append({**combo, "order": order, "target": target, "holds": ok})
        holds.append(ok)
    if not rows:
        return Outcome(None, "undecided, because the data hold no chain of more than two units there", {"rows": []})
    measured = "; ".join(
        f"{_label({k: r[k] for k in DIMENSIONS['convergence']})}: {r['order']:.2f} vs {r['target']:.2f}"
        + ("" if r["holds"] is not None else " (not asymptotic)")
        for r in rows
    )
    return Outcome(combine_holds(holds), measured, {"rows": rows})


def _bisected(ds, combo) -> bool:
    return str(ds["status"].sel(combo).values) == "bisected"


def check_trend(datasets, *, where: dict, relation: str):
    ds = _dataset(datasets, "stability")
    sub = None if ds is None else _where(ds, where)
    if sub is None or sub["n_units"].size < 2:
        return Outcome(None, "undecided, because the data hold fewer than two chain lengths there", {"rows": []})
    others = [d for d in DIMENSIONS["stability"] if d != "n_units"]
    ns = sorted(sub["n_units"].values.tolist())
    rows, holds = [], []
    for combo in _combos(sub, others):
        for a, b in zip(ns, ns[1:]):
            ca, cb = {**combo, "n_units": a}, {**combo, "n_units": b}
            if not (_bisected(sub, ca) and _bisected(sub, cb)):
                ok = None
            elif relation == "nonincreasing":
                ok = float(sub["H_max"].sel(cb)) < float(sub["H_unstable"].sel(ca))
            else:
                ok = float(sub["H_max"].sel(ca)) < float(sub["H_unstable"].sel(cb))
            rows.append({**combo, "from": a, "to": b, "holds": ok})
            holds.append(ok)
    counts = {v: sum(1 for h in holds if h is v) for v in (True, False, None)}
    failing = [f"{_label({d: r[d] for d in others})}: N {r['from']} -> {r['to']}" for r in rows if r["holds"] is False]
    measured = (
        f"{counts[True]} steps in N hold, {counts[False]} do not, {counts[None]} undecided (a search not bisected)"
        + (f"; first that do not: {'; '.join(failing[:3])}" if failing else "")
    )
    return Outcome(combine_holds(holds), measured, {"rows": rows})


def check_placement(datasets, *, where: dict, relation: str):
    ds = _dataset(datasets, "placement")
    sub = None if ds is None else _where(ds, where)
    if sub is None or sub["position"].size < 2:
        return Outcome(None, "undecided, because the data hold fewer than two places there", {"rows": []})
    others = [d for d in DIMENSIONS["placement"] if d != "position"]
    rows, holds = [], []
    for combo in _combos(sub, others):
        places = sub["position"].values.tolist()
        cells = [{**combo, "position": p} for p in places]
        if not all(_bisected(sub, c) for c in cells):
            ok = None
        else:
            lo = [float(sub["H_max"].sel(c)) for c in cells]
            hi = [float(sub["H_unstable"].sel(c)) for c in cells]
            ok = all(lo[i] < hi[j] for i in range(len(cells)) for j in range(len(cells)))
        H = [float(sub["H_max"].sel(c)) for c in cells]
        rows.append({**combo, "H_max": dict(zip(places, H)), "holds": ok})
        holds.append(ok)
    measured = "; ".join(
        f"{_label({d: r[d] for d in others})}: H_max "
        + ", ".join(f"{p} {h:.3g}" if math.isfinite(h) else f"{p} -" for p, h in r["H_max"].items())
        for r in rows
    )
    return Outcome(combine_holds(holds), measured, {"rows": rows})


def _validate_where(dataset):
    def validate(label, params):
        where = params["where"]
        if not isinstance(where, dict):
            raise ParameterError(f"{label}: check.where must be a mapping of coordinate -> value(s)")
        for key in where:
            if key not in DIMENSIONS[dataset]:
                raise ParameterError(
                    f"{label}: check.where.{key}: must be one of {', '.join(DIMENSIONS[dataset])}, got {key!r}"
                )
        for key in ("rtol", "tolerance"):
            if key in params and (
                isinstance(params[key], bool) or not isinstance(params[key], (int, float)) or not params[key] > 0
            ):
                raise ParameterError(f"{label}: check.{key} must be a number > 0, got {params[key]!r}")

    return validate


def _where_text(p) -> str:
    return _label(p["where"]) or "every configuration"


#: check kind -> :class:`~icosim.verdicts.CheckKind`, collected by :mod:`icosim.claims.registry`.
CHECKS = {
    "chain_two_unit": CheckKind(
        check_two_unit,
        validate=_validate_where("stability"),
        describe=lambda p: (
            f"rho of the two-unit chains ({_where_text(p)}) against the paper's two-mass model at every scanned H",
            f"a pair differs by more than {p['rtol']:g} (relative) plus the float64 error estimate",
        ),
    ),
    "chain_order": CheckKind(
        check_order,
        validate=_validate_where("convergence"),
        choices={"expect": ("k+1", "two-unit")},
        describe=lambda p: (
            f"orders over H of the chains ({_where_text(p)}) against {p['expect']}",
            f"an asymptotic order differs by more than {p['tolerance']:g}",
        ),
    ),
    "chain_trend": CheckKind(
        check_trend,
        validate=_validate_where("stability"),
        choices={"relation": ("nonincreasing", "nondecreasing")},
        describe=lambda p: (
            f"the largest stable H over the number of units ({_where_text(p)})",
            f"a step in N where H_max is not {p['relation']} beyond the bisection's bracket",
        ),
    ),
    "chain_placement": CheckKind(
        check_placement,
        validate=_validate_where("placement"),
        choices={"relation": ("same",)},
        describe=lambda p: (
            f"the largest stable H over the place of the changed unit ({_where_text(p)})",
            "the brackets of two places do not overlap",
        ),
    ),
}

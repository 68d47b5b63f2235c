"""Check kinds of the stability claims (config/claims/stability.yaml).

They measure the share of stable grid points of panel datasets
(:mod:`icosim.stability.panels`); a difference between two shares is called
only if it exceeds the grid resolution ``1/(n - 1)`` (the change of the share
when the stability boundary moves by one grid spacing across the whole plot).
Smaller differences are ``undecided``: the grid cannot tell them from
discretisation.

============================  ==================================================
kind                          reads
============================  ==================================================
``stable_fraction``           every selected panel's stable share against a value
``compare``                   two groups of panels' mean stable shares
``trend``                     the stable share along an attribute (e.g. ``row``)
============================  ==================================================
"""

from __future__ import annotations

import math

import numpy as np

from ..claims import CheckKind, Outcome, combine_holds, select
from ..model import ParameterError

__all__ = ["CHECKS", "check_stable_fraction", "check_compare", "check_trend", "stable_share", "grid_resolution"]

_select = select  # the checks take a parameter called `select`


def grid_resolution(datasets) -> float:
    """``1/(n - 1)`` of the coarsest axis: the resolution of a stable share."""
    n = min(min(ds.sizes["lr1"], ds.sizes["li1"]) for ds in datasets)
    return 1.0 / (n - 1)


def _region_mask(ds, region):
    lr1 = ds["lr1"].values[:, None]
    li1 = ds["li1"].values[None, :]
    mask = np.ones((lr1.size, li1.size), dtype=bool)
    region = region or {}
    unknown = sorted(set(region) - {"lr1", "li1", "exclude_undamped"})
    if unknown:
        raise ParameterError(f"region: unknown key(s) {unknown}; allowed: lr1, li1, exclude_undamped")
    if "lr1" in region:
        lo, hi = region["lr1"]
        mask &= (lr1 >= lo) & (lr1 <= hi)
    if "li1" in region:
        lo, hi = region["li1"]
        mask &= (li1 >= lo) & (li1 <= hi)
    if region.get("exclude_undamped"):
        # lr1 = 0: both subsystems undamped, the model itself only marginally stable
        mask &= np.broadcast_to(lr1 < 0, mask.shape)
    return mask


def stable_share(ds, region=None) -> tuple[float, int, int]:
    """(share of stable points, stable count, point count) inside ``region``."""
    mask = _region_mask(ds, region)
    n = int(mask.sum())
    if n == 0:
        raise ParameterError(f"region {region} holds no grid point of figure {ds.attrs.get('figure')}")
    s = int(ds["stable"].values[mask].sum())
    return s / n, s, n


def _describe(ds) -> str:
    a = ds.attrs
    return f"Fig. {a.get('figure')} row {a.get('row')} k={a.get('k')}" + (" zoom" if a.get("view") == "zoom" else "")


def _nearest_unstable(ds, region):
    mask = _region_mask(ds, region) & ~ds["stable"].values.astype(bool)
    if not mask.any():
        return None
    LR, LI = np.meshgrid(ds["lr1"].values, ds["li1"].values, indexing="ij")
    return float(np.min(np.hypot(LR[mask], LI[mask])))


_OPS = {
    "==": lambda x, v: math.isclose(x, v, abs_tol=1e-12),
    ">=": lambda x, v: x >= v,
    "<=": lambda x, v: x <= v,
    ">": lambda x, v: x > v,
    "<": lambda x, v: x < v,
}


def check_stable_fraction(datasets, *, select: dict, op: str, value: float, region: dict | None = None):
    """Every selected panel's share of stable points (inside ``region``) satisfies ``op value``.

    ``op: "<", value: 1`` reads "has unstable points"; ``"==", 1`` "only
    stable points"; ``"==", 0`` "no stable point".
    """
    if op not in _OPS:
        raise ParameterError(f"stable_fraction: op must be one of {sorted(_OPS)}, got {op!r}")
    chosen = _select(datasets, select)
    if not chosen:
        return Outcome(None, f"no dataset matches {select}")
    parts, numbers, ok = [], {}, []
    for ds in chosen:
        share, s, n = stable_share(ds, region)
        good = _OPS[op](share, value)
        ok.append(good)
        nearest = _nearest_unstable(ds, region)
        entry = {"stable_share": share, "n_stable": s, "n_points": n}
        text = f"{_describe(ds)}: {s}/{n} stable ({share:.1%})"
        if nearest is not None and op in ("<", "<=") and value >= 1:
            entry["nearest_unstable_to_origin"] = nearest
            text += f", nearest unstable point at distance {nearest:.3g} from the origin"
        if region and region.get("exclude_undamped"):
            axis_mask = _region_mask(ds, {**region, "exclude_undamped": False})
            axis_mask &= np.broadcast_to(ds["lr1"].values[:, None] == 0, axis_mask.shape)
            if axis_mask.any():
                n_axis_unstable = int((~ds["stable"].values.astype(bool))[axis_mask].sum())
                entry["undamped_axis_unstable"] = n_axis_unstable
                text += f" (undamped axis lr1 = 0, not counted: {n_axis_unstable}/{int(axis_mask.sum())} unstable)"
        numbers[_describe(ds)] = entry
        parts.append(text)
    return Outcome(all(ok), "; ".join(parts), numbers)


def _group_share(datasets, selector, region):
    chosen = select(datasets, selector)
    if not chosen:
        return None, [], {}
    shares = {_describe(ds): stable_share(ds, region)[0] for ds in chosen}
    return float(np.mean(list(shares.values()))), chosen, shares


def check_compare(datasets, *, a: dict, b, relation: str, within: float | None = None, region: dict | None = None):
    """Compare the mean stable share of the panels selected by ``a`` with that of ``b``.

    ``relation``: ``greater`` (a more stable than b), ``less``, or ``similar``
    (``|a - b| <= within``).  ``b`` may be a list of selectors: the relation
    must then hold against each.  Differences within the grid resolution are
    undecided.
    """
    if relation not in ("greater", "less", "similar"):
        raise ParameterError(f"compare: relation must be greater, less or similar, got {relation!r}")
    if relation == "similar" and within is None:
        raise ParameterError("compare: relation 'similar' needs `within` (largest difference of stable shares)")
    sa, da, shares_a = _group_share(datasets, a, region)
    if sa is None:
        return Outcome(None, f"no dataset matches {a}")
    holds, texts, numbers = [], [], {"a": sa, "shares_a": shares_a, "b": []}
    for sel in b if isinstance(b, list) else [b]:
        sb, db, shares_b = _group_share(datasets, sel, region)
        if sb is None:
            holds.append(None)
            texts.append(f"no dataset matches {sel}")
            continue
        tol = grid_resolution(da + db)
        diff = sa - sb
        numbers["b"].append({"b": sb, "difference": diff, "resolution": tol, "shares_b": shares_b})
        text = (
            f"stable share {sa:.1%} ({_label(a)}) vs {sb:.1%} ({_label(sel)}), difference {diff:+.1%} "
            f"(resolution {tol:.1%})"
        )
        if relation == "similar":
            h = True if abs(diff) <= within else (False if abs(diff) > within + tol else None)
            text += f", similar means within {within:.0%}"
        else:
            sign = 1 if relation == "greater" else -1
            h = True if sign * diff > tol else (False if sign * diff < -tol else None)
        holds.append(h)
        texts.append(text)
    return Outcome(combine_holds(holds), "; ".join(texts), numbers)


def _label(selector):
    return ", ".join(f"{k}={v}" for k, v in selector.items() if k != "view")


def check_trend(
    datasets,
    *,
    select: dict,
    along: str,
    direction: str,
    region: dict | None = None,
    label: str | None = None,
):
    """The stable share changes monotonically along an attribute (e.g. ``row``).

    Groups the selected panels by ``along`` (ascending); ``direction`` is
    ``increasing`` or ``decreasing``.  Fails if any step goes the other way by
    more than the grid resolution; passes if, besides, the total change exceeds
    it; undecided otherwise.  ``label`` names the attribute shown for each
    group (e.g. ``mu``).
    """
    if direction not in ("increasing", "decreasing"):
        raise ParameterError(f"trend: direction must be increasing or decreasing, got {direction!r}")
    chosen = _select(datasets, select)
    if not chosen:
        return Outcome(None, f"no dataset matches {select}")
    groups = {}
    for ds in chosen:
        groups.setdefault(float(ds.attrs[along]), []).append(ds)
    if len(groups) < 2:
        return Outcome(None, f"only one value of {along} among {select}")
    keys = sorted(groups)
    shares = [float(np.mean([stable_share(ds, region)[0] for ds in groups[key]])) for key in keys]
    names = []
    for key in keys:
        attrs = groups[key][0].attrs
        names.append(f"{label}={float(attrs[label]):g}" if label else f"{along}={key:g}")
    tol = grid_resolution(chosen)
    sign = 1 if direction == "increasing" else -1
    steps = [sign * (b - a) for a, b in zip(shares, shares[1:])]
    total = sign * (shares[-1] - shares[0])
    if any(s < -tol for s in steps):
        holds = False
    elif total > tol:
        holds = True
    else:
        holds = None
    text = ", ".join(f"{n}: {s:.1%}" for n, s in zip(names, shares)) + f" (resolution {tol:.1%})"
    return Outcome(holds, text, {"groups": dict(zip(names, shares)), "resolution": tol})


REGION_KEYS = ("lr1", "li1", "exclude_undamped")


def _validate_region(label: str, params: dict):
    region = params.get("region")
    if region is None:
        return
    if not isinstance(region, dict):
        raise ParameterError(f"{label}: check.region must be a mapping of attribute -> value")
    unknown = sorted(set(region) - set(REGION_KEYS))
    if unknown:
        raise ParameterError(f"{label}: check.region has unknown key(s) {unknown}; allowed: lr1, li1, exclude_undamped")


def _validate_compare(label: str, params: dict):
    _validate_region(label, params)
    if params.get("relation") == "similar" and params.get("within") is None:
        raise ParameterError(f"{label}: check (compare) with relation 'similar' needs `within`")


#: The stability check kinds (collected by :mod:`icosim.checks`).
CHECKS = {
    "stable_fraction": CheckKind(
        check_stable_fraction, _validate_region, choices={"op": ("==", ">=", "<=", ">", "<")}, selectors=("select",)
    ),
    "compare": CheckKind(
        check_compare,
        _validate_compare,
        choices={"relation": ("greater", "less", "similar")},
        selectors=("a", "b"),
        selector_lists=("b",),
    ),
    "trend": CheckKind(
        check_trend, _validate_region, choices={"direction": ("increasing", "decreasing")}, selectors=("select",)
    ),
}

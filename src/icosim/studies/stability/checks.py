"""Check kinds of the stability claims (config/claims/stability.yaml).

They measure the share of stable grid points of panel datasets
(:mod:`icosim.studies.stability.panels`); a difference between two shares is called
only if it exceeds the grid resolution ``1/(n - 1)`` (the change of the share
when the stability boundary moves by one grid spacing across the whole plot).
Smaller differences are ``undecided``: the grid cannot tell them from
discretisation.

Marginal (and undecided) points -- the proven enclosure of ``rho`` contains 1
-- are neither counted stable nor unstable: a share is an interval from "none
of them stable" to "all of them stable", and a claim whose verdict depends on
where in that interval the truth lies is ``undecided``.  Each claim reports how
many of the points it uses are certified and how many are marginal.

============================  ==================================================
kind                          reads
============================  ==================================================
``stable_fraction``           every selected panel's stable share against a value
``compare``                   two groups of panels' mean stable shares
``trend``                     the stable share along an attribute (e.g. ``row``)
``pointwise``                 two groups of panels' verdicts, point by point
                              (:mod:`icosim.studies.stability.pointwise`)
============================  ==================================================
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...engine.spectral.policy import VERDICTS
from ...errors import ParameterError
from ...verdicts import CheckKind, Outcome, combine_holds, select, selector_text
from .pointwise import RELATIONS, check_pointwise, describe_pointwise, validate_pointwise
from .regions import region_mask, validate_region, verdict_masks

__all__ = [
    "CHECKS",
    "check_stable_fraction",
    "check_compare",
    "check_trend",
    "stable_share",
    "Share",
    "grid_resolution",
    "PANEL_VARIABLES",
]

_select = select  # the checks take a parameter called `select`


def grid_resolution(datasets) -> float:
    """``1/(n - 1)`` of the coarsest axis: the resolution of a stable share."""
    n = min(min(np.asarray(ds["lr1"]).size, np.asarray(ds["li1"]).size) for ds in datasets)
    return 1.0 / (n - 1)


@dataclass(frozen=True)
class Share:
    """Stable points inside a region: ``stable`` proven (or float64) stable, ``open`` marginal or
    undecided (``undecided`` of them), ``certified`` decided by a proof, out of ``n``.  The share lies in
    ``[low, high]``."""

    stable: int
    open: int
    certified: int
    n: int
    undecided: int = 0

    @property
    def low(self) -> float:
        return self.stable / self.n

    @property
    def high(self) -> float:
        return (self.stable + self.open) / self.n

    def text(self) -> str:
        core = f"{self.stable}/{self.n} stable ({self.low:.1%})"
        marginal = self.open - self.undecided
        if self.open:
            parts = [f"{marginal} marginal"] * bool(marginal) + [f"{self.undecided} undecided"] * bool(self.undecided)
            core += f" + {' + '.join(parts)} (up to {self.high:.1%})"
        return core


def stable_share(ds, region=None) -> Share:
    """The stable points inside ``region`` as a :class:`Share`."""
    mask = region_mask(ds, region)
    n = int(mask.sum())
    if n == 0:
        raise ParameterError(f"region {region} holds no grid point of figure {ds.attrs.get('figure')}")
    stable, unstable = verdict_masks(ds)
    certified = np.asarray(ds["certified"]).astype(bool) if "certified" in ds else np.zeros(mask.shape, bool)
    undecided = (
        np.asarray(ds["verdict"]) == VERDICTS.index("undecided") if "verdict" in ds else np.zeros(mask.shape, bool)
    )
    s, u = int(stable[mask].sum()), int(unstable[mask].sum())
    return Share(s, n - s - u, int(certified[mask].sum()), n, int(undecided[mask].sum()))


def _holds(a: bool, b: bool):
    """One verdict from the two ends of an interval: True/False if both agree, else None (undecided)."""
    return a if a == b else None


def _describe(ds) -> str:
    a = ds.attrs
    return f"Fig. {a.get('figure')} row {a.get('row')} k={a.get('k')}" + (" zoom" if a.get("view") == "zoom" else "")


def _nearest_unstable(ds, region):
    mask = region_mask(ds, region) & verdict_masks(ds)[1]
    if not mask.any():
        return None
    LR, LI = np.meshgrid(np.asarray(ds["lr1"]), np.asarray(ds["li1"]), indexing="ij")
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
        share = stable_share(ds, region)
        good = _holds(_OPS[op](share.low, value), _OPS[op](share.high, value))
        ok.append(good)
        nearest = _nearest_unstable(ds, region)
        entry = {
            "stable_share": share.low,
            "stable_share_high": share.high,
            "n_stable": share.stable,
            "n_marginal": share.open - share.undecided,
            "n_undecided": share.undecided,
            "n_certified": share.certified,
            "n_points": share.n,
        }
        text = f"{_describe(ds)}: {share.text()}"
        if nearest is not None and op in ("<", "<=") and value >= 1:
            entry["nearest_unstable_to_origin"] = nearest
            text += f", nearest unstable point at distance {nearest:.3g} from the origin"
        if region and region.get("exclude_undamped"):
            axis_mask = region_mask(ds, {**region, "exclude_undamped": False})
            axis_mask &= np.broadcast_to(np.asarray(ds["lr1"])[:, None] == 0, axis_mask.shape)
            if axis_mask.any():
                stable, unstable = verdict_masks(ds)
                n_axis_unstable, n_axis_marginal = (
                    int(unstable[axis_mask].sum()),
                    int((~stable & ~unstable)[axis_mask].sum()),
                )
                entry["undamped_axis_unstable"] = n_axis_unstable
                entry["undamped_axis_marginal"] = n_axis_marginal
                text += (
                    f" (undamped axis lr1 = 0, not counted: {n_axis_unstable} unstable, {n_axis_marginal} marginal "
                    f"of {int(axis_mask.sum())})"
                )
        if region and region.get("exclude_origin"):
            text += _origin_text(ds, entry)
        numbers[_describe(ds)] = entry
        parts.append(text)
    return Outcome(combine_holds(ok), "; ".join(parts) + _certified_text(chosen, region), numbers)


def _origin_text(ds, entry: dict) -> str:
    """The verdict at the origin lr1 = li1 = 0 (left out of the share), if the grid holds it."""
    i, j = np.flatnonzero(np.asarray(ds["lr1"]) == 0), np.flatnonzero(np.asarray(ds["li1"]) == 0)
    if not (i.size and j.size):
        return ""
    stable, unstable = verdict_masks(ds)
    at = (i[0], j[0])
    verdict = "stable" if stable[at] else "unstable" if unstable[at] else "marginal"
    entry["origin_verdict"] = verdict
    return f" (origin lr1 = li1 = 0, free masses where rho >= 1 for every scheme, not counted: {verdict})"


def _certified_text(chosen, region) -> str:
    """How many of the points a claim uses are certified (proven) and how many are marginal."""
    shares = [stable_share(ds, region) for ds in chosen]
    n, c, m = sum(x.n for x in shares), sum(x.certified for x in shares), sum(x.open - x.undecided for x in shares)
    u = sum(x.undecided for x in shares)
    return f" [{n} points used: {c} certified, {m} marginal" + (f", {u} undecided]" if u else "]")


def _group_share(datasets, selector, region):
    """Mean share interval ``(low, high)`` of the panels ``selector`` picks, the panels, and per-panel shares."""
    chosen = select(datasets, selector)
    if not chosen:
        return None, [], {}
    shares = {_describe(ds): stable_share(ds, region) for ds in chosen}
    low = float(np.mean([x.low for x in shares.values()]))
    high = float(np.mean([x.high for x in shares.values()]))
    return (low, high), chosen, {key: x.low for key, x in shares.items()}


def check_compare(
    datasets,
    *,
    a: dict,
    b,
    relation: str,
    within: float | None = None,
    by: float = 0.0,
    region: dict | None = None,
):
    """Compare the mean stable share of the panels selected by ``a`` with that of ``b``.

    ``relation``: ``greater`` (a more stable than b), ``less``, or ``similar``
    (``|a - b| <= within``).  ``by`` (greater, less): the difference must be at
    least this (e.g. 0.1 for "notably": ten points of stable share).  ``b`` may
    be a list of selectors: the relation must then hold against each.
    Differences within the grid resolution are undecided, and so are relations
    that the marginal points could turn.
    """
    if relation not in ("greater", "less", "similar"):
        raise ParameterError(f"compare: relation must be greater, less or similar, got {relation!r}")
    if relation == "similar" and within is None:
        raise ParameterError("compare: relation 'similar' needs `within` (largest difference of stable shares)")
    sa, da, shares_a = _group_share(datasets, a, region)
    if sa is None:
        return Outcome(None, f"no dataset matches {a}")
    holds, texts, numbers, used = [], [], {"a": sa[0], "a_high": sa[1], "shares_a": shares_a, "b": []}, list(da)
    for sel in b if isinstance(b, list) else [b]:
        sb, db, shares_b = _group_share(datasets, sel, region)
        if sb is None:
            holds.append(None)
            texts.append(f"no dataset matches {sel}")
            continue
        used += db
        tol = grid_resolution(da + db)
        lo, hi = sa[0] - sb[1], sa[1] - sb[0]  # the difference, over every way the marginal points may go
        diff = sa[0] - sb[0]
        numbers["b"].append(
            {
                "b": sb[0],
                "b_high": sb[1],
                "difference": diff,
                "difference_range": [lo, hi],
                "resolution": tol,
                "shares_b": shares_b,
            }
        )
        text = (
            f"stable share {_fmt(sa)} ({_label(a)}) vs {_fmt(sb)} ({_label(sel)}), difference {diff:+.1%} "
            f"(resolution {tol:.1%})"
        )
        if relation == "similar":
            worst, best = max(abs(lo), abs(hi)), (0.0 if lo <= 0 <= hi else min(abs(lo), abs(hi)))
            h = True if worst <= within else (False if best > within + tol else None)
            text += f", similar means within {within:.0%}"
        else:
            sign = 1 if relation == "greater" else -1
            lo_s, hi_s = sorted((sign * lo, sign * hi))
            h = True if lo_s > max(tol, by) else (False if hi_s < by - tol else None)
            if by:
                text += f", {relation} by at least {by:.0%} claimed"
        holds.append(h)
        texts.append(text)
    return Outcome(combine_holds(holds), "; ".join(texts) + _certified_text(used, region), numbers)


def _fmt(share) -> str:
    low, high = share
    return f"{low:.1%}" if high == low else f"{low:.1%}–{high:.1%}"


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
    lows = [float(np.mean([stable_share(ds, region).low for ds in groups[key]])) for key in keys]
    highs = [float(np.mean([stable_share(ds, region).high for ds in groups[key]])) for key in keys]
    names = []
    for key in keys:
        attrs = groups[key][0].attrs
        names.append(f"{label}={float(attrs[label]):g}" if label else f"{along}={key:g}")
    tol = grid_resolution(chosen)
    sign = 1 if direction == "increasing" else -1

    def steps(first, second):  # the change from one group to the next, in the claimed direction
        return [sign * (b - a) for a, b in zip(first, second[1:])]

    # the worst and the best case over where the marginal points fall
    worst = [min(x, y) for x, y in zip(steps(lows, highs), steps(highs, lows))]
    best = [max(x, y) for x, y in zip(steps(lows, highs), steps(highs, lows))]
    total_worst = min(sign * (highs[-1] - lows[0]), sign * (lows[-1] - highs[0]))
    if any(s < -tol for s in best):
        holds = False
    elif all(s >= -tol for s in worst) and total_worst > tol:
        holds = True
    else:
        holds = None
    text = ", ".join(f"{n}: {_fmt((lo, hi))}" for n, lo, hi in zip(names, lows, highs)) + f" (resolution {tol:.1%})"
    return Outcome(holds, text + _certified_text(chosen, region), {"groups": dict(zip(names, lows)), "resolution": tol})


def _validate_compare(label: str, params: dict):
    validate_region(label, params)
    if params.get("relation") == "similar" and params.get("within") is None:
        raise ParameterError(f"{label}: check (compare) with relation 'similar' needs `within`")
    by = params.get("by", 0)
    if not isinstance(by, (int, float)) or isinstance(by, bool) or not 0 <= by <= 1:
        raise ParameterError(f"{label}: check.by must be a share difference in [0, 1], got {by!r}")
    if by and params.get("relation") == "similar":
        raise ParameterError(f"{label}: check.by goes with relation greater or less, not similar (use within)")


def _region_text(region) -> str:
    if not region:
        return ""
    parts = [f"{axis} in [{region[axis][0]:g}, {region[axis][1]:g}]" for axis in ("lr1", "li1") if axis in region]
    parts += ["damped points only (lr1 < 0)"] * bool(region.get("exclude_undamped"))
    parts += ["the origin left out"] * bool(region.get("exclude_origin"))
    return " inside " + ", ".join(parts)


def _describe_stable_fraction(p):
    what = f"stable share of every panel with {selector_text(p['select'])}{_region_text(p.get('region'))} {p['op']} {p['value']:g}"
    return what, f"a selected panel's share fails {p['op']} {p['value']:g} whichever way its marginal points go"


def _describe_compare(p):
    b = selector_text(p["b"])
    region = _region_text(p.get("region"))
    what = f"mean stable share of ({selector_text(p['a'])}) against ({b}){region}: {p['relation']}"
    if p["relation"] == "similar":
        what += f" within {p['within']:.0%}"
        fails = f"the shares differ by more than {p['within']:.0%} plus one grid spacing"
    else:
        word = "more" if p["relation"] == "greater" else "less"
        by = p.get("by", 0)
        what += f" by at least {by:.0%}" if by else ""
        fails = (
            f"a is not {word} stable than b by {by:.0%} or more (short by more than one grid spacing)"
            if by
            else f"a is {'less' if word == 'more' else 'more'} stable than b by more than one grid spacing"
        )
    return what, fails


def _describe_trend(p):
    what = f"stable share of {selector_text(p['select'])}{_region_text(p.get('region'))} along {p['along']}: {p['direction']}"
    return what, "a step goes the other way by more than one grid spacing (or the whole change is within it)"


#: The stability check kinds (collected by :mod:`icosim.claims.registry`).
CHECKS = {
    "stable_fraction": CheckKind(
        check_stable_fraction,
        validate_region,
        choices={"op": ("==", ">=", "<=", ">", "<")},
        selectors=("select",),
        describe=_describe_stable_fraction,
    ),
    "compare": CheckKind(
        check_compare,
        _validate_compare,
        choices={"relation": ("greater", "less", "similar")},
        selectors=("a", "b"),
        selector_lists=("b",),
        describe=_describe_compare,
    ),
    "pointwise": CheckKind(
        check_pointwise,
        validate_pointwise,
        choices={"relation": RELATIONS},
        selectors=("a", "b"),
        describe=describe_pointwise,
    ),
    "trend": CheckKind(
        check_trend,
        validate_region,
        choices={"direction": ("increasing", "decreasing")},
        selectors=("select",),
        describe=_describe_trend,
    ),
}

#: The panel variables the check kinds read (the claims job reads only these: :func:`icosim.io.netcdf.open_variables`).
PANEL_VARIABLES = ("lr1", "li1", "rho", "stable", "verdict", "certified")

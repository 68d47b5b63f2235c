"""Point-by-point comparison of stability panels: the check kind ``pointwise``.

A statement that two stable regions are *the same* (or that one lies within
the other) is a statement about every grid point, not about the shares of
stable points: two regions of equal area may lie in different places.  This
check pairs the panels two selectors pick (by the attributes ``pair_by``:
the same method, decomposition, row, ``k`` and view, say) and compares their
verdicts at every grid point of a region.

Each point has one of four verdicts (:data:`icosim.engine.spectral.policy.VERDICTS`):
stable ``S``, unstable ``U``, marginal ``M`` (the proven enclosure of ``rho``
contains 1 at the precision cap) or undecided ``X``.  Per point:

==============  ===================================  =====================================
relation        holds                                 fails
==============  ===================================  =====================================
``same``        both verdicts equal (not ``X``)       one ``S``, the other ``U``
``subset``      ``a`` not stable, or ``b`` stable;     ``a`` ``S`` and ``b`` ``U``
                both ``M``
==============  ===================================  =====================================

Every other pair of verdicts (one marginal or undecided, the other not) is
*open*: the data cannot tell.  A claim holds if it holds at every point; it
fails if it fails at one point (the points are listed); otherwise it is
undecided.  ``proper_subset`` is ``subset`` plus at least one point where ``b``
is stable and ``a`` unstable; ``differ`` is the negation of ``same`` (it holds
where ``same`` fails: at least one point stable in one panel and unstable in
the other).

>>> import numpy as np, xarray as xr
>>> def panel(verdicts, **attrs):
...     v = np.array(verdicts, dtype=np.int8)
...     return xr.Dataset({"verdict": (("lr1", "li1"), v), "rho": (("lr1", "li1"), 0.5 + v)},
...                       coords={"lr1": [-1.0, 0.0], "li1": [0.0, 1.0]}, attrs={"row": 1, **attrs})
>>> a = panel([[0, 0], [1, 2]], scheme="gs")  # 0 stable, 1 unstable, 2 marginal
>>> b = panel([[0, 1], [1, 2]], scheme="jacobi")
>>> check_pointwise([a, b], a={"scheme": "gs"}, b={"scheme": "jacobi"}, relation="same", pair_by=["row"]).holds
False
>>> check_pointwise([a, b], a={"scheme": "jacobi"}, b={"scheme": "gs"}, relation="subset", pair_by=["row"]).holds
True
"""

from __future__ import annotations

import numpy as np

from ...engine.spectral.policy import VERDICTS
from ...errors import ParameterError
from ...verdicts import Outcome, combine_holds, select, selector_text
from .regions import region_mask, validate_region, verdict_masks

__all__ = ["check_pointwise", "describe_pointwise", "point_verdicts", "RELATIONS", "PAIR_BY", "MAX_LISTED"]

#: Relations between the verdicts of two paired panels.
RELATIONS = ("same", "differ", "subset", "proper_subset")
#: Attributes that pair a panel of ``a`` with one of ``b`` unless a claim says otherwise.
PAIR_BY = ("method", "decomposition", "row", "k", "view")
#: Differing points listed in a verdict's text (all of them are in its numbers, up to :data:`MAX_RECORDED`).
MAX_LISTED = 6
MAX_RECORDED = 200

_LETTERS = np.array(["S", "U", "M", "X"])  # stable, unstable, marginal, undecided


def point_verdicts(ds) -> np.ndarray:
    """Per grid point ``"S"``, ``"U"``, ``"M"`` or ``"X"`` (a panel without verdicts: ``S`` or ``U``)."""
    stable, unstable = verdict_masks(ds)
    code = np.full(stable.shape, 3)
    code[stable], code[unstable] = 0, 1
    if "verdict" in ds:
        code[np.asarray(ds["verdict"]) == VERDICTS.index("marginal")] = 2
    return _LETTERS[code]


def _relation_per_point(va, vb, relation):
    """Per point: 1 holds, 0 fails, -1 open."""
    out = np.full(va.shape, -1)
    if relation == "same":
        out[(va == vb) & (va != "X")] = 1
        out[((va == "S") & (vb == "U")) | ((va == "U") & (vb == "S"))] = 0
    else:  # subset: every point stable in a is stable in b
        out[(va == "U") | (vb == "S") | ((va == "M") & (vb == "M"))] = 1
        out[(va == "S") & (vb == "U")] = 0
    return out


def _key(ds, pair_by):
    missing = [name for name in pair_by if name not in ds.attrs]
    if missing:
        raise ParameterError(f"pointwise: panel {ds.attrs.get('title', '?')} has no attribute(s) {missing} to pair by")
    return tuple(str(ds.attrs[name]) for name in pair_by)


def _group(datasets, selector, pair_by, side):
    groups = {}
    for ds in select(datasets, selector):
        key = _key(ds, pair_by)
        if key in groups:
            raise ParameterError(
                f"pointwise: {side} = {selector} picks two panels with {dict(zip(pair_by, key))}; "
                f"add an attribute to pair_by or narrow the selector"
            )
        groups[key] = ds
    return groups


def _describe(key, pair_by) -> str:
    return ", ".join(f"{name} {value}" for name, value in zip(pair_by, key))


def _points(ds, mask, va, vb, rho_a, rho_b):
    lr1, li1 = np.meshgrid(np.asarray(ds["lr1"]), np.asarray(ds["li1"]), indexing="ij")
    return [
        {
            "lr1": float(lr1[i, j]),
            "li1": float(li1[i, j]),
            "a": str(va[i, j]),
            "b": str(vb[i, j]),
            "rho_a": float(rho_a[i, j]),
            "rho_b": float(rho_b[i, j]),
        }
        for i, j in zip(*np.nonzero(mask))
    ]


def check_pointwise(datasets, *, a: dict, b: dict, relation: str, pair_by: list | None = None, region=None):
    """Compare the verdicts of paired panels point by point (module docstring).

    ``a`` and ``b`` select the panels; ``pair_by`` (default :data:`PAIR_BY`)
    names the attributes a pair shares.  Every panel of ``a`` needs a partner
    in ``b`` on the same grid.
    """
    if relation not in RELATIONS:
        raise ParameterError(f"pointwise: relation must be one of {', '.join(RELATIONS)}, got {relation!r}")
    pair_by = tuple(pair_by or PAIR_BY)
    group_a, group_b = _group(datasets, a, pair_by, "a"), _group(datasets, b, pair_by, "b")
    if not group_a:
        return Outcome(None, f"no dataset matches {a}")
    base = "same" if relation in ("same", "differ") else "subset"
    holds, texts, numbers = [], [], {}
    # name a pair by the attributes the selector leaves open (the fixed ones are the claim's own words)
    shown = [i for i, name in enumerate(pair_by) if isinstance(a.get(name), list) or name not in a]
    for key, da in sorted(group_a.items()):
        label = _describe([key[i] for i in shown], [pair_by[i] for i in shown]) or "panel"
        db = group_b.get(key)
        if db is None:
            holds.append(None)
            texts.append(f"{label}: no panel of b = {b}")
            continue
        if not (
            np.array_equal(np.asarray(da["lr1"]), np.asarray(db["lr1"]))
            and np.array_equal(np.asarray(da["li1"]), np.asarray(db["li1"]))
        ):
            holds.append(None)
            texts.append(f"{label}: the two panels lie on different grids")
            continue
        mask = region_mask(da, region)
        va, vb = point_verdicts(da), point_verdicts(db)
        per_point = np.where(mask, _relation_per_point(va, vb, base), 1)
        failed, open_ = (per_point == 0) & mask, (per_point == -1) & mask
        # b stable where a is unstable: what makes a subset proper
        narrower = mask & (va == "U") & (vb == "S")
        h = False if failed.any() else (None if open_.any() else True)
        if relation == "proper_subset" and h is True and not narrower.any():
            h = False
        if relation == "differ":  # per pair: the panels differ where "same" fails
            h = None if h is None else not h
        holds.append(h)
        rho_a, rho_b = np.asarray(da["rho"]), np.asarray(db["rho"])
        bad = _points(da, failed, va, vb, rho_a, rho_b)
        entry = {
            "n_points": int(mask.sum()),
            "n_failing": int(failed.sum()),
            "n_open": int(open_.sum()),
            "n_b_stable_a_unstable": int(narrower.sum()),
            "failing_points": bad[:MAX_RECORDED],
            "open_points": _points(da, open_, va, vb, rho_a, rho_b)[:MAX_RECORDED],
        }
        numbers[label] = entry
        text = f"{label}: {entry['n_points']} points, {entry['n_failing']} contradict, {entry['n_open']} open"
        text += f" ({entry['n_b_stable_a_unstable']} stable only in b"
        if base == "same":
            entry["n_a_stable_b_unstable"] = int((mask & (va == "S") & (vb == "U")).sum())
            text += f", {entry['n_a_stable_b_unstable']} only in a"
        text += ")"
        if bad:
            listed = ", ".join(
                f"({p['lr1']:g}, {p['li1']:g}) {p['a']}/{p['b']} rho {p['rho_a']:.4g}/{p['rho_b']:.4g}"
                for p in bad[:MAX_LISTED]
            )
            text += f" [{listed}{', ...' if len(bad) > MAX_LISTED else ''}]"
        texts.append(text)
    return Outcome(combine_holds(holds), "; ".join(texts), numbers)


def validate_pointwise(label: str, params: dict):
    validate_region(label, params)
    pair_by = params.get("pair_by")
    if pair_by is not None and (not isinstance(pair_by, list) or not all(isinstance(p, str) for p in pair_by)):
        raise ParameterError(f"{label}: check.pair_by must be a list of attribute names, got {pair_by!r}")


#: What makes a pointwise claim fail, per relation.
FAILS_IF = {
    "same": "a grid point is stable in one panel and unstable in its partner",
    "differ": "every grid point has the same verdict in both panels",
    "subset": "a grid point is stable in a and unstable in b",
    "proper_subset": "a grid point is stable in a and unstable in b, or no point is stable only in b",
}


def describe_pointwise(p):
    pair_by = ", ".join(p.get("pair_by") or PAIR_BY)
    what = (
        f"verdicts of ({selector_text(p['a'])}) and ({selector_text(p['b'])}) point by point, panels paired by "
        f"{pair_by}{' inside ' + str(p['region']) if p.get('region') else ''}: {p['relation'].replace('_', ' ')}"
    )
    return what, FAILS_IF[p["relation"]]

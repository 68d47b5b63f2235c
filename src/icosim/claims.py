"""The paper's claims as data, evaluated against result datasets.

A *claim* is a plain mapping (kept in ``config/claims/<part>.yaml``)::

    id: wm_ff_k2_unstable_near_origin       # unique, stable name
    source: Sect. 3.1.2; Sect. 5            # where the paper says it
    statement: The weighted multiplier ... # the paper's claim in words
    figures: ["10"]                         # figures whose data decide it
    check: {kind: stable_fraction, select: {...}, op: "<", value: 1, ...}
    each: {k: [1, 2]}                       # optional: evaluate once per value
    ci: true                                # the reduced CI grid must reproduce `reference`
    reference: pass                         # verdict of the full-resolution run (recorded)
    note: how the words were turned into a check

One mechanism serves every part: the stability checks are defined here, the
convergence checks in :mod:`icosim.convergence` (``convergence_order``), the
pendulum's in :mod:`icosim.pendulum` (``pendulum_stability``); each registers
its kinds with :func:`register_check`.  :func:`parse_claims` validates every
claims file the same way, :func:`evaluate` gives one :class:`Verdict` per
claim, :func:`write_verdicts` writes JSON and TSV, :func:`enforce_references`
fails a CI run whose ``ci: true`` claims do not reproduce their ``reference``,
and :func:`claims_table` renders the report table.

``check.kind`` names a function in :data:`CHECKS`; it receives the check's
parameters and the datasets and returns an :class:`Outcome`: does the claim
hold (``True``/``False``), or can the data not decide (``None``), together with
the numbers measured.  The verdict is ``pass``, ``fail`` or ``undecided``.
Datasets are picked by *selectors*, mappings of attribute -> value (or list of
values) matched against ``ds.attrs``, so any part whose datasets carry
attributes (figure, method, k, ...) can reuse the machinery and register its
own check kinds with :func:`register_check`.

The stability checks below measure the share of stable grid points; a
difference between two shares is called only if it exceeds the grid
resolution ``1/(n - 1)`` (the change of the share when the stability boundary
moves by one grid spacing across the whole plot).  Smaller differences are
``undecided``: the grid cannot tell them from discretisation.
"""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, field

import numpy as np

from .model import ParameterError

__all__ = [
    "Claim",
    "Outcome",
    "Verdict",
    "CHECKS",
    "VERDICTS",
    "register_check",
    "load_claims",
    "parse_claims",
    "select",
    "matches",
    "evaluate",
    "combine_holds",
    "reference_mismatches",
    "enforce_references",
    "write_verdicts",
    "claims_table",
    "evaluate_claim",
    "stable_share",
    "grid_resolution",
]

VERDICTS = ("pass", "fail", "undecided")
CLAIM_KEYS = {"id", "source", "statement", "figures", "check", "each", "ci", "reference", "note"}
REQUIRED_KEYS = {"id", "source", "statement", "figures", "check"}


@dataclass(frozen=True)
class Claim:
    id: str
    source: str
    statement: str
    figures: tuple
    check: dict
    each: dict = field(default_factory=dict)
    ci: bool = False
    reference: str | None = None
    note: str = ""

    def as_dict(self) -> dict:
        return {
            "id": self.id,
            "source": self.source,
            "statement": self.statement,
            "figures": list(self.figures),
            "check": self.check,
            "each": self.each,
            "note": self.note,
            "ci": self.ci,
            "reference": self.reference,
        }


@dataclass
class Outcome:
    """What one check measured: ``holds`` is True, False or None (cannot decide)."""

    holds: bool | None
    measured: str
    numbers: dict = field(default_factory=dict)


@dataclass
class Verdict:
    claim: Claim
    verdict: str
    measured: str
    numbers: dict

    @property
    def matches_reference(self) -> bool | None:
        return None if self.claim.reference is None else self.verdict == self.claim.reference

    def as_dict(self) -> dict:
        return {
            **self.claim.as_dict(),
            "verdict": self.verdict,
            "matches_reference": self.matches_reference,
            "measured": self.measured,
            "numbers": self.numbers,
        }


#: check kind -> function(datasets, **params) -> Outcome
CHECKS: dict = {}
#: check kind -> function(label, params) raising ParameterError (part-specific parameter checks)
VALIDATORS: dict = {}


def register_check(kind: str, validate=None):
    """Decorator: make ``fn(datasets, **params) -> Outcome`` available as ``kind``.

    ``validate(label, params)``, if given, checks the parameters further when the
    claims are read (the signature check -- unknown, missing -- is always made).
    """

    def deco(fn):
        CHECKS[kind] = fn
        if validate is not None:
            VALIDATORS[kind] = validate
        return fn

    return deco


def _register_part_checks():
    """Import the parts that register their own check kinds (lazily: they import this module)."""
    from . import convergence, pendulum  # noqa: F401


# -- reading claims ------------------------------------------------------------


def parse_claims(items, *, where: str = "claims") -> list[Claim]:
    """Validate a list of claim mappings; errors name the claim and the key."""
    _register_part_checks()
    if not isinstance(items, list):
        raise ParameterError(f"{where} must be a list of claims")
    claims, seen = [], set()
    for i, item in enumerate(items):
        label = f"{where}[{i}]" + (f" ({item.get('id')})" if isinstance(item, dict) and "id" in item else "")
        if not isinstance(item, dict):
            raise ParameterError(f"{label} must be a mapping")
        unknown = sorted(set(item) - CLAIM_KEYS)
        if unknown:
            raise ParameterError(f"{label}: unknown key(s) {unknown}; allowed: {sorted(CLAIM_KEYS)}")
        missing = sorted(REQUIRED_KEYS - set(item))
        if missing:
            raise ParameterError(f"{label}: missing key(s) {missing}")
        if item["id"] in seen:
            raise ParameterError(f"{label}: duplicate id {item['id']!r}")
        seen.add(item["id"])
        if not isinstance(item["check"], dict):
            raise ParameterError(f"{label}: check must be a mapping with a kind and its parameters")
        check = dict(item["check"])
        kind = check.get("kind")
        if kind not in CHECKS:
            raise ParameterError(f"{label}: check.kind must be one of {sorted(CHECKS)}, got {kind!r}")
        _check_parameters(label, kind, {k: v for k, v in check.items() if k != "kind"})
        if kind in VALIDATORS:
            VALIDATORS[kind](label, {k: v for k, v in check.items() if k != "kind"})
        if not isinstance(item.get("ci", False), bool):
            raise ParameterError(f"{label}: ci must be true or false, got {item['ci']!r}")
        if not isinstance(item["figures"], list) or not item["figures"]:
            raise ParameterError(f"{label}: figures must be a non-empty list of figure numbers")
        reference = item.get("reference")
        if reference is not None and reference not in VERDICTS:
            raise ParameterError(f"{label}: reference must be one of {VERDICTS}, got {reference!r}")
        each = item.get("each") or {}
        if not isinstance(each, dict) or any(not isinstance(v, list) for v in each.values()):
            raise ParameterError(f"{label}: each must map an attribute to a list of values")
        claims.append(
            Claim(
                id=str(item["id"]),
                source=str(item["source"]),
                statement=str(item["statement"]),
                figures=tuple(str(f) for f in item["figures"]),
                check=check,
                each=each,
                ci=bool(item.get("ci", False)),
                reference=reference,
                note=str(item.get("note", "")),
            )
        )
    return claims


#: Allowed values of the checks' choice parameters (checked when the claims are read).
CHOICES = {
    ("stable_fraction", "op"): ("==", ">=", "<=", ">", "<"),
    ("compare", "relation"): ("greater", "less", "similar"),
    ("trend", "direction"): ("increasing", "decreasing"),
}


def _check_parameters(label: str, kind: str, params: dict):
    """The check's parameters against its function's signature: unknown, missing, bad choices."""
    sig = inspect.signature(CHECKS[kind])
    names = [n for n in sig.parameters if n != "datasets"]
    unknown = sorted(set(params) - set(names))
    if unknown:
        raise ParameterError(f"{label}: check ({kind}) has unknown key(s) {unknown}; allowed: {names}")
    missing = [n for n in names if sig.parameters[n].default is inspect.Parameter.empty and n not in params]
    if missing:
        raise ParameterError(f"{label}: check ({kind}) lacks {missing}")
    for (k, name), allowed in CHOICES.items():
        if k == kind and name in params and params[name] not in allowed:
            raise ParameterError(f"{label}: check.{name} must be one of {list(allowed)}, got {params[name]!r}")
    for name in ("select", "a", "b", "region"):
        value = params.get(name)
        if value is None:
            continue
        items = value if (name == "b" and isinstance(value, list)) else [value]
        if not all(isinstance(v, dict) for v in items):
            raise ParameterError(f"{label}: check.{name} must be a mapping of attribute -> value")
    unknown = sorted(set(params.get("region") or {}) - {"lr1", "li1", "exclude_undamped"})
    if unknown:
        raise ParameterError(f"{label}: check.region has unknown key(s) {unknown}; allowed: lr1, li1, exclude_undamped")
    if kind == "compare" and params.get("relation") == "similar" and params.get("within") is None:
        raise ParameterError(f"{label}: check (compare) with relation 'similar' needs `within`")


def load_claims(path, key: str = "claims") -> list[Claim]:
    """Read claims from a YAML file whose top-level ``key`` holds the list."""
    import yaml

    with open(path) as fh:
        doc = yaml.safe_load(fh)
    if not isinstance(doc, dict) or key not in doc:
        raise ParameterError(f"{path}: expected a top-level key {key!r}")
    unknown = sorted(set(doc) - {key})
    if unknown:
        raise ParameterError(f"{path}: unknown top-level key(s) {unknown}; allowed: {key}")
    return parse_claims(doc[key], where=f"{path}:{key}")


# -- selecting datasets ----------------------------------------------------------


def _equal(have, want) -> bool:
    if isinstance(want, bool) or isinstance(have, bool):
        return have == want
    try:
        return math.isclose(float(have), float(want), rel_tol=1e-12, abs_tol=0.0)
    except (TypeError, ValueError):
        return str(have) == str(want)


def matches(attrs, selector) -> bool:
    """``attrs`` (a mapping) has every attribute of ``selector`` with the value (or one of the list) given."""
    for key, want in selector.items():
        if key not in attrs:
            return False
        wants = want if isinstance(want, (list, tuple)) else [want]
        if not any(_equal(attrs[key], w) for w in wants):
            return False
    return True


def select(datasets, selector: dict) -> list:
    """Datasets whose attributes match every entry of ``selector``.

    A selector value may be a list (any of the values).  Numbers compare
    numerically (``10`` matches ``10.0``), everything else as strings.
    """
    return [ds for ds in datasets if matches(ds.attrs, selector)]


_select = select  # the checks take a parameter called `select`


# -- evaluation -------------------------------------------------------------------


def _fill(selector, key, value):
    """``each`` fills an attribute in where a selector leaves it open."""
    if isinstance(selector, list):
        return [_fill(sel, key, value) for sel in selector]
    return selector if key in selector else {**selector, key: value}


def _with_each(check: dict, key, value) -> dict:
    out = dict(check)
    for name in ("select", "a", "b"):
        if name in out:
            out[name] = _fill(out[name], key, value)
    return out


def evaluate_claim(claim: Claim, datasets) -> Verdict:
    """Evaluate one claim; a check that raises is a bug and propagates."""
    check = dict(claim.check)
    kind = check.pop("kind")
    fn = CHECKS[kind]
    if not claim.each:
        outcome = fn(datasets, **check)
        return Verdict(claim, _verdict(outcome.holds), outcome.measured, outcome.numbers)
    # one evaluation per combination of the `each` values
    combos = [{}]
    for key, values in claim.each.items():
        combos = [{**c, key: v} for c in combos for v in values]
    parts, numbers, holds = [], {}, []
    for combo in combos:
        sub = check
        for key, value in combo.items():
            sub = _with_each(sub, key, value)
        outcome = fn(datasets, **sub)
        tag = ", ".join(f"{k} = {v}" for k, v in combo.items())
        parts.append(f"[{tag}] {outcome.measured} -> {_verdict(outcome.holds)}")
        numbers[tag] = outcome.numbers
        holds.append(outcome.holds)
    return Verdict(claim, _verdict(combine_holds(holds)), "; ".join(parts), numbers)


def evaluate(claims, datasets) -> list[Verdict]:
    return [evaluate_claim(c, datasets) for c in claims]


def _verdict(holds) -> str:
    return {True: "pass", False: "fail"}.get(holds, "undecided")


def combine_holds(holds) -> bool | None:
    """Several outcomes as one: False if any is False, True if all are True, else None (undecided)."""
    holds = list(holds)
    return False if any(h is False for h in holds) else True if all(h is True for h in holds) else None


# -- results: CI references, files, report table ------------------------------------------


def reference_mismatches(verdicts) -> list[Verdict]:
    """Claims marked ``ci: true`` whose verdict differs from their recorded ``reference``."""
    return [v for v in verdicts if v.claim.ci and v.matches_reference is False]


def enforce_references(verdicts, enforce: bool):
    """With ``enforce`` (the CI configuration), stop (SystemExit, before anything is written)
    if a ``ci: true`` claim did not reproduce its full-resolution reference verdict."""
    mismatched = reference_mismatches(verdicts)
    if enforce and mismatched:
        lines = [
            f"  {v.claim.id}: verdict {v.verdict}, reference {v.claim.reference} ({v.measured})" for v in mismatched
        ]
        raise SystemExit(
            "claims marked ci: true did not reproduce their full-resolution reference verdict:\n" + "\n".join(lines)
        )


def _json_default(x):
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.ndarray):
        return x.tolist()
    return float(x)


def write_verdicts(verdicts, json_path, tsv_path=None):
    """Every verdict as JSON (``{"claims": [Verdict.as_dict(), ...]}``) and as a TSV table (atomic)."""
    import csv
    import json

    from .datasets import atomic_path

    records = [v.as_dict() for v in verdicts]
    with atomic_path(json_path) as tmp:
        tmp.write_text(json.dumps({"claims": records}, indent=1, default=_json_default))
    if tsv_path is None:
        return records
    with atomic_path(tsv_path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh, delimiter="\t")
        w.writerow(["id", "source", "figures", "statement", "verdict", "reference", "measured"])
        for r in records:
            w.writerow(
                [
                    r["id"],
                    r["source"],
                    " ".join(r["figures"]),
                    r["statement"],
                    r["verdict"],
                    r["reference"] or "",
                    r["measured"],
                ]
            )
    return records


def read_verdicts(path) -> list[dict]:
    """The verdict records written by :func:`write_verdicts`."""
    import json
    from pathlib import Path

    return json.loads(Path(path).read_text())["claims"]


def verdict_counts(records) -> dict:
    return {k: sum(r["verdict"] == k for r in records) for k in VERDICTS}


def claims_table(records, *, note_header: str = "note") -> str:
    """HTML table of verdict records (claim, source, figures, verdict and reference, measured, note)."""
    from . import report as rp

    rows = []
    for c in records:
        ref = c["reference"]
        ref_note = (
            ""
            if ref is None
            else f" (full-resolution reference: {ref}"
            + (", reproduced)" if c["matches_reference"] else ", NOT reproduced at this resolution)")
        )
        rows.append(
            [
                f"<b>{rp.escape(c['id'])}</b><br>{rp.escape(c['statement'])}",
                rp.escape(c["source"]),
                rp.escape(", ".join(c["figures"])),
                rp.verdict_badge(c["verdict"]) + rp.escape(ref_note),
                rp.escape(c["measured"]),
                rp.escape(c["note"]),
            ]
        )
    return rp.table(
        ["claim", "source", "figures", "verdict", "measured", note_header], rows, raw_columns=(0, 1, 2, 3, 4, 5)
    )


# -- stability measures ---------------------------------------------------------------


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


@register_check("stable_fraction")
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


@register_check("compare")
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


@register_check("trend")
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

"""The paper's claims as data, evaluated against result datasets (generic machinery).

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

``check.kind`` names a :class:`CheckKind`: a function that receives the
check's parameters and the datasets and returns an :class:`Outcome` -- does
the claim hold (``True``/``False``), or can the data not decide (``None``),
together with the numbers measured.  The verdict is ``pass``, ``fail`` or
``undecided``.  Datasets are picked by *selectors*, mappings of attribute ->
value (or list of values) matched against ``ds.attrs``.

This module knows no part: each part defines its check kinds in its
``checks`` module (:mod:`icosim.studies.stability.checks`,
:mod:`icosim.studies.convergence.checks`, :mod:`icosim.studies.pendulum.checks`), and the
registry :mod:`icosim.claims.registry` collects them into one table and binds
:func:`parse_claims`, :func:`load_claims` and :func:`evaluate` to it.
:func:`write_verdicts` writes JSON and TSV, :func:`enforce_references` fails a
CI run whose ``ci: true`` claims do not reproduce their ``reference``.

>>> kinds = {"always": CheckKind(lambda datasets, *, value: Outcome(value, f"value {value}"))}
>>> [claim] = parse_claims([{"id": "c", "source": "Sect. 1", "statement": "s", "figures": ["1"],
...                          "check": {"kind": "always", "value": True}}], kinds)
>>> evaluate_claim(claim, [], kinds).verdict
'pass'
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from .errors import ParameterError
from .io.jsonio import dumps

__all__ = [
    "check_expected_orders",
    "Claim",
    "CheckKind",
    "Outcome",
    "Verdict",
    "VERDICTS",
    "load_claims",
    "parse_claims",
    "select",
    "matches",
    "evaluate",
    "evaluate_claim",
    "describe_claim",
    "selector_text",
    "combine_holds",
    "reference_mismatches",
    "enforce_references",
    "write_verdicts",
    "verdict_table",
    "read_verdicts",
    "verdict_counts",
]

VERDICTS = ("pass", "fail", "undecided")


CLAIM_KEYS = {"id", "source", "statement", "figures", "check", "each", "ci", "reference", "note", "scope"}

#: Whose claim it is: the paper's, or the project's own about data beyond the paper (other schemes, ...).
SCOPES = ("paper", "beyond")


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
    scope: str = "paper"

    def as_dict(self) -> dict:
        return {
            "scope": self.scope,
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


@dataclass(frozen=True)
class CheckKind:
    """A kind of check: ``fn(datasets, **params) -> Outcome`` and what its parameters may be.

    ``choices`` maps a parameter to its allowed values; ``selectors`` are the
    parameters that pick datasets (mappings of attribute -> value; those in
    ``selector_lists`` may also be a list of them), filled in by a claim's
    ``each``; ``validate(label, params)``, if given, checks the parameters
    further when the claims are read (the signature check -- unknown,
    missing -- is always made).  ``describe(params) -> (what, fails_if)``
    says in words what the check reads and which data outcome would make the
    claim fail (the claims table of the documentation).
    """

    fn: Callable
    validate: Callable | None = None
    choices: Mapping[str, tuple] = field(default_factory=dict)
    selectors: tuple[str, ...] = ()
    selector_lists: tuple[str, ...] = ()
    describe: Callable | None = None


# -- reading claims ------------------------------------------------------------


def parse_claims(items, checks: Mapping[str, CheckKind], *, where: str = "claims") -> list[Claim]:
    """Validate a list of claim mappings against the check kinds ``checks``; errors name the claim and the key."""
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
        if kind not in checks:
            raise ParameterError(f"{label}: check.kind must be one of {sorted(checks)}, got {kind!r}")
        _check_parameters(label, kind, checks[kind], {k: v for k, v in check.items() if k != "kind"})
        if not isinstance(item.get("ci", False), bool):
            raise ParameterError(f"{label}: ci must be true or false, got {item['ci']!r}")
        if not isinstance(item["figures"], list) or not item["figures"]:
            raise ParameterError(f"{label}: figures must be a non-empty list of figure numbers")
        reference = item.get("reference")
        if reference is not None and reference not in VERDICTS:
            raise ParameterError(f"{label}: reference must be one of {VERDICTS}, got {reference!r}")
        scope = item.get("scope", "paper")
        if scope not in SCOPES:
            raise ParameterError(f"{label}: scope must be one of {SCOPES}, got {scope!r}")
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
                scope=scope,
            )
        )
    return claims


def _check_parameters(label: str, kind: str, spec: CheckKind, params: dict):
    """The check's parameters against its function's signature (unknown, missing), choices and selectors."""
    sig = inspect.signature(spec.fn)
    names = [n for n in sig.parameters if n != "datasets"]
    unknown = sorted(set(params) - set(names))
    if unknown:
        raise ParameterError(f"{label}: check ({kind}) has unknown key(s) {unknown}; allowed: {names}")
    missing = [n for n in names if sig.parameters[n].default is inspect.Parameter.empty and n not in params]
    if missing:
        raise ParameterError(f"{label}: check ({kind}) lacks {missing}")
    for name, allowed in spec.choices.items():
        if name in params and params[name] not in allowed:
            raise ParameterError(f"{label}: check.{name} must be one of {list(allowed)}, got {params[name]!r}")
    for name in spec.selectors:
        value = params.get(name)
        if value is None:
            continue
        items = value if (name in spec.selector_lists and isinstance(value, list)) else [value]
        if not all(isinstance(v, dict) for v in items):
            raise ParameterError(f"{label}: check.{name} must be a mapping of attribute -> value")
    if spec.validate is not None:
        spec.validate(label, params)


def load_claims(path, checks: Mapping[str, CheckKind], key: str = "claims") -> list[Claim]:
    """Read claims from a YAML file whose top-level ``key`` holds the list."""
    from .io.yamlio import load_yaml

    with open(path) as fh:
        doc = load_yaml(fh)
    if not isinstance(doc, dict) or key not in doc:
        raise ParameterError(f"{path}: expected a top-level key {key!r}")
    unknown = sorted(set(doc) - {key})
    if unknown:
        raise ParameterError(f"{path}: unknown top-level key(s) {unknown}; allowed: {key}")
    return parse_claims(doc[key], checks, where=f"{path}:{key}")


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


# -- evaluation -------------------------------------------------------------------


def _fill(selector, key, value):
    """``each`` fills an attribute in where a selector leaves it open."""
    if isinstance(selector, list):
        return [_fill(sel, key, value) for sel in selector]
    return selector if key in selector else {**selector, key: value}


def _with_each(check: dict, selectors, key, value) -> dict:
    out = dict(check)
    for name in selectors:
        if name in out:
            out[name] = _fill(out[name], key, value)
    return out


def evaluate_claim(claim: Claim, datasets, checks: Mapping[str, CheckKind], defaults: Mapping | None = None) -> Verdict:
    """Evaluate one claim with the check kinds ``checks``; a check that raises is a bug and propagates.

    ``defaults`` (attribute -> value) are filled into every selector that names neither them nor
    gets them from ``each``: what a claim selects unless it says otherwise.
    """
    check = dict(claim.check)
    kind = check.pop("kind")
    fn = checks[kind].fn

    def with_defaults(sub):
        for key, value in (defaults or {}).items():
            sub = _with_each(sub, checks[kind].selectors, key, value)
        return sub

    if not claim.each:
        outcome = fn(datasets, **with_defaults(check))
        return Verdict(claim, _verdict(outcome.holds), outcome.measured, outcome.numbers)
    # one evaluation per combination of the `each` values
    combos = [{}]
    for key, values in claim.each.items():
        combos = [{**c, key: v} for c in combos for v in values]
    parts, numbers, holds = [], {}, []
    for combo in combos:
        sub = check
        for key, value in combo.items():
            sub = _with_each(sub, checks[kind].selectors, key, value)
        outcome = fn(datasets, **with_defaults(sub))
        tag = ", ".join(f"{k} = {v}" for k, v in combo.items())
        parts.append(f"[{tag}] {outcome.measured} -> {_verdict(outcome.holds)}")
        numbers[tag] = outcome.numbers
        holds.append(outcome.holds)
    return Verdict(claim, _verdict(combine_holds(holds)), "; ".join(parts), numbers)


def selector_text(selector) -> str:
    """A selector in words: ``{figure: "9", row: [1, 2]}`` -> ``figure 9, row 1 or 2``."""
    if isinstance(selector, list):
        return "; ".join(selector_text(s) for s in selector)
    parts = []
    for key, value in selector.items():
        values = value if isinstance(value, list) else [value]
        parts.append(f"{key} {' or '.join(str(v) for v in values)}")
    return ", ".join(parts) or "every dataset"


def describe_claim(claim: Claim, checks: Mapping[str, CheckKind]) -> dict:
    """What a claim's check reads and what would make it fail, in words (``check``, ``fails_if``)."""
    params = {k: v for k, v in claim.check.items() if k != "kind"}
    describe = checks[claim.check["kind"]].describe
    what, fails_if = describe(params) if describe else (claim.check["kind"], "the check does not hold")
    if claim.each:
        what += "; once for each " + ", ".join(f"{k} in {v}" for k, v in claim.each.items())
        fails_if += " (in any of them)"
    return {"check": what, "fails_if": fails_if}


def evaluate(claims, datasets, checks: Mapping[str, CheckKind], defaults: Mapping | None = None) -> list[Verdict]:
    return [evaluate_claim(c, datasets, checks, defaults) for c in claims]


def _verdict(holds) -> str:
    return {True: "pass", False: "fail"}.get(holds, "undecided")


def combine_holds(holds) -> bool | None:
    """Several outcomes as one: False if any is False, True if all are True, else None (undecided)."""
    holds = list(holds)
    return False if any(h is False for h in holds) else True if all(h is True for h in holds) else None


# -- results: CI references, files ------------------------------------------------


def check_expected_orders(label: str, expect) -> None:
    """Refuse an order check's ``expect`` unless it is a non-empty list of ``{k: ..., order: p}``."""
    if not isinstance(expect, list) or not expect:
        raise ParameterError(f"{label}: check.expect must be a non-empty list of {{k: ..., order: p}}")
    for j, exp in enumerate(expect):
        if not isinstance(exp, dict) or set(exp) != {"k", "order"}:
            raise ParameterError(f"{label}: check.expect[{j}] must be {{k: ..., order: p}}, got {exp!r}")


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


def write_verdicts(verdicts, json_path, tsv_path=None):
    """Every verdict as JSON (``{"claims": [Verdict.as_dict(), ...]}``) and as a TSV table (atomic)."""

    from .io.netcdf import atomic_path

    records = [v.as_dict() for v in verdicts]
    with atomic_path(json_path) as tmp:
        tmp.write_text(dumps({"claims": records}, indent=1))  # strict: a non-finite number is null, with why
    if tsv_path is None:
        return records
    with atomic_path(tsv_path) as tmp:
        # csv's dialect as before (CRLF line ends, minimal quoting): the files stay byte for byte the same
        verdict_table(records).to_csv(tmp, sep="\t", index=False, lineterminator="\r\n")
    return records


#: Columns of the claims TSV table (:func:`verdict_table`).
TABLE_COLUMNS = ("id", "source", "figures", "statement", "verdict", "reference", "measured")


def verdict_table(records):
    """The verdict records as a :class:`pandas.DataFrame` (one row per claim, :data:`TABLE_COLUMNS`;
    ``figures`` joined by spaces, a missing ``reference`` as an empty string)."""
    import pandas as pd

    df = pd.DataFrame.from_records(list(records), columns=[c for c in TABLE_COLUMNS])
    df["figures"] = df["figures"].map(" ".join)
    df["reference"] = df["reference"].fillna("").astype(str)
    return df


def read_verdicts(path) -> list[dict]:
    """The verdict records written by :func:`write_verdicts`."""
    import json
    from pathlib import Path

    return json.loads(Path(path).read_text())["claims"]


def verdict_counts(records) -> dict:
    return {k: sum(r["verdict"] == k for r in records) for k in VERDICTS}

"""The tolerance mode of ``tools/compare_results.py`` (``--tolerances``): the same results within the tolerances
of the replication speed target, and the claims' verdicts.

* stability panels (``stability/fig*/<scheme>/r*_k*_*.nc``): ``rho`` within 1e-12 relative (NaN where NaN);
* convergence panels (``convergence/fig*/<scheme>/*.nc``): ``nrmse`` within 1e-9 relative (NaN where NaN);
* pendulum runs (``pendulum/runs/<scheme>/*.nc``): the angles ``phi1`` and ``phi2`` within 1e-9 rad;
* every dataset: verdict- and status-like variables (strings, booleans, integer codes named like a verdict
  or status) and global attributes named so equal; the dimension coordinates (the grid) within 1e-12
  relative; every other difference (variables, attributes) a note with its largest relative size;
* claims (``claims*.json``, ``claims*.tsv``): every claim id's verdict equal (the measured text and the
  other fields: notes); a claim id in one run only is listed.

Relative difference: ``|a - b| / max(|a|, |b|)`` (0 where both are 0); infinities must be equal.
"""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np

RHO_RTOL, NRMSE_RTOL, ANGLE_ATOL, GRID_RTOL = 1e-12, 1e-9, 1e-9, 1e-12
#: kind of dataset: (NEW's path, {variable: (relative?, tolerance, summary column)})
TOLERANCES = {
    "stability panel": (r"stability/fig[^/]+/[^/]+/r\d+_k\d+_(?:full|zoom)\.nc", {"rho": (True, RHO_RTOL, "rho")}),
    "convergence panel": (r"convergence/fig[^/]+/[^/]+/[^/]+\.nc", {"nrmse": (True, NRMSE_RTOL, "nrmse")}),
    "pendulum run": (
        r"pendulum/runs/[^/]+/[^/]+\.nc",
        {"phi1": (False, ANGLE_ATOL, "angle"), "phi2": (False, ANGLE_ATOL, "angle")},
    ),
}
#: integer variables and attributes named so hold verdicts, statuses or decisions: they must be equal
VERDICT_NAME = re.compile(r"verdict|status|stable|decided|reason|diverged|failed|certified|overturn|audited|unstable")
PARTS = ("stability", "convergence", "pendulum", "claims")


def new_stats() -> dict:
    return {part: {"datasets": 0, "rho": 0.0, "nrmse": 0.0, "angle": 0.0, "verdicts": 0} for part in PARTS}


def part_of(rel: str) -> str:
    return rel.split("/")[0] if rel.split("/")[0] in PARTS else "other"


def _load(path: Path):
    import xarray as xr

    with xr.open_dataset(path, decode_times=False, mask_and_scale=False) as ds:  # integer codes stay integers
        return ds.load()


def _text(a) -> bool:
    return a.dtype.kind in "OSU"


def rel_diff(a, b) -> np.ndarray:
    """|a - b| / max(|a|, |b|), 0 where a == b (infinities, zeros) and NaN where a or b is NaN."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.abs(a - b) / np.maximum(np.abs(a), np.abs(b))
    return np.where(a == b, 0.0, d)


def _where(da, mask, n=4) -> str:
    """The first points of ``mask`` named by their coordinates."""
    idx = np.argwhere(np.asarray(mask))[:n]
    dims = da.dims
    parts = []
    for i in idx:
        value = lambda d, j: getattr(da[d].values[j], "item", lambda: da[d].values[j])()  # noqa: E731
        labels = [f"{d}={value(d, j)!r}" if d in da.coords else f"{d}[{j}]" for d, j in zip(dims, i)]
        parts.append("(" + ", ".join(labels) + ")")
    return " ".join(parts) + (" ..." if int(np.sum(mask)) > n else "")


def _align(a, b, rel, problems, notes):
    """NEW at OLD's labels where NEW holds more along a labelled dimension (the merged summaries)."""
    for dim in set(a.dims) & set(b.dims):
        if dim not in a.coords or dim not in b.coords or not (_text(a[dim]) and _text(b[dim])):
            continue
        la, lb = [str(x) for x in a[dim].values], [str(x) for x in b[dim].values]
        if la == lb:
            continue
        if set(la) <= set(lb) and len(set(la)) == len(la):
            b = b.sel({dim: a[dim].values})
            notes.append(f"{rel}: NEW has {len(lb) - len(la)} more {dim} labels than OLD: compared at OLD's {len(la)}")
        else:
            problems.append(
                f"{rel}: {dim} labels differ: only OLD {sorted(set(la) - set(lb))[:6]}, only NEW {sorted(set(lb) - set(la))[:6]}"
            )
    return b


def compare_dataset(old: Path, new: Path, rel: str, problems, notes, stats, volatile_attrs=(), volatile_vars=()):
    """``rel``: the path under results/."""
    part, path = part_of(rel), rel
    rules = next((r for pattern, r in TOLERANCES.values() if re.fullmatch(pattern, path)), {})
    a, b = _load(old), _load(new)
    b = _align(a, b, rel, problems, notes)
    if part in stats:
        stats[part]["datasets"] += 1
    small, described = [], []
    for name in sorted(set(a.variables) | set(b.variables)):
        if name in volatile_vars:
            continue
        strict = name in rules or name in a.dims or (name in a.variables and _verdict_like(name, a[name]))
        if name not in b.variables or name not in a.variables:
            where = "NEW" if name in b.variables else "OLD"
            (problems if strict and where == "OLD" else notes).append(f"{rel}:{name}: only in {where}")
            continue
        va, vb = a[name], b[name]
        keys = sorted(k for k in set(va.attrs) | set(vb.attrs) if not _same(va.attrs.get(k), vb.attrs.get(k)))
        described += [f"{name} ({', '.join(keys)})"] if keys else []
        if va.shape != vb.shape:
            (problems if strict else notes).append(f"{rel}:{name}: shape {va.shape} != {vb.shape}")
            continue
        if name in rules:
            relative, tol, column = rules[name]
            x, y = va.values.astype(float), vb.values.astype(float)
            nan, both = np.isnan(x) != np.isnan(y), np.isnan(x) & np.isnan(y)
            d = rel_diff(x, y) if relative else np.where(x == y, 0.0, np.abs(x - y))
            d = np.where(nan | both, 0.0, np.where(np.isnan(d), np.inf, d))  # an infinity against a number: inf
            worst = float(d.max()) if d.size else 0.0
            stats[part][column] = max(stats[part][column], worst)
            if nan.any():
                problems.append(f"{rel}:{name}: NaN in one run only at {int(nan.sum())} points {_where(va, nan)}")
            if worst > tol:
                kind = "relative" if relative else "absolute"
                problems.append(
                    f"{rel}:{name}: {kind} difference {worst:.3g} > {tol:g} at {int(np.sum(d > tol))} points {_where(va, d > tol)}"
                )
        elif _verdict_like(name, va) or _text(vb):
            x, y = va.values, vb.values
            diff = x.astype(str) != y.astype(str) if _text(va) or _text(vb) else ~((x == y) | _both_nan(x, y))
            if diff.any():
                stats[part]["verdicts"] += int(diff.sum())
                pairs = ", ".join(f"{p!r}->{q!r}" for p, q in list(zip(x[diff].tolist(), y[diff].tolist()))[:4])
                problems.append(f"{rel}:{name}: {int(diff.sum())} value(s) changed {_where(va, diff)}: {pairs}")
        else:
            d = rel_diff(va.values, vb.values) if va.dtype.kind in "fciu" and vb.dtype.kind in "fciu" else None
            nan = d is not None and np.any(np.isnan(va.values.astype(float)) != np.isnan(vb.values.astype(float)))
            worst = float(np.nanmax(d)) if d is not None and d.size and not np.all(np.isnan(d)) else 0.0
            if name in a.dims and worst > GRID_RTOL:
                problems.append(f"{rel}:{name}: the grid differs (relative {worst:.3g})")
            elif worst or nan:
                small.append(f"{name} {worst:.2g}" + (" (NaN pattern)" if nan else ""))
    if small:
        notes.append(f"{rel}: other variables differ (largest relative difference): {', '.join(small)}")
    if described:
        notes.append(f"{rel}: variables' attributes differ: {', '.join(described)}")
    _compare_attrs(a.attrs, b.attrs, rel, problems, notes, stats, part, volatile_attrs)


def _both_nan(x, y):
    return np.isnan(x) & np.isnan(y) if x.dtype.kind == "f" and y.dtype.kind == "f" else np.zeros(x.shape, bool)


def _verdict_like(name, var) -> bool:
    return var.dtype.kind in "bOSU" or (var.dtype.kind in "iu" and bool(VERDICT_NAME.search(name)))


def _same(x, y) -> bool:
    x, y = np.asarray(x), np.asarray(y)
    if x.shape != y.shape:
        return False
    if x.dtype.kind in "fc" and y.dtype.kind in "fc":
        return bool(np.all((x == y) | (np.isnan(x) & np.isnan(y))))
    return bool(np.all(x.astype(str) == y.astype(str))) if x.dtype != y.dtype else bool(np.all(x == y))


def _compare_attrs(ga, gb, rel, problems, notes, stats, part, volatile):
    other = []
    for key in sorted(set(ga) | set(gb)):
        if key in volatile or (key == "config_sha256" and _same(ga.get("config_json"), gb.get("config_json"))):
            continue  # the configuration's digest follows its text, which OLD may spell the old way
        if key in ga and key in gb and _same(ga[key], gb[key]):
            continue
        if VERDICT_NAME.search(key):
            problems.append(f"{rel}: global attribute {key!r}: {ga.get(key)!r} != {gb.get(key)!r}")
            if part in stats:
                stats[part]["verdicts"] += 1
        else:
            other.append(key if key in ga and key in gb else f"{key} (only {'OLD' if key in ga else 'NEW'})")
    if other:
        notes.append(f"{rel}: global attributes differ: {', '.join(other)}")


# -- claims --------------------------------------------------------------------------------------------------
def read_claims(path: Path) -> dict:
    """claim id -> record, from a claims JSON (``{"claims": [...]}``) or TSV table."""
    import json

    if path.suffix == ".json":
        records = json.loads(path.read_text())["claims"]
    else:
        with path.open(newline="") as fh:
            records = list(csv.DictReader(fh, delimiter="\t"))
    return {r["id"]: r for r in records}


def compare_claims(old: Path, new: Path, rel, problems, notes, stats, *, strict=False, allow_new=False):
    """Every claim id's verdict in OLD's file against NEW's; ``strict``: every other field too."""
    a, b = read_claims(old), read_claims(new)
    part = rel.split("/")[0]
    compared, changed = stats["claims"].setdefault("ids", set()), stats["claims"].setdefault("changed", set())
    compared.update((part, cid) for cid in set(a) & set(b))
    for cid in sorted(set(a) - set(b)):
        problems.append(f"{rel}: claim {cid} ({a[cid]['verdict']}) only in OLD")
    for cid in sorted(set(b) - set(a)):
        (notes if allow_new else problems).append(f"{rel}: claim {cid} ({b[cid]['verdict']}) only in NEW (added)")
    fields = {}
    for cid in sorted(set(a) & set(b)):
        if a[cid]["verdict"] != b[cid]["verdict"]:
            changed.add((part, cid))
            defined = [k for k in ("check", "each", "reference", "statement") if a[cid].get(k) != b[cid].get(k)]
            why = f" (the claim's {', '.join(defined)} changed too)" if defined else " (the same claim)"
            problems.append(f"{rel}: claim {cid}: verdict {a[cid]['verdict']} -> {b[cid]['verdict']}{why}")
        for key in sorted(set(a[cid]) | set(b[cid])):
            if key != "verdict" and a[cid].get(key) != b[cid].get(key):
                fields.setdefault(key, []).append(cid)
    for key, ids in fields.items():
        line = (
            f"{rel}: field {key!r} differs in {len(ids)} claim(s): {', '.join(ids[:5])}{' ...' if len(ids) > 5 else ''}"
        )
        (problems if strict else notes).append(line)


def summary_table(stats) -> str:
    """Per part: datasets (or claims files) compared, the largest differences, verdicts changed."""
    head = f"{'part':<13}{'compared':>9}{'max rel rho':>14}{'max rel NRMSE':>15}{'max |d angle|':>15}{'verdicts changed':>18}"
    rows = [head]
    for part in PARTS:
        s = dict(stats[part])
        if part == "claims":  # claims (JSON and TSV count once) compared, and changed
            s["datasets"], s["verdicts"] = len(s.get("ids", ())), len(s.get("changed", ()))
        cells = [
            f"{s[c]:.3g}" if part == p or s[c] else "-"
            for c, p in (("rho", "stability"), ("nrmse", "convergence"), ("angle", "pendulum"))
        ]
        rows.append(f"{part:<13}{s['datasets']:>9}{cells[0]:>14}{cells[1]:>15}{cells[2]:>15}{s['verdicts']:>18}")
    rows.append("(compared: datasets, claims: claim ids in both runs; verdicts changed: values, claims: claim ids)")
    return "\n".join(rows)


def grouped(notes, least=4) -> list:
    """Notes that say the same of at least ``least`` files as one line: how many, and the first file."""

    def split(line):  # (file, what is said of it), or (None, line) for a note about no one file or a file's absence
        path, sep, text = line.partition(": ")
        one = sep and "/" in path and " " not in path.replace(" -> ", "") and not text.startswith("only in")
        return (path, text) if one else (None, line)

    by_text = {}
    for line in notes:
        path, text = split(line)
        by_text.setdefault(text, []).append(path)
    out = []
    for line in notes:
        path, text = split(line)
        paths = by_text.pop(text, None)
        if paths is None:
            continue
        if path is None or len(paths) < least:
            out += [line] if path is None else [f"{p}: {text}" for p in paths]
        else:
            out.append(f"{len(paths)} files: {text} (first: {paths[0]})")
    return out

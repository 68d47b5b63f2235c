"""Older layouts of ``results/`` mapped onto this tree's, for ``tools/compare_results.py --layout``.

A layout is a :class:`Layout`: ``path(rel)`` gives the path under NEW's ``results/`` that holds what OLD
wrote at ``rel`` (several OLD files may map to one NEW file: the claims and the summaries that were
merged), or a :class:`Dropped` with the reason the file has no counterpart by design; ``text(value)``
spells a string of OLD's (an attribute, a label, a claims record's field) the way NEW does;
``claims`` maps claim ids OLD had and NEW replaced to their successors (OLD's verdict is compared with
each successor's); ``renames`` names a dataset's variables and dimensions as NEW does (``--tolerances``).

897a1b5 (before the coupling scheme became a dimension of the workflow):

========================================================  =====================================================
897a1b5                                                   now
========================================================  =====================================================
stability/fig<N>[gs12|gs21]/r<row>_k<k>_<view>.nc         stability/fig<N>/<scheme>/r<row>_k<k>_<view>.nc
stability/figures/fig<N>[gs12|gs21].<ext>                 stability/figures/fig<N>_<scheme>.<ext>
convergence/<dec>/fig<N>[gs12|gs21]_<panel>.nc            convergence/fig<N>/<scheme>/<dec>_<panel>.nc
convergence/figures/fig<N>[gs..]_<dec>[_slopes].<ext>     convergence/figures/fig<N>_<dec>_<scheme>[_slopes].<ext>
pendulum/<method>_<dec>_k<k>[_gs12|_gs21].nc              pendulum/runs/<scheme>/<method>_<dec>_k<k>.nc
pendulum/figures/pendulum_k<k>[_gs12|_gs21].<ext>         pendulum/figures/pendulum_k<k>_<scheme>.<ext>
pendulum/trade/<study>/<scheme>_<method>_<dec>.nc         pendulum/trade/<study>/<scheme>/<method>_<dec>.nc
<part>/claims.<ext> and <part>/claims_gauss_seidel.<ext>  <part>/claims.<ext> (one file per part)
pendulum/summary.nc and pendulum/summary_gauss_seidel.nc  pendulum/summary.nc (every scheme's runs)
report/gauss_seidel.html                                  (dropped: each part's section compares its schemes)
========================================================  =====================================================

``<scheme>`` is the scheme's registry name: no suffix -> ``jacobi``, ``gs12`` -> ``gauss-seidel-12``,
``gs21`` -> ``gauss-seidel-21``.  In OLD's strings a figure id ``<N>gs12`` reads ``<N>`` (the scheme is
the attribute ``scheme``, which OLD already wrote) and a run name ``..._k<k>_gs12`` reads
``..._k<k>_gauss-seidel-12``.  Claims split in two since (5693186, 5ea9e54): ``gs_added_mass_weighted``
and ``gs_projection_ff_k12_unchanged``.  ``convergence/work_precision.nc``: the dimension ``scheme`` is
``configuration`` (f0390e6).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

__all__ = ["Dropped", "Layout", "LAYOUTS", "get_layout", "pair_files"]


@dataclass(frozen=True)
class Dropped:
    """An OLD file with no NEW counterpart by design, and why."""

    reason: str


@dataclass(frozen=True)
class Layout:
    name: str
    rules: tuple  # (compiled pattern, replacement function or Dropped, NEW's path as a template), tried in order
    spellings: tuple = ()  # (pattern, replacement) applied to OLD's strings
    claims: dict = field(default_factory=dict)  # OLD claim id -> NEW claim ids that replaced it
    renames: dict = field(default_factory=dict)  # NEW's path -> {OLD's variable or dimension: NEW's name}

    def match(self, rel: str):
        """(NEW's path for OLD's ``rel`` (relative to results/) or a :class:`Dropped`, the rule's template);
        ``(rel, None)`` where no rule applies."""
        for pattern, target, template in self.rules:
            m = pattern.fullmatch(rel)
            if m:
                return (target if isinstance(target, Dropped) else target(m)), template
        return rel, None

    def path(self, rel: str):
        return self.match(rel)[0]

    def text(self, value: str) -> str:
        for pattern, repl in self.spellings:
            value = pattern.sub(repl, value)
        return value

    def value(self, value):
        """OLD's attribute or label value (string, list of strings, bytes) spelled as NEW spells it."""
        if isinstance(value, bytes):
            return self.text(value.decode())
        if isinstance(value, str):
            return self.text(value)
        if isinstance(value, (list, tuple)):
            return type(value)(self.value(v) for v in value)
        if getattr(value, "dtype", None) is not None and value.dtype.kind in "OSU":  # an array of strings
            return [self.value(v) for v in value.tolist()]
        return value


IDENTITY = Layout("identity", ())

_GS = {None: "jacobi", "": "jacobi", "gs12": "gauss-seidel-12", "gs21": "gauss-seidel-21"}
_FID = r"(?P<fig>\d+)(?P<gs>gs12|gs21)?"


def _rule(pattern: str, fmt):
    def target(m):
        groups = {key: value or "" for key, value in m.groupdict().items()}  # an optional group unmatched: ""
        return fmt.format(**groups, scheme=_GS[groups.get("gs")])

    if isinstance(fmt, Dropped):
        return re.compile(pattern), fmt, "(dropped)"
    return re.compile(pattern), target, fmt


_MERGED_CLAIMS = "{part}/claims.{ext}"
L897A1B5 = Layout(
    "897a1b5",
    rules=(
        _rule(rf"stability/fig{_FID}/(?P<panel>r\d+_k\d+_(?:full|zoom)\.nc)", "stability/fig{fig}/{scheme}/{panel}"),
        _rule(rf"stability/figures/fig{_FID}\.(?P<ext>png|pdf)", "stability/figures/fig{fig}_{scheme}.{ext}"),
        _rule(
            rf"convergence/(?P<dec>ff|fd|dd)/fig{_FID}_(?P<panel>[^/]+)\.nc",
            "convergence/fig{fig}/{scheme}/{dec}_{panel}.nc",
        ),
        _rule(
            rf"convergence/figures/fig{_FID}_(?P<dec>ff|fd|dd)(?P<kind>_slopes)?\.(?P<ext>png|pdf)",
            "convergence/figures/fig{fig}_{dec}_{scheme}{kind}.{ext}",
        ),
        _rule(
            r"pendulum/(?P<run>[a-z]+_(?:ff|fd|dd)_k\d+)(?:_(?P<gs>gs12|gs21))?\.nc", "pendulum/runs/{scheme}/{run}.nc"
        ),
        _rule(
            r"pendulum/figures/pendulum_k(?P<k>\d+)(?:_(?P<gs>gs12|gs21))?\.(?P<ext>png|pdf)",
            "pendulum/figures/pendulum_k{k}_{scheme}.{ext}",
        ),
        _rule(
            r"pendulum/trade/(?P<study>sweep|limits)/(?P<s>jacobi|gauss-seidel-12|gauss-seidel-21)_(?P<group>[^/]+\.nc)",
            "pendulum/trade/{study}/{s}/{group}",
        ),
        _rule(r"(?P<part>stability|convergence|pendulum)/claims_gauss_seidel\.(?P<ext>json|tsv)", _MERGED_CLAIMS),
        _rule(r"pendulum/summary_gauss_seidel\.nc", "pendulum/summary.nc"),
        _rule(
            r"report/gauss_seidel\.html",
            Dropped("no Gauss-Seidel section: each part's section compares its schemes (2cee16f)"),
        ),
    ),
    spellings=(
        (re.compile(r"\b([a-z]+_(?:ff|fd|dd)_k\d+)_gs(12|21)\b"), r"\1_gauss-seidel-\2"),  # run names
        (re.compile(r"\b(\d+)gs(?:12|21)\b"), r"\1"),  # figure ids: the scheme is an attribute of its own
    ),
    # claims rewritten after 897a1b5 (5693186: 'same region' point by point; 5ea9e54: the audit)
    claims={
        "gs_added_mass_weighted": (
            "gs_added_mass_weighted_gs12_no_stable_point",
            "gs_added_mass_weighted_gs21_most_stable",
        ),
        "gs_projection_ff_k12_unchanged": (
            "gs_projection_ff_k12_same_in_rows_1_to_3",
            "gs_projection_ff_k12_row4_differs",
        ),
    },
    # f0390e6: the work-precision curves are configurations, not schemes
    renames={"convergence/work_precision.nc": {"scheme": "configuration"}},
)

LAYOUTS = {"897a1b5": L897A1B5}


def get_layout(name):
    """The layout called ``name`` (a commit in LAYOUTS), or the identity layout for ``None``."""
    if name is None:
        return IDENTITY
    if name not in LAYOUTS:
        raise SystemExit(f"unknown layout {name!r}: known are {', '.join(LAYOUTS)}")
    return LAYOUTS[name]


def pair_files(files_a, files_b, layout, problems, notes, allow_new_files):
    """NEW's path -> OLD's paths found there (``--layout``); what has no counterpart is listed."""
    pairs, rules = {}, {}
    for rel in sorted(files_a):
        target, template = layout.match(rel)
        if isinstance(target, Dropped):
            notes.append(f"{rel}: only in OLD, dropped by design ({target.reason})")
        elif target in files_b:
            pairs.setdefault(target, []).append(rel)
            if template:
                rules[template] = rules.get(template, 0) + 1
        else:
            problems.append(f"{rel}: only in OLD" + (f" (no {target} in NEW)" if target != rel else ""))
    for rel in sorted(files_b - set(pairs)):
        (notes if allow_new_files else problems).append(f"{rel}: only in NEW" + (" (added)" if allow_new_files else ""))
    for template, n in rules.items():
        notes.append(f"layout {layout.name}: {n} OLD file(s) found at {template}")
    return pairs

"""The report page: the answer first (a summary of the claims), then the parts' sections, provenance.

The summary counts, per part, the paper's claims reproduced (verdict pass), not
reproduced (fail) and undecided, then lists every disagreement with one
sentence on why -- taken from the claim's own note (the sentence that states
the disagreement, else the first one), never written here -- and links to the
claim's row, the figure panel and the dataset.  Figures are found in the
sections by their ``id`` and ``data-paper-figures`` attributes
(:func:`icosim.report.html.figure`).
"""

from __future__ import annotations

import datetime as dt
import hashlib
import platform
import re
import subprocess
from pathlib import Path

from ..verdicts import verdict_counts
from ..version import package_version
from .html import claim_anchor, fold, page, table, verdict_badge
from .html import escape as esc

__all__ = ["report_page", "summary_section", "why", "figure_anchors", "git_commit_text", "utc_now", "DATASET_PATHS"]

#: Where each part's datasets are, per paper figure (relative to the project directory).
DATASET_PATHS = {
    "stability": "results/stability/fig{figure}/jacobi/",
    "convergence": "results/convergence/fig{figure}/jacobi/",
    "pendulum": "results/pendulum/summary.nc",
    "fmi": "results/fmi/validation/",
    "chains": "results/chains/",
    "signals": "results/signals/",
}
#: The report's directory relative to the project directory (links to datasets go up from it).
REPORT_DIR = "reports"

_SENTENCE_END = re.compile(r"(\S+)[.!?]\s+(?=[A-Z\"])")
#: Words whose full stop ends no sentence.
_ABBREVIATIONS = {"e.g", "i.e", "Sect", "Sects", "Eq", "Eqs", "Fig", "Figs", "cf", "vs", "et al", "al", "approx"}


def _sentences(text: str) -> list:
    out, start = [], 0
    for m in _SENTENCE_END.finditer(text):
        if m.group(1).lstrip("(") in _ABBREVIATIONS:
            continue
        out.append(text[start : m.end()].strip())
        start = m.end()
    out.append(text[start:].strip())
    return [t for t in out if t]


_FIGURE = re.compile(r'<figure id="([^"]+)" data-paper-figures="([^"]*)"')


def why(claim: dict) -> str:
    """One sentence on why a claim is not reproduced, from its note (or what was measured).

    >>> why({"note": "Read as x.  Disagreement (the data stand): y differs, e.g. Eq. (72) fails.  More."})
    'Disagreement (the data stand): y differs, e.g. Eq. (72) fails.'
    """
    for text in (claim.get("note") or "", claim.get("measured") or ""):
        sentences = _sentences(text)
        if sentences:
            return next((t for t in sentences if "disagree" in t.lower()), sentences[0])
    return ""


def figure_anchors(sections_html) -> dict:
    """``(part, paper figure) -> id`` of the first figure showing it, read from the sections."""
    out = {}
    for html in sections_html:
        for anchor, figures in _FIGURE.findall(html):
            part = anchor.split("-", 1)[0]
            for f in figures.split():
                out.setdefault((part, f), anchor)
    return out


def _dataset_link(part, figure, datasets) -> str:
    pattern = datasets.get(part)
    if not pattern:
        return ""
    path = pattern.format(figure=figure)
    if any(ch in path for ch in "*?["):
        return f"<code>{esc(path)}</code>"
    href = "../" * len(Path(REPORT_DIR).parts) + path
    return f'<a href="{esc(href)}"><code>{esc(path)}</code></a>'


def summary_section(claims: dict, sections_html, *, datasets=None) -> str:
    """The answer first: per part the claims reproduced / not reproduced / undecided, then each disagreement.

    ``claims`` maps a part to its verdict records (:func:`icosim.verdicts.read_verdicts`), in page order;
    only the paper's (scope ``paper``) are counted here, the others are in the parts' sections.
    """
    datasets = DATASET_PATHS if datasets is None else datasets
    claims = {part: [c for c in records if c.get("scope", "paper") == "paper"] for part, records in claims.items()}
    anchors = figure_anchors(sections_html)
    rows, total = [], {"pass": 0, "fail": 0, "undecided": 0}
    for part, records in claims.items():
        n = verdict_counts(records)
        for key in total:
            total[key] += n[key]
        rows.append([f'<a href="#{esc(part)}">{esc(part)}</a>', len(records), n["pass"], n["fail"], n["undecided"]])
    rows.append(["all", sum(len(r) for r in claims.values()), total["pass"], total["fail"], total["undecided"]])
    header = ["part", "claims", "reproduced", "not reproduced", "undecided"]
    items = {"fail": [], "undecided": []}
    for part, records in claims.items():
        for c in records:
            if c["verdict"] not in items:
                continue
            figs = []
            for f in c["figures"]:
                anchor = anchors.get((part, str(f)))
                fig = f'<a href="#{esc(anchor)}">Fig. {esc(str(f))}</a>' if anchor else f"Fig. {esc(str(f))}"
                data = _dataset_link(part, f, datasets)
                figs.append(fig + (f" ({data})" if data else ""))
            items[c["verdict"]].append(
                f'<li>{verdict_badge(c["verdict"])} <b>{esc(part)}</b>: <a href="#{esc(claim_anchor(part, c["id"]))}">'
                f"{esc(c['id'])}</a> — {fold(c['statement'], 140)}"
                + (
                    f" <i>(full-resolution reference: {esc(c['reference'])}; this resolution does not reproduce it)</i>"
                    if c.get("reference") not in (None, c["verdict"])
                    else ""
                )
                + (f"<br><i>Why:</i> {esc(why(c))}" if c["verdict"] == "fail" and why(c) else "")
                + f"<br>Figures and data: {'; '.join(figs)}</li>"
            )
    body = (
        "<p>The paper's claims, each checked against the data (details in each part's claims table). "
        "Reproduced: the data show what the paper says; not reproduced: they show otherwise (the data stand); "
        "undecided: the data cannot decide at this resolution.</p>"
        + table(header, rows, raw_columns=(0,))
        + "<h3>Where the data disagree with the paper</h3>"
        + ("<ul>" + "".join(items["fail"]) + "</ul>" if items["fail"] else "<p>Nowhere.</p>")
        + ("<h3>Undecided</h3><ul>" + "".join(items["undecided"]) + "</ul>" if items["undecided"] else "")
    )
    return f'<section id="summary"><h2>Summary: the paper\'s claims against the data</h2>{body}</section>'


def git_commit_text(cwd=None) -> str:
    """The checkout's commit, marked if the tracked files have uncommitted changes."""

    def git(*args):
        try:
            out = subprocess.run(["git", *args], capture_output=True, text=True, timeout=10, check=True, cwd=cwd)
            return out.stdout.strip()
        except (OSError, subprocess.SubprocessError):
            return None

    commit = git("rev-parse", "HEAD")
    dirty = bool(git("status", "--porcelain", "--untracked-files=no")) if commit else False
    if commit is None:
        return "not available (not a git checkout)"
    return commit + (" (with uncommitted changes)" if dirty else "")


def utc_now() -> str:
    return dt.datetime.now(dt.UTC).replace(microsecond=0).isoformat()


def report_page(
    *,
    title: str,
    parts: list,
    skipped: list,
    sections: list,
    configfiles: list,
    config_sha256: dict,
    precision: dict,
    commit_text: str,
    generated: str,
    claims: dict | None = None,
    datasets: dict | None = None,
) -> str:
    """The whole page.

    ``parts`` name the ``sections`` (HTML fragments, in order), ``skipped`` the
    configured parts without a section; ``configfiles`` are hashed as they are
    on disk, ``config_sha256`` is the hash of each part's effective
    configuration; ``precision`` the stability precision policy;
    ``commit_text`` and ``generated`` say which code made the page, and when.  ``claims`` (part ->
    verdict records), if given, put the summary (:func:`summary_section`) first; ``datasets`` overrides
    :data:`DATASET_PATHS`.
    """
    files = [[esc(f), f"<code>{hashlib.sha256(Path(f).read_bytes()).hexdigest()}</code>"] for f in configfiles]
    merged = [[esc(part), f"<code>{sha}</code>"] for part, sha in config_sha256.items()]
    prec = precision
    provenance = (
        '<section id="provenance"><h2>Provenance</h2><ul>'
        f"<li>icosim {esc(package_version())} (Python {esc(platform.python_version())})</li>"
        f"<li>git commit: <code>{esc(commit_text)}</code></li>"
        f"<li>generated: {esc(generated)}</li>"
        f"<li>precision policy: '{esc(prec['policy'])}': float64, with every point float64 cannot decide "
        f"(|ρ − 1| within its error estimate, or not finite) recomputed with mpmath at {int(prec['digits'])} digits; "
        "each dataset records the precision of every point</li>"
        + (f"<li>parts without a section (not built): {esc(', '.join(skipped))}</li>" if skipped else "")
        + "</ul><h3>Configuration files (SHA-256)</h3>"
        + table(["file", "sha256"], files, raw_columns=(0, 1))
        + "<h3>Effective configuration per part (SHA-256 of its canonical JSON)</h3>"
        + table(["part", "sha256"], merged, raw_columns=(0, 1))
        + "</section>"
    )
    summary = [summary_section(claims, sections, datasets=datasets)] if claims else []
    toc = (
        "<nav><ul>"
        + ('<li><a href="#summary">summary</a></li>' if summary else "")
        + "".join(f'<li><a href="#{esc(part)}">{esc(part)}</a></li>' for part in parts)
        + '<li><a href="#provenance">provenance</a></li></ul></nav>'
    )
    return page(title, [toc] + summary + list(sections), provenance)

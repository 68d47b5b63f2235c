"""Building blocks of the self-contained HTML report: escaping, tables, figures, sections, the page.

>>> table(["a", "b"], [[1, "<x>"]])
'<table><thead><tr><th>a</th><th>b</th></tr></thead><tbody><tr><td>1</td><td>&lt;x&gt;</td></tr></tbody></table>'
"""

from __future__ import annotations

import base64
import html
import itertools
import math
from pathlib import Path

__all__ = [
    "number",
    "embed_image",
    "figure",
    "figure_pair",
    "table",
    "section",
    "verdict_badge",
    "page",
    "escape",
    "fold",
    "claim_anchor",
    "figure_anchor",
    "used_by",
]

escape = html.escape

STYLE = """
body{font-family:system-ui,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}
h1,h2,h3{font-weight:600} figure{margin:1.5em 0} figure img{max-width:100%;border:1px solid #ddd}
figcaption{font-size:.9em;color:#444;margin-top:.4em}
.pair{display:flex;gap:.5em;align-items:flex-start} .pair img{width:50%;min-width:0}
table{border-collapse:collapse;font-size:.9em;margin:1em 0} th,td{border:1px solid #ccc;padding:.3em .6em;vertical-align:top}
th{background:#f4f4f4} .pass{color:#0a0;font-weight:600} .fail{color:#c00;font-weight:600}
.undecided{color:#a60;font-weight:600} code{font-size:.9em} .note{font-size:.9em;color:#444}
details summary{cursor:pointer} .usedby{font-size:.85em;color:#555;margin-top:.2em}
#summary{border:2px solid #bbb;padding:0 1em 1em;border-radius:6px;background:#fafafa}
tr:target,figure:target{outline:3px solid #f0c040}
"""

#: Longer claim texts (statement, measured, note) fold away behind their first words.
FOLD_AT = 200


#: zlib level of the palette PNGs: on the project's figures level 9 (``optimize``) makes them 8 % smaller
#: than level 7 and takes six times as long (the larger part of a report section's time); the pixels are the same.
PALETTE_ZLIB_LEVEL = 7


def number(x, fmt: str = ".3g") -> str:
    """``x`` formatted by ``fmt``, a dash where it is not finite (a quantity the data do not give)."""
    x = float(x)
    return format(x, fmt) if math.isfinite(x) else "—"


def compact_png(data: bytes) -> bytes:
    """The smaller of a PNG and its 256-colour palette version (no dithering; deterministic).

    Figures have few distinct colours apart from anti-aliased edges and colour
    fields, so the palette PNG is about a third of the size
    (``benchmarks/report_size.py``); figures with transparency are left as they are.
    """
    import io

    from PIL import Image

    with Image.open(io.BytesIO(data)) as im:
        if im.mode == "P" or (im.mode == "RGBA" and im.getextrema()[3][0] < 255):
            return data  # already a palette, or transparent
        # maximum coverage: the smallest files and the smallest colour error (at most 14 of 255 per channel
        # on the project's figures, where median cut leaves up to 91 and bands the colour bars)
        pal = im.convert("RGB").quantize(256, method=Image.Quantize.MAXCOVERAGE, dither=Image.Dither.NONE)
        buf = io.BytesIO()
        pal.save(buf, "PNG", compress_level=PALETTE_ZLIB_LEVEL)
    return buf.getvalue() if buf.tell() < len(data) else data


def embed_image(path) -> str:
    """``data:`` URI of a figure in its most compact form: an SVG next to the PNG where one exists
    and is smaller (vector line plots), else the PNG, palette-compressed where that is smaller."""
    path = Path(path)
    png = compact_png(path.read_bytes())
    svg = path.with_suffix(".svg")
    if svg.exists() and svg.stat().st_size < len(png):
        return "data:image/svg+xml;base64," + base64.b64encode(svg.read_bytes()).decode("ascii")
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def figure_anchor(part: str, path) -> str:
    """The ``id`` of a figure in the page: ``<part>-<file stem>`` (e.g. ``stability-fig10``)."""
    return f"{part}-{Path(path).stem}"


def claim_anchor(part: str, claim_id: str) -> str:
    """The ``id`` of a claim's row in its part's claims table."""
    return f"{part}-claim-{claim_id}"


def used_by(part: str, claim_ids) -> str:
    """``Used by claims: a, b`` with links to the claims' rows (empty if none)."""
    ids = list(dict.fromkeys(claim_ids))
    if not ids:
        return ""
    links = ", ".join(f'<a href="#{escape(claim_anchor(part, c))}">{escape(c)}</a>' for c in ids)
    return f'<div class="usedby">Used by claims: {links}</div>'


def _figure_attrs(anchor, paper_figures) -> str:
    out = f' id="{escape(anchor)}"' if anchor else ""
    if paper_figures:
        out += f' data-paper-figures="{escape(" ".join(str(f) for f in paper_figures))}"'
    return out


def figure(png_path, caption_html: str, alt: str = "", *, anchor=None, paper_figures=(), claims_html="") -> str:
    """A figure with its caption; ``anchor`` its ``id``, ``paper_figures`` the paper's figure numbers it
    shows (the summary links to it by them), ``claims_html`` the claims that use it (:func:`used_by`)."""
    return (
        f'<figure{_figure_attrs(anchor, paper_figures)}><img src="{embed_image(png_path)}" '
        f'alt="{escape(alt or Path(png_path).stem)}"><figcaption>{caption_html}{claims_html}</figcaption></figure>'
    )


def figure_pair(left_png, right_png, caption_html: str, *, anchor=None, paper_figures=(), claims_html="") -> str:
    """Two figures side by side under one caption (e.g. a convergence figure and its local slopes)."""
    imgs = "".join(f'<img src="{embed_image(p)}" alt="{escape(Path(p).stem)}">' for p in (left_png, right_png))
    return (
        f'<figure{_figure_attrs(anchor, paper_figures)}><div class="pair">{imgs}</div>'
        f"<figcaption>{caption_html}{claims_html}</figcaption></figure>"
    )


def fold(text: str, limit: int = FOLD_AT) -> str:
    """Escaped ``text``; longer than ``limit`` characters, folded behind its first words (``<details>``).

    >>> fold("short")
    'short'
    >>> fold("word " * 50, limit=20)[:39]
    '<details><summary>word word …</summary>'
    """
    text = str(text)
    if len(text) <= limit:
        return escape(text)
    head = text[: limit // 2].rsplit(" ", 1)[0]
    return f"<details><summary>{escape(head)} …</summary>{escape(text)}</details>"


def verdict_badge(verdict: str) -> str:
    """``pass`` / ``fail`` / ``undecided`` rendered with a colour."""
    cls = {"pass": "pass", "fail": "fail"}.get(verdict, "undecided")
    return f'<span class="{cls}">{escape(verdict)}</span>'


def table(header, rows=None, *, raw_columns=(), row_ids=None) -> str:
    """An HTML table; cells in ``raw_columns`` (indices) are inserted unescaped; ``row_ids`` (one per
    row, or None) give rows an ``id`` to link to.

    ``header`` may be a :class:`pandas.DataFrame` (then ``rows`` is not given): its columns are the
    header and its rows the rows, rendered exactly as the same lists would be.
    """
    if rows is None:  # a DataFrame
        header, rows = list(header.columns), header.itertuples(index=False, name=None)
    ids = row_ids if row_ids is not None else itertools.repeat(None)
    head = "".join(f"<th>{escape(str(h))}</th>" for h in header)
    body = []
    for row, rid in zip(rows, ids):
        cells = "".join(f"<td>{c if i in raw_columns else escape(str(c))}</td>" for i, c in enumerate(row))
        body.append(f'<tr id="{escape(rid)}">{cells}</tr>' if rid else f"<tr>{cells}</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def section(title: str, body_html: str, anchor: str) -> str:
    return f'<section id="{escape(anchor)}"><h2>{escape(title)}</h2>{body_html}</section>'


def page(title: str, sections_html: list[str], provenance_html: str = "") -> str:
    toc = ""
    return (
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
        f"<title>{escape(title)}</title><style>{STYLE}</style></head><body>"
        f"<h1>{escape(title)}</h1>{toc}{''.join(sections_html)}{provenance_html}</body></html>"
    )

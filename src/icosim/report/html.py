"""Building blocks of the self-contained HTML report: escaping, tables, figures, sections, the page.

>>> table(["a", "b"], [[1, "<x>"]])
'<table><thead><tr><th>a</th><th>b</th></tr></thead><tbody><tr><td>1</td><td>&lt;x&gt;</td></tr></tbody></table>'
"""

from __future__ import annotations

import base64
import html
from pathlib import Path

__all__ = ["embed_png", "figure", "figure_pair", "table", "section", "verdict_badge", "page", "escape"]

escape = html.escape

STYLE = """
body{font-family:system-ui,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}
h1,h2,h3{font-weight:600} figure{margin:1.5em 0} figure img{max-width:100%;border:1px solid #ddd}
figcaption{font-size:.9em;color:#444;margin-top:.4em}
.pair{display:flex;gap:.5em;align-items:flex-start} .pair img{width:50%;min-width:0}
table{border-collapse:collapse;font-size:.9em;margin:1em 0} th,td{border:1px solid #ccc;padding:.3em .6em;vertical-align:top}
th{background:#f4f4f4} .pass{color:#0a0;font-weight:600} .fail{color:#c00;font-weight:600}
.undecided{color:#a60;font-weight:600} code{font-size:.9em} .note{font-size:.9em;color:#444}
"""


def embed_png(path) -> str:
    """``data:`` URI of a PNG file, so the page needs no other files."""
    data = base64.b64encode(Path(path).read_bytes()).decode("ascii")
    return f"data:image/png;base64,{data}"


def figure(png_path, caption_html: str, alt: str = "") -> str:
    return (
        f'<figure><img src="{embed_png(png_path)}" alt="{escape(alt or Path(png_path).stem)}">'
        f"<figcaption>{caption_html}</figcaption></figure>"
    )


def figure_pair(left_png, right_png, caption_html: str) -> str:
    """Two figures side by side under one caption (e.g. a convergence figure and its local slopes)."""
    imgs = "".join(f'<img src="{embed_png(p)}" alt="{escape(Path(p).stem)}">' for p in (left_png, right_png))
    return f'<figure><div class="pair">{imgs}</div><figcaption>{caption_html}</figcaption></figure>'


def verdict_badge(verdict: str) -> str:
    """``pass`` / ``fail`` / ``undecided`` rendered with a colour."""
    cls = {"pass": "pass", "fail": "fail"}.get(verdict, "undecided")
    return f'<span class="{cls}">{escape(verdict)}</span>'


def table(header, rows=None, *, raw_columns=()) -> str:
    """An HTML table; cells in ``raw_columns`` (indices) are inserted unescaped.

    ``header`` may be a :class:`pandas.DataFrame` (then ``rows`` is not given): its columns are the
    header and its rows the rows, rendered exactly as the same lists would be.
    """
    if rows is None:  # a DataFrame
        header, rows = list(header.columns), header.itertuples(index=False, name=None)
    head = "".join(f"<th>{escape(str(h))}</th>" for h in header)
    body = []
    for row in rows:
        cells = "".join(f"<td>{c if i in raw_columns else escape(str(c))}</td>" for i, c in enumerate(row))
        body.append(f"<tr>{cells}</tr>")
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

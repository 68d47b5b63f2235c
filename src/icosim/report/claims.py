"""The claims table of a report section, from the verdict records of :func:`icosim.verdicts.write_verdicts`."""

from __future__ import annotations

from . import html as rp

__all__ = ["claims_table", "claims_markdown"]


def claims_table(records, *, note_header: str = "note", part: str | None = None) -> str:
    """HTML table of verdict records (claim, source, figures, verdict and reference, measured, note).

    Long texts fold away (:func:`icosim.report.html.fold`); with ``part`` each row has the ``id``
    :func:`icosim.report.html.claim_anchor` that the summary and the figures link to.
    """
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
                f"<b>{rp.escape(c['id'])}</b><br>{rp.fold(c['statement'])}",
                rp.escape(c["source"]),
                rp.escape(", ".join(c["figures"])),
                rp.verdict_badge(c["verdict"]) + rp.escape(ref_note),
                rp.fold(c["measured"]),
                rp.fold(c["note"]),
            ]
        )
    ids = None if part is None else [rp.claim_anchor(part, c["id"]) for c in records]
    return rp.table(
        ["claim", "source", "figures", "verdict", "measured", note_header],
        rows,
        raw_columns=(0, 1, 2, 3, 4, 5),
        row_ids=ids,
    )


def claims_markdown(claims, describe) -> str:
    """A Markdown table of claims for the documentation: what each says, what its check reads, what
    data outcome would make it fail, and its recorded full-resolution verdict.

    ``describe(claim) -> {"check": ..., "fails_if": ...}`` (:func:`icosim.claims.registry.describe_claim`).
    """

    def cell(text) -> str:
        return " ".join(str(text).split()).replace("|", "\\|")

    lines = ["| claim | statement | check | fails if | verdict |", "|---|---|---|---|---|"]
    for c in claims:
        d = describe(c)
        verdict = c.reference or "–"
        lines.append(
            f"| `{c.id}` ({cell(c.source)}) | {cell(c.statement)} | {cell(d['check'])} | {cell(d['fails_if'])} "
            f"| {verdict} |"
        )
    return "\n".join(lines) + "\n"

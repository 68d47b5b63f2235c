"""The claims table of a report section, from the verdict records of :func:`icosim.claims.write_verdicts`."""

from __future__ import annotations

from . import html as rp

__all__ = ["claims_table"]


def claims_table(records, *, note_header: str = "note") -> str:
    """HTML table of verdict records (claim, source, figures, verdict and reference, measured, note)."""
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

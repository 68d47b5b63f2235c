"""The stability section of the report (Figs. 9-20): decisions, precision and cost, claims, figures.

Everything shown comes from generated files -- the figures, the claim verdicts
and the panel datasets' attributes (precision and timing) -- and from the
configuration (the decisions).
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

from ..claims import verdict_counts
from ..stability.panels import RATIOS, row_label
from . import html as rp
from .claims import claims_table

__all__ = ["stability_section"]

esc = rp.escape
KEYS = ("panels", "points", "hp", "hp_axis", "cpu64", "cpump")


def fmt_grid(g):
    return f"{g['n']} × {g['n']} points over λ̄r1 ∈ [{g['lr1'][0]:g}, {g['lr1'][1]:g}], λ̄i1 ∈ [{g['li1'][0]:g}, {g['li1'][1]:g}]"


def cost_row(label, t):
    cpu = t["cpu64"] + t["cpump"]
    return [
        label,
        int(t["panels"]),
        int(t["points"]),
        int(t["hp"]),
        int(t["hp_axis"]),
        f"{t['hp'] / t['points']:.2%}",
        f"{t['cpu64']:.1f}",
        f"{t['cpump']:.1f}",
        f"{t['cpump'] / max(cpu, 1e-12):.0%}",
    ]


def cost_table(panel_attrs, figures):
    """Per figure (rows, in the order of ``figures``): panels, points, high-precision points (on the undamped
    axis too) and CPU seconds of the float64 pass and of the rechecks, summed over the panels' attributes."""
    import pandas as pd

    columns = {
        "n_points": "points",
        "n_high_precision": "hp",
        "n_high_precision_undamped": "hp_axis",
        "cpu_seconds_float64": "cpu64",
        "cpu_seconds_mp": "cpump",
    }
    df = pd.DataFrame(list(panel_attrs), columns=["figure", *columns]).rename(columns=columns)
    df["figure"] = df["figure"].astype(str)
    sums = df.groupby("figure").agg(panels=("points", "size"), **{c: (c, "sum") for c in columns.values()})
    return sums.reindex([str(f) for f in figures], fill_value=0).astype(float)[list(KEYS)]


def stability_section(
    *,
    figures: dict,
    grid: dict,
    zoom_grid: dict,
    precision: dict,
    style: str,
    decisions: list,
    panel_attrs: list,
    claims: list,
    figure_pngs: list,
) -> str:
    """The section as an HTML fragment.

    ``figures``, ``grid``, ``zoom_grid``, ``precision``, ``style`` and
    ``decisions`` are the configuration (``stability:``); ``panel_attrs`` the
    attributes of every panel dataset, ``claims`` the verdict records
    (:func:`icosim.claims.read_verdicts`), ``figure_pngs`` the figures
    (``.../fig<figure>.png``), in the order shown.
    """
    # -- panel attributes: precision and cost, per figure (and all) ---------------------------------
    attrs_by_fig = defaultdict(list)
    for attrs in panel_attrs:
        attrs_by_fig[attrs["figure"]].append(attrs)
    per_figure = cost_table(panel_attrs, list(figures))
    cost_rows = [cost_row(f"Fig. {fig}", t) for fig, t in per_figure.iterrows()]
    t = per_figure.sum()
    cost_rows.append(cost_row("all", t))

    # -- decisions, read from the configuration ---------------------------------------------------
    raised = sorted(
        {
            float(v)
            for fig, cfg in figures.items()
            for row in cfg["rows"]
            for key, v in row.items()
            if key in RATIOS and cfg["ratios"].get(key) != v
        }
    )
    zooms = [
        f"Fig. {fig}: rows {', '.join(map(str, cfg['zoom']['rows']))}, k = {', '.join(map(str, cfg['zoom']['k']))}"
        for fig, cfg in figures.items()
        if cfg.get("zoom")
    ]
    pairs = {
        fig: [row_label(cfg, r) for r in range(1, len(cfg["rows"]) + 1)]
        for fig, cfg in figures.items()
        if cfg["method"] == "weighted" and not cfg["params"]
    }
    computed = [
        "Rows of Figs. 9–15: row 1 is (αm21, αλr21, αλi21) = (1, 1, 1); rows 2, 3, 4 raise αm21, αλr21, αλi21 "
        f"in turn to {', '.join(f'{v:g}' for v in raised) or '(none)'}.",
        f"Full panels: {fmt_grid(grid)}.",
        f"Zoom panels near the origin: {fmt_grid(zoom_grid)}, for " + ("; ".join(zooms) or "no figure") + ".",
    ]
    for fig, labels in pairs.items():
        computed.append(f"Fig. {fig}: the three (a, b) pairs are " + "; ".join(labels) + ".")
    computed.append(
        f"Precision: policy '{precision['policy']}': float64 over the whole grid; every point whose float64 value cannot "
        f"decide ρ ≤ 1 (|ρ − 1| within its error estimate, or not finite) is recomputed with mpmath at {precision['digits']} "
        "digits (the paper's 128 decimal places). Each dataset records which precision decided each point (variable digits)."
    )
    hp_share = t["hp"] / t["points"]
    cpu = t["cpu64"] + t["cpump"]
    body = [
        "<h3>What was computed</h3><ul>"
        + "".join(f"<li>{esc(d)}</li>" for d in computed)
        + "</ul>"
        + ("<h3>Why</h3><ul>" + "".join(f"<li>{esc(d)}</li>" for d in decisions) + "</ul>" if decisions else ""),
        f"<p>{int(t['hp'])} of {int(t['points'])} grid points ({hp_share:.2%}) needed high precision, "
        f"{int(t['hp_axis'])} of them on the undamped axis λ̄r1 = 0 (ρ = 1 to working precision there, which float64 "
        f"cannot decide). The rechecks took {t['cpump'] / max(cpu, 1e-12):.0%} of the sweeps' compute time "
        f"({t['cpump']:.0f} of {cpu:.0f} CPU-seconds in {int(t['panels'])} panel jobs; process start-up and file "
        "writing not included).</p>",
    ]

    # -- claims -------------------------------------------------------------------------------------
    counts = verdict_counts(claims)
    body.append(
        f"<h3>The paper's claims</h3><p>{len(claims)} claims from Sects. 3.1–3.6 and 5 (config/claims/stability.yaml), "
        f"evaluated on the datasets: {counts['pass']} pass, {counts['fail']} fail, {counts['undecided']} undecided. "
        "Shares are of stable grid points; differences below the grid resolution 1/(n−1) are undecided. "
        "Where the data disagree with the paper, the data stand.</p>"
        + claims_table(claims, note_header="how the words were read", part="stability")
    )
    body.append(
        "<h3>Precision and cost per figure</h3>"
        + rp.table(
            [
                "figure",
                "panels",
                "points",
                "high precision",
                "of them at λ̄r1 = 0",
                "share of points",
                "float64 CPU s",
                "mp CPU s",
                "mp share of CPU",
            ],
            cost_rows,
        )
    )

    # -- figures --------------------------------------------------------------------------------------
    shown = (
        "ρ as a colour field (green ρ < 1, yellow ρ = 1, red ρ > 1, grey not finite), black line ρ = 1"
        if style == "field"
        else "green circles at stable grid points (the paper's style), black line ρ = 1"
    )
    for png in figure_pngs:
        fig = Path(png).stem.removeprefix("fig")
        cfg = figures[fig]
        al = attrs_by_fig[fig]
        hp = sum(a["n_high_precision"] for a in al)
        n = sum(a["n_points"] for a in al)
        params = ", ".join(f"{k} = {v:g}" for k, v in cfg["params"].items())
        rows_txt = "; ".join(f"row {r}: {row_label(cfg, r)}" for r in range(1, len(cfg["rows"]) + 1))
        zoom_txt = (
            f" Zoom columns (right; outlined in blue on the full panels): {fmt_grid(zoom_grid)}, rows {', '.join(map(str, cfg['zoom']['rows']))}, k = {', '.join(map(str, cfg['zoom']['k']))}."
            if cfg.get("zoom")
            else ""
        )
        caption = (
            f"<b>Fig. {fig}</b> (paper Fig. {fig}): {esc(cfg['title'])}. Method {esc(cfg['method'])}"
            + (f" ({esc(params)})" if params else "")
            + f", decomposition {esc(cfg['decomposition'])}, columns k = {', '.join(map(str, cfg['k']))}; {esc(rows_txt)}. "
            + f"Grid {esc(fmt_grid(grid))}.{esc(zoom_txt)} Precision: {hp} of {n} points recomputed with mpmath at "
            + f"{precision['digits']} digits, the rest float64. Shown: {esc(shown)}."
        )
        body.append(
            rp.figure(
                png,
                caption,
                alt=f"Fig. {fig}",
                anchor=rp.figure_anchor("stability", png),
                paper_figures=[fig],
                claims_html=rp.used_by("stability", [c["id"] for c in claims if fig in c["figures"]]),
            )
        )

    return rp.section("Stability (Figs. 9–20)", "".join(body), "stability")

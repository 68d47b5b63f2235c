"""The stability section of the report (Figs. 9-20): decisions, precision and cost, claims, figures.

Everything shown comes from generated files -- the figures, the claim verdicts
and the panel datasets' attributes (precision and timing) -- and from the
configuration (the decisions).
"""

from __future__ import annotations

from pathlib import Path

from ..labels import figure_label
from ..studies.stability.panels import RATIOS, row_label
from ..verdicts import verdict_counts
from . import html as rp
from .claims import claims_table

__all__ = ["stability_section"]

esc = rp.escape
KEYS = ("panels", "points", "cert", "marginal", "hp_axis", "audited", "overturned", "cpu64", "cpucert")


def fmt_grid(g):
    return f"{g['n']} × {g['n']} points over λ̄r1 ∈ [{g['lr1'][0]:g}, {g['lr1'][1]:g}], λ̄i1 ∈ [{g['li1'][0]:g}, {g['li1'][1]:g}]"


def cost_row(label, t):
    cpu = t["cpu64"] + t["cpucert"]
    return [
        label,
        int(t["panels"]),
        int(t["points"]),
        int(t["cert"]),
        int(t["marginal"]),
        int(t["hp_axis"]),
        int(t["audited"]),
        int(t["overturned"]),
        f"{t['cpu64']:.1f}",
        f"{t['cpucert']:.1f}",
        f"{t['cpucert'] / max(cpu, 1e-12):.0%}",
    ]


def cost_table(panel_attrs, figures):
    """Per figure (rows, in the order of ``figures``): panels, points, certified points (marginal ones, on the
    undamped axis, audited, overturned) and CPU seconds of the float64 pass and of the certification, summed
    over the panels' attributes.  Panels written before certification count their multiprecision rechecks as
    certified (the only high-precision pass they had)."""
    import pandas as pd

    df = pd.DataFrame(list(panel_attrs))
    if df.empty:
        df = pd.DataFrame(columns=["figure", "n_points", "n_high_precision", "n_high_precision_undamped"])

    def col(name, fallback=0.0):
        return df[name].fillna(fallback) if name in df else pd.Series(fallback, index=df.index, dtype=float)

    parts = pd.DataFrame(
        {
            "figure": df["figure"].astype(str),
            "points": col("n_points"),
            "cert": col("n_certified", float("nan")).fillna(col("n_high_precision")),
            "marginal": col("n_marginal"),
            "hp_axis": col("n_high_precision_undamped"),
            "audited": col("n_audited"),
            "overturned": col("n_overturned"),
            "cpu64": col("cpu_seconds_float64"),
            "cpucert": col("cpu_seconds_certify") + col("cpu_seconds_mp"),
        }
    )
    value_columns = [c for c in KEYS if c != "panels"]
    sums = parts.groupby("figure").agg(panels=("points", "size"), **{c: (c, "sum") for c in value_columns})
    return sums.reindex([str(f) for f in figures], fill_value=0).astype(float)[list(KEYS)]


def overturned_html(panel_attrs) -> str:
    """Every float64 verdict that certification overturned, or that there was none and how many were checked."""
    import json

    checked = sum(a.get("n_audited", 0) for a in panel_attrs)
    rows = [
        [
            f"Fig. {a['figure']} row {a['row']} k = {a['k']} ({a['view']})",
            f"{p['lr1']:g}",
            f"{p['li1']:g}",
            p["float64_verdict"],
            p["verdict"],
            f"[{p['rho_lower']:.12g}, {p['rho_upper']:.12g}]",
        ]
        for a in panel_attrs
        for p in json.loads(a.get("overturned_points", "[]"))
    ]
    if not rows:
        return (
            f"<p><b>Overturned float64 verdicts: none.</b> {checked} points that float64 decided were also certified "
            "(every point within the band around ρ = 1 and the random audit sample), and every certified verdict "
            "agreed with float64's.</p>"
        )
    return (
        f"<p><b>Overturned float64 verdicts: {len(rows)}</b> of {checked} points checked; the certified verdict "
        "stands in the datasets and figures.</p>"
        + rp.table(["panel", "λ̄r1", "λ̄i1", "float64", "certified", "proven ρ"], rows)
    )


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
    schemes_html: str = "",
) -> str:
    """The section as an HTML fragment.

    ``figures``, ``grid``, ``zoom_grid``, ``precision``, ``style`` and
    ``decisions`` are the configuration (``stability:``); ``panel_attrs`` the
    attributes of every panel dataset, ``claims`` the verdict records
    (:func:`icosim.verdicts.read_verdicts`), ``figure_pngs`` the figures
    (``.../fig<figure>.png``), in the order shown.
    """
    # -- panel attributes: precision and cost, per figure (and all) ---------------------------------
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
    cert = {"band": 1e-6, "audit": 0.01, "bits": 128, "max_bits": 1024, **(precision.get("certify") or {})}
    computed.append(
        f"Precision: policy '{precision['policy']}': float64 over the whole grid; certified in ball arithmetic "
        "(python-flint Arb: a proven enclosure of ρ from the characteristic polynomial of the ball amplification "
        f"matrix at {cert['bits']} bits, where undecided once more at {cert['max_bits']}) are every point float64 cannot decide "
        f"(|ρ − 1| within its error estimate, or not finite), every point with |ρ − 1| < {cert['band']:g}, and a "
        f"random {cert['audit']:.0%} audit sample of the rest. Verdicts: stable (ρ < 1 proven, or float64 trusted), "
        "unstable, marginal (the proven enclosure still contains 1 at the cap, e.g. ρ = 1 exactly: drawn as blue "
        "squares), undecided. Each dataset records per point which arithmetic decided it and whether it is certified."
    )
    cpu = t["cpu64"] + t["cpucert"]
    body = [
        "<h3>What was computed</h3><ul>"
        + "".join(f"<li>{esc(d)}</li>" for d in computed)
        + "</ul>"
        + ("<h3>Why</h3><ul>" + "".join(f"<li>{esc(d)}</li>" for d in decisions) + "</ul>" if decisions else ""),
        f"<p>{int(t['cert'])} of {int(t['points'])} grid points ({t['cert'] / t['points']:.2%}) were certified, "
        f"{int(t['marginal'])} of them marginal, {int(t['hp_axis'])} on the undamped axis λ̄r1 = 0 (ρ = 1 to any "
        f"precision there for identical subsystems, which float64 cannot decide). The certification took "
        f"{t['cpucert'] / max(cpu, 1e-12):.0%} of the sweeps' compute time ({t['cpucert']:.0f} of {cpu:.0f} "
        f"CPU-seconds in {int(t['panels'])} panel jobs; process start-up and file writing not included).</p>"
        + overturned_html(panel_attrs),
    ]

    # -- claims -------------------------------------------------------------------------------------
    counts = verdict_counts(claims)
    body.append(
        f"<h3>The paper's claims</h3><p>{len(claims)} claims from Sects. 3.1–3.6 and 5 (config/claims/stability.yaml), "
        f"evaluated on the datasets: {counts['pass']} pass, {counts['fail']} fail, {counts['undecided']} undecided. "
        "Shares are of stable grid points; differences below the grid resolution 1/(n−1) are undecided, and so is a "
        "claim the marginal points could turn (they count neither as stable nor as unstable); each claim says how "
        "many of the points it uses are certified. "
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
                "certified",
                "marginal",
                "rechecked at λ̄r1 = 0",
                "float64 verdicts checked",
                "overturned",
                "float64 CPU s",
                "certification CPU s",
                "its share of CPU",
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
        fig = Path(png).stem.removeprefix("fig").split("_", 1)[0]  # fig<figure>_<scheme>
        cfg = figures[fig]
        tf = per_figure.loc[fig]
        params = ", ".join(f"{k} = {v:g}" for k, v in cfg["params"].items())
        rows_txt = "; ".join(f"row {r}: {row_label(cfg, r)}" for r in range(1, len(cfg["rows"]) + 1))
        zoom_txt = (
            f" Zoom columns (right; outlined in blue on the full panels): {fmt_grid(zoom_grid)}, rows {', '.join(map(str, cfg['zoom']['rows']))}, k = {', '.join(map(str, cfg['zoom']['k']))}."
            if cfg.get("zoom")
            else ""
        )
        caption = (
            f"<b>{figure_label(fig)}</b>{f' (paper Fig. {fig})' if fig.isdigit() else ' (beyond the paper)'}: "
            f"{esc(cfg['title'])}. Method {esc(cfg['method'])}"
            + (f" ({esc(params)})" if params else "")
            + f", decomposition {esc(cfg['decomposition'])}, columns k = {', '.join(map(str, cfg['k']))}; {esc(rows_txt)}. "
            + f"Grid {esc(fmt_grid(grid))}.{esc(zoom_txt)} Precision: {int(tf['cert'])} of {int(tf['points'])} points "
            + f"certified ({int(tf['marginal'])} marginal, blue), the rest float64. Shown: {esc(shown)}."
        )
        body.append(
            rp.figure(
                png,
                caption,
                alt=figure_label(fig),
                anchor=rp.figure_anchor("stability", png),
                paper_figures=[fig],
                claims_html=rp.used_by("stability", [c["id"] for c in claims if fig in c["figures"]]),
            )
        )

    return rp.section("Stability (Figs. 9–20)", "".join(body) + schemes_html, "stability")

"""Snakemake job: the stability section of the report (thin: icosim.report.stability, icosim.report.schemes)."""

import logging

from icosim.io.netcdf import atomic_path, open_attributes, open_dataset
from icosim.job import start_job
from icosim.report.schemes import stability_schemes
from icosim.report.stability import stability_section
from icosim.verdicts import read_verdicts, verdict_counts

start_job(snakemake.log[0])
i, p = snakemake.input, snakemake.params
claims = read_verdicts(i.claims)
paper = [c for c in claims if c.get("scope", "paper") == "paper"]
beyond = [c for c in claims if c.get("scope") == "beyond"]
attrs = [open_attributes(path) for path in i.panels]
jacobi_pngs = [f for f in i.figures if f.endswith("_jacobi.png")]
schemes_html = ""
if "shares" in i.keys():
    schemes_html = stability_schemes(
        shares=open_dataset(i.shares),
        claims=beyond,
        comparison_png=i.comparison,
        figure_pngs=[f for f in i.figures if f not in jacobi_pngs],
        figures_cfg=p.figures,
    )
html = stability_section(
    figures=p.figures,
    grid=p.grid,
    zoom_grid=p.zoom_grid,
    precision=p.precision,
    style=p.style,
    decisions=p.decisions,
    panel_attrs=[a for a in attrs if a["scheme"] == "jacobi"],
    claims=paper,
    figure_pngs=jacobi_pngs,
    schemes_html=schemes_html,
)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html)
logging.info("section with %d figures and %d claims (%s)", len(i.figures), len(claims), verdict_counts(claims))

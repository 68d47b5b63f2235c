"""Snakemake job: the stability section of the report (thin: icosim.report.stability)."""

import logging

from icosim.claims.core import read_verdicts, verdict_counts
from icosim.io.netcdf import atomic_path, open_dataset
from icosim.report.stability import stability_section

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
p = snakemake.params
claims = read_verdicts(snakemake.input.claims)
html = stability_section(
    figures=p.figures,
    grid=p.grid,
    zoom_grid=p.zoom_grid,
    precision=p.precision,
    style=p.style,
    decisions=p.decisions,
    panel_attrs=[open_dataset(path).attrs for path in snakemake.input.panels],
    claims=claims,
    figure_pngs=list(snakemake.input.figures),
)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html)
logging.info(
    "section with %d figures and %d claims (%s)", len(snakemake.input.figures), len(claims), verdict_counts(claims)
)

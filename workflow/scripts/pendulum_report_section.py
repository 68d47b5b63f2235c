"""Snakemake job: the pendulum section of the report (thin: icosim.report.pendulum)."""

import logging
from pathlib import Path

from icosim.claims.core import read_verdicts
from icosim.io.netcdf import atomic_path, open_dataset
from icosim.report.pendulum import pendulum_section, trade_section

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
summary = open_dataset(snakemake.input.summary)
trade = trade_section(
    work_precision=open_dataset(snakemake.input.work_precision),
    stability_limit=open_dataset(snakemake.input.stability_limit),
    tolerance=open_dataset(snakemake.input.tolerance),
    adaptive=open_dataset(snakemake.input.adaptive),
    figure_pngs={Path(path).stem: path for path in snakemake.input.trade_figures},
)
html = pendulum_section(
    config=snakemake.params.config,
    paper_figure=snakemake.params.paper_figure,
    summary=summary,
    claims=read_verdicts(snakemake.input.claims),
    figure_pngs=list(snakemake.input.figures),
    error_png=snakemake.input.error_figure,
    trade_html=trade,
)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html, encoding="utf-8")
logging.info("section written: %d runs, %d figures", summary.sizes["run"], len(snakemake.input.figures) + 1)

"""Snakemake job: the pendulum section of the report (thin: icosim.report.pendulum, icosim.report.schemes)."""

import logging
from pathlib import Path

from icosim.io.netcdf import atomic_path, open_dataset
from icosim.job import start_job
from icosim.report.pendulum import pendulum_section, trade_section
from icosim.report.schemes import pendulum_schemes
from icosim.verdicts import read_verdicts

start_job(snakemake.log[0])
i, p = snakemake.input, snakemake.params
summary = open_dataset(i.summary)
claims = read_verdicts(i.claims)
trade = trade_section(
    work_precision=open_dataset(i.work_precision),
    stability_limit=open_dataset(i.stability_limit),
    tolerance=open_dataset(i.tolerance),
    adaptive=open_dataset(i.adaptive),
    figure_pngs={Path(path).stem: path for path in i.trade_figures},
)
schemes_html = ""
if len(set(summary["scheme"].values.tolist())) > 1:
    schemes_html = pendulum_schemes(
        summary=summary,
        claims=[c for c in claims if c.get("scope") == "beyond"],
        figure_pngs=list(i.scheme_figures),
    )
html = pendulum_section(
    config=p.config,
    paper_figure=p.paper_figure,
    summary=summary.isel(run=(summary["scheme"] == "jacobi").values),
    claims=[c for c in claims if c.get("scope", "paper") == "paper"],
    figure_pngs=list(i.figures),
    error_png=i.error_figure,
    trade_html=trade,
    schemes_html=schemes_html,
)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html, encoding="utf-8")
logging.info("section written: %d runs, %d figures", summary.sizes["run"], len(i.figures) + 1)

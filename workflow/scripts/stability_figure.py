"""Snakemake job: draw one figure from its panel datasets, once per scheme (never recomputes)."""

import logging

from icosim.figures import save_figure
from icosim.figures.stability import drawn_variables, stability_figure
from icosim.io.netcdf import open_variables
from icosim.job import start_job

start_job(snakemake.log[0])
p = snakemake.params
panels = [open_variables(path, drawn_variables(p.style)) for path in snakemake.input.panels]
outputs = iter(snakemake.output)
for scheme, title in p.titles.items():
    mine = [ds for ds in panels if ds.attrs["scheme"] == scheme]
    fig = stability_figure(mine, title=title, style=p.style, rho_max=p.rho_max, dots_stride=p.dots_stride)
    png, pdf = next(outputs), next(outputs)
    save_figure(fig, png, pdf, dpi=p.dpi)
    logging.info("%s: drew %d panels (%s style) into %s, %s", scheme, len(mine), p.style, png, pdf)

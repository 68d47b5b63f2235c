"""Snakemake job: draw one figure of the paper from its panel datasets (never recomputes)."""

import logging

from icosim.figures import save_figure
from icosim.figures.stability import stability_figure
from icosim.io.netcdf import open_dataset

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
p = snakemake.params
panels = [open_dataset(path) for path in snakemake.input.panels]
fig = stability_figure(panels, title=p.title, style=p.style, rho_max=p.rho_max, dots_stride=p.dots_stride)
save_figure(fig, snakemake.output.png, snakemake.output.pdf, dpi=p.dpi)
logging.info("drew %d panels (%s style) into %s", len(panels), p.style, ", ".join(snakemake.output))

"""Snakemake job: draw one convergence figure from its panel datasets (never recomputes)."""

import logging

from icosim.figures import save_figure
from icosim.figures.convergence import convergence_figure, row_title, slope_figure
from icosim.io.netcdf import open_dataset

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
p = snakemake.params
datasets = {ds.attrs["panel"]: ds for ds in (open_dataset(path) for path in snakemake.input.panels)}
layout = [[(panel, int(index)) for panel, index in col] for col in p.layout]
rows = [row_title(datasets[panel].attrs["method"], index) for panel, index in layout[0]]
fig = convergence_figure(datasets, layout, columns=p.columns, rows=rows, title=p.title, guide_orders=p.guide_orders)
save_figure(fig, snakemake.output.png, snakemake.output.pdf, dpi=p.dpi)
slopes = slope_figure(
    datasets, layout, columns=p.columns, rows=rows, title=f"{p.title}: local slopes", tolerance=p.tolerance
)
save_figure(slopes, snakemake.output.slopes_png, snakemake.output.slopes_pdf, dpi=p.dpi)
logging.info("drew %d panels into %s", len(datasets), ", ".join(snakemake.output))

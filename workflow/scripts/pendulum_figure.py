"""Snakemake job: Fig. 6, 7 or 8 (one k) from the run datasets and the reference -> PNG + PDF."""

import logging

from icosim.figures import save_figure
from icosim.figures.pendulum import pendulum_figure
from icosim.io.netcdf import open_dataset

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
runs = [open_dataset(path) for path in snakemake.input.runs]
reference = open_dataset(snakemake.input.reference)
fig = pendulum_figure(runs, reference, k=int(snakemake.wildcards.k), title=snakemake.params.title)
save_figure(fig, snakemake.output.png, snakemake.output.pdf, dpi=snakemake.params.dpi)
logging.info("%d runs drawn", len(runs))

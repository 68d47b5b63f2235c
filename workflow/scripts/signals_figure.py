"""Snakemake job: the signal-coupling study's figure from its case datasets (thin: icosim.figures.signals)."""

import logging

from icosim.figures import save_figure
from icosim.figures.signals import signals_figure
from icosim.io.netcdf import open_dataset
from icosim.job import start_job

start_job(snakemake.log[0])
fig = signals_figure([open_dataset(path) for path in snakemake.input], title=snakemake.params.title)
save_figure(fig, snakemake.output.png, snakemake.output.pdf, dpi=snakemake.params.dpi)
logging.info("drew %d cases", len(snakemake.input))

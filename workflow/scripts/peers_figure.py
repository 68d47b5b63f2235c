"""Snakemake job: the peers study's figure from its system datasets (thin: icosim.figures.peers)."""

import logging

from icosim.figures import save_figure
from icosim.figures.peers import peers_figure
from icosim.io.netcdf import open_dataset
from icosim.job import start_job

start_job(snakemake.log[0])
fig = peers_figure([open_dataset(path) for path in snakemake.input], title=snakemake.params.title)
save_figure(fig, snakemake.output.png, snakemake.output.pdf, dpi=snakemake.params.dpi)
logging.info("drew %d systems", len(snakemake.input))

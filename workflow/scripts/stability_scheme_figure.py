"""Snakemake job: the coupling schemes' stable shares side by side (never recomputes)."""

import logging

from icosim.figures import save_figure
from icosim.figures.schemes import scheme_comparison_figure
from icosim.io.netcdf import open_dataset
from icosim.job import start_job

start_job(snakemake.log[0])
ds = open_dataset(snakemake.input.shares)
fig = scheme_comparison_figure(ds, title=snakemake.params.title)
save_figure(fig, snakemake.output.png, snakemake.output.pdf, dpi=snakemake.params.dpi)
logging.info("compared %d figures", ds.sizes["figure"])

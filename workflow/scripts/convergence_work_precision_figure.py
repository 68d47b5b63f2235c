"""Snakemake job: the work-precision diagram from its dataset (never recomputes)."""

import logging

from icosim.figures import save_figure
from icosim.figures.convergence import WORK_PRECISION_VARIABLES, work_precision_figure
from icosim.io.netcdf import open_variables
from icosim.job import start_job

start_job(snakemake.log[0])
wp = open_variables(snakemake.input.wp, WORK_PRECISION_VARIABLES)  # only the variables drawn, without xarray
fig = work_precision_figure(wp, title="Work-precision: CPU time per simulated second over NRMSE (Eq. 72)")
save_figure(fig, snakemake.output.png, snakemake.output.pdf, dpi=snakemake.params.dpi)
logging.info("%d configurations drawn", len(wp["configuration"]))

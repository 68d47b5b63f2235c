"""Snakemake job: the work-precision diagram from its dataset (never recomputes)."""

import logging

from icosim.figures import save_figure
from icosim.figures.convergence import work_precision_figure
from icosim.io.netcdf import open_dataset

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
wp = open_dataset(snakemake.input.wp)
fig = work_precision_figure(wp, title="Work-precision: CPU time per simulated second over NRMSE (Eq. 72)")
save_figure(fig, snakemake.output.png, snakemake.output.pdf, dpi=snakemake.params.dpi)
logging.info("%d configurations drawn", wp.sizes["configuration"])

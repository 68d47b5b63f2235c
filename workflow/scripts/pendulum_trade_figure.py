"""Snakemake job: the speed-accuracy figures (work-precision, error over H, stability limit, tolerance,
adaptive) -> PNG + PDF (thin: icosim.figures.pendulum_trade)."""

import logging

from icosim.datasets import open_dataset
from icosim.figures import pendulum_trade as fig
from icosim.figures import save_figure

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
wp = open_dataset(snakemake.input.work_precision)
limits = open_dataset(snakemake.input.stability_limit)
tolerance = open_dataset(snakemake.input.tolerance)
adaptive = open_dataset(snakemake.input.adaptive)
out, dpi = snakemake.output, snakemake.params.dpi
save_figure(fig.work_precision_figure(wp, adaptive), out.work_precision, out.work_precision_pdf, dpi=dpi)
save_figure(fig.error_over_H_figure(wp), out.error_over_H, out.error_over_H_pdf, dpi=dpi)
save_figure(fig.stability_limit_figure(limits), out.stability_limit, out.stability_limit_pdf, dpi=dpi)
save_figure(fig.tolerance_figure(tolerance), out.tolerance, out.tolerance_pdf, dpi=dpi)
save_figure(fig.adaptive_figure(adaptive), out.adaptive, out.adaptive_pdf, dpi=dpi)
logging.info("5 figures written")

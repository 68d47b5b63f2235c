"""Snakemake job: one figure of the speed-accuracy trade (work-precision, error over H, stability limit,
tolerance or adaptive) -> PNG + PDF (thin: icosim.figures.pendulum_trade)."""

import logging

from icosim.figures import save_figure
from icosim.figures.pendulum_trade import TRADE_FIGURES
from icosim.io.netcdf import open_dataset
from icosim.job import start_job
from icosim.problems.pendulum.names import TRADE_FIGURE_DATASETS

start_job(snakemake.log[0])
name = snakemake.wildcards.name
fig = TRADE_FIGURES[name](*(open_dataset(snakemake.input[stem]) for stem in TRADE_FIGURE_DATASETS[name]))
save_figure(fig, snakemake.output.png, snakemake.output.pdf, dpi=snakemake.params.dpi)
logging.info("figure %s written", name)

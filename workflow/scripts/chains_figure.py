"""Snakemake job: one figure of the chain study from its dataset (thin: icosim.figures.chains)."""

import logging

from icosim.figures import save_figure
from icosim.figures.chains import chain_convergence_figure, chain_placement_figure, chain_stability_figure
from icosim.io.netcdf import open_dataset
from icosim.job import start_job

start_job(snakemake.log[0])
draw = {
    "stability": chain_stability_figure,
    "convergence": chain_convergence_figure,
    "placement": chain_placement_figure,
}
part = snakemake.wildcards.part
fig = draw[part](open_dataset(snakemake.input[0]), title=snakemake.params.titles[part])
save_figure(fig, snakemake.output.png, snakemake.output.pdf, dpi=snakemake.params.dpi)
logging.info("drew %s", part)

"""Snakemake job: Figs. 6, 7 and 8 (every k) with one scheme, from the run datasets and the reference -> PNG + PDF."""

import logging

from icosim.figures import save_figure
from icosim.figures.pendulum import DRAWN_VARIABLES, pendulum_figure
from icosim.io.netcdf import open_variables
from icosim.job import start_job

start_job(snakemake.log[0])
p = snakemake.params
# only the variables drawn, without xarray (icosim.io.netcdf.open_variables)
runs = [open_variables(path, DRAWN_VARIABLES) for path in snakemake.input.runs]
reference = open_variables(snakemake.input.reference, DRAWN_VARIABLES)
outputs = iter(snakemake.output)
for k, title in zip(p.k, p.titles, strict=True):
    mine = [ds for ds in runs if int(ds.attrs["k"]) == int(k)]
    fig = pendulum_figure(mine, reference, k=int(k), title=title)
    png, pdf = next(outputs), next(outputs)
    save_figure(fig, png, pdf, dpi=p.dpi)
    logging.info("k = %s: %d runs drawn into %s", k, len(mine), png)

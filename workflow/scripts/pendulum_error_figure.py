"""Snakemake job: error of every run against the monolithic reference -> PNG."""

import logging

from icosim.figures import save_figure
from icosim.figures.pendulum import DRAWN_VARIABLES, error_figure
from icosim.io.netcdf import open_variables
from icosim.job import start_job

start_job(snakemake.log[0])
runs_by_k = {}
for path in snakemake.input.runs:
    ds = open_variables(path, DRAWN_VARIABLES)  # only the variables drawn, without xarray
    runs_by_k.setdefault(int(ds.attrs["k"]), []).append(ds)
reference = open_variables(snakemake.input.reference, DRAWN_VARIABLES)
save_figure(error_figure(runs_by_k, reference), snakemake.output[0], dpi=snakemake.params.dpi)
logging.info("%d runs drawn", sum(len(v) for v in runs_by_k.values()))

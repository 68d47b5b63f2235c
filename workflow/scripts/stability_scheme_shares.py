"""Snakemake job: stable shares per figure, row, k and scheme from the full panels (thin: icosim.studies.stability.comparison)."""

import logging

from icosim.io.netcdf import open_variables, provenance_attrs, write_netcdf
from icosim.job import start_job
from icosim.studies.stability.checks import PANEL_VARIABLES
from icosim.studies.stability.comparison import scheme_shares_data

start_job(snakemake.log[0])
panels = [open_variables(path, PANEL_VARIABLES) for path in snakemake.input.panels]  # the shares read no others
job = {"panels": list(snakemake.input.panels)}
ds = scheme_shares_data(
    panels,
    provenance=provenance_attrs(
        job, title="Stable shares of the coupling schemes", command="snakemake rule stability_scheme_shares"
    ),
)
write_netcdf(ds, snakemake.output[0])
logging.info("shares of %d figures x %d rows x %d k x %d schemes", *ds.sizes.values())

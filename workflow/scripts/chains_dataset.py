"""Snakemake job: one part of the chain study (stability, convergence or placement) as a NetCDF dataset
(thin: icosim.studies.chains)."""

import logging

from icosim.io.netcdf import write_netcdf
from icosim.job import start_job
from icosim.studies.chains.convergence import convergence_data
from icosim.studies.chains.placement import placement_data
from icosim.studies.chains.stability import stability_data

start_job(snakemake.log[0])
build = {"stability": stability_data, "convergence": convergence_data, "placement": placement_data}
ds = build[snakemake.wildcards.part](dict(snakemake.params.config), command=f"rule {snakemake.rule}", log=logging.info)
write_netcdf(ds, snakemake.output[0])
logging.info("wrote %s", snakemake.output[0])

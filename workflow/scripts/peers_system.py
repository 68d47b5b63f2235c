"""Snakemake job: one system of the peers study, every master's runs (thin: icosim.studies.peers.study.system_data)."""

import logging

from icosim.io.netcdf import write_netcdf
from icosim.job import start_job
from icosim.studies.peers.study import system_data

start_job(snakemake.log[0])
system = snakemake.wildcards.system
ds = system_data(dict(snakemake.params.config), system, root=".")
write_netcdf(ds, snakemake.output[0])
status = ds["data_vars"]["status"]["data"]
logging.info("%s: %d runs, %d completed, %.1f s CPU", system, len(status), sum(s == "completed" for s in status),
             ds.attrs["cpu_seconds"])  # fmt: skip

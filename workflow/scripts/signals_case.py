"""Snakemake job: one case of the signal-coupling study over its H (thin: icosim.studies.signals.study.case_data)."""

import logging

from icosim.io.netcdf import write_netcdf
from icosim.job import start_job
from icosim.studies.signals.study import case_data

start_job(snakemake.log[0])
p = snakemake.params
ds = case_data(dict(p.config), dict(p.case), root=".")
write_netcdf(ds, snakemake.output[0])
a = ds.attrs
logging.info("%s: order %.3f (%s), %.1f s CPU", a["case"], a["order"], a["order_status"], a["cpu_seconds"])

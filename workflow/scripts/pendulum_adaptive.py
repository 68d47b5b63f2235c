"""Snakemake job: adaptive macro steps against fixed H at equal error -> NetCDF
(thin: icosim.studies.trade.adaptive)."""

import logging

from icosim.io.netcdf import write_netcdf
from icosim.job import start_job
from icosim.studies.trade.adaptive import adaptive_study_data

start_job(snakemake.log[0])
p = snakemake.params


def log(kind, label, x, rec):
    logging.info(
        "%-8s %-22s %.1e %-8s err %.2e steps %d cpu %.2f s %s",
        *(kind, label, x, rec["status"], rec["error_max"], rec["n_macro_steps"], rec["cpu_seconds"], rec["reason"]),
    )


ds = adaptive_study_data(
    dict(p.settings), dict(p.adaptive), reference=dict(p.reference), command="snakemake rule pendulum_adaptive", log=log
)
write_netcdf(ds, snakemake.output[0])

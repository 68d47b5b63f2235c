"""Snakemake job: error over the links' Radau tolerance at fixed H -> NetCDF (thin: icosim.studies.trade.tolerance)."""

import logging

from icosim.io.netcdf import write_netcdf
from icosim.job import start_job
from icosim.studies.trade.tolerance import tolerance_study_data

start_job(snakemake.log[0])
p = snakemake.params
tol = p.tolerance


def log(label, H, rtol, rec, effect):
    logging.info("%-22s H=%.0e rtol=%.0e err %.3e effect %.2e", label, H, rtol, rec["error_max"], effect)


ds = tolerance_study_data(
    dict(p.settings),
    [dict(c) for c in tol["configurations"]],
    list(tol["H"]),
    list(tol["rtol"]),
    p.t_end,
    reference=dict(p.reference),
    command="snakemake rule pendulum_tolerance",
    log=log,
)
ds.attrs["share"] = float(tol["share"])
write_netcdf(ds, snakemake.output[0])

"""Snakemake job: the monolithic pendulum over tolerances (Radau IIA, DOP853) and the linear test model's
errors for every configuration -> two NetCDF files (thin: icosim.studies.trade.baselines)."""

import logging

from icosim.io.netcdf import write_netcdf
from icosim.job import start_job
from icosim.problems.pendulum.model import PendulumParameters
from icosim.studies.trade.baselines import linear_orders_dataset_data, monolithic_baselines_data

start_job(snakemake.log[0])
p = snakemake.params
mono = monolithic_baselines_data(
    PendulumParameters(**p.settings["model"]),
    p.monolithic["tolerances"],
    p.t_end,
    reference=dict(p.reference),
    repeats=p.monolithic["repeats"],
    command="snakemake rule pendulum_baselines",
)
write_netcdf(mono, snakemake.output.monolithic)
logging.info("monolithic: %s", mono.array("error_max").tolist())
lin = p.linear_orders
ds = linear_orders_dataset_data(
    dict(p.settings),
    [tuple(c) for c in p.configs],
    list(p.H),
    model=dict(lin["model"]),
    x0=lin["x0"],
    t_end=lin["t_end"],
    command="snakemake rule pendulum_baselines",
)
write_netcdf(ds, snakemake.output.linear)
logging.info("linear errors for %d configurations", ds.sizes["config"])

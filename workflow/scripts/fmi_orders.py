"""Snakemake job: one configuration of the linear convergence study on the FMU units over H, with the built-in
model's errors and both orders (thin: icosim.studies.fmi.orders.order_case_data)."""

import logging
from pathlib import Path

from icosim.io.netcdf import write_netcdf
from icosim.job import start_job
from icosim.studies.fmi.orders import order_case_data

start_job(snakemake.log[0])
p = snakemake.params
case = {key: value for key, value in p.case.items() if key != "H"}
ds = order_case_data(
    case,
    H=p.case["H"],
    t_end=p.t_end,
    model=dict(p.model),
    x0=p.x0,
    units_dir=p.units_dir,
    cache=Path(snakemake.input.units).parent,
    fit=dict(p.fit),
)
write_netcdf(ds, snakemake.output[0])
a = ds.attrs
logging.info(
    "%s: order %.3f (%s), built-in %.3f (%s)",
    a["case"],
    a["order_fmu"],
    a["status_fmu"],
    a["order_builtin"],
    a["status_builtin"],
)

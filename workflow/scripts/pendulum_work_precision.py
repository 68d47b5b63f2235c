"""Snakemake job: results/pendulum/work_precision.nc from the sweep groups, the monolithic baselines and the
linear test model's errors: orders, cheapest scheme per accuracy level (thin: icosim.studies.trade.work_precision)."""

import logging

from icosim.io.netcdf import open_dataset, write_netcdf
from icosim.job import start_job
from icosim.studies.trade.work_precision import work_precision_dataset

start_job(snakemake.log[0])
p = snakemake.params
ds = work_precision_dataset(
    [open_dataset(path) for path in snakemake.input.sweeps],
    open_dataset(snakemake.input.monolithic),
    open_dataset(snakemake.input.linear),
    fit=dict(p.fit),
    accuracy_levels=list(p.accuracy_levels),
    command="snakemake rule pendulum_work_precision",
)
write_netcdf(ds, snakemake.output[0])
for label, order, status, lin, lin_status in zip(
    *(ds[v].values for v in ("config", "order", "order_status", "order_linear", "order_linear_status"))
):
    logging.info("%-22s order %.2f (%s), linear %.2f (%s)", label, order, status, lin, lin_status)

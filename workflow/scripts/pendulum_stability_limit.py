"""Snakemake job: results/pendulum/stability_limit.nc from the groups' limits (thin: icosim.studies.trade.stability_limit)."""

import logging

from icosim.io.netcdf import open_dataset, provenance_attrs, write_netcdf
from icosim.job import start_job
from icosim.studies.trade.stability_limit import merge_limits

start_job(snakemake.log[0])
ds = merge_limits([open_dataset(path) for path in snakemake.input.groups])
ds.attrs.update(
    provenance_attrs(
        {"groups": list(snakemake.input.groups)},
        title="Double pendulum: stability limit in H, measured and predicted",
        command="snakemake rule pendulum_stability_limit",
    )
)
write_netcdf(ds, snakemake.output[0])
for label, h, hl in zip(ds["config"].values, ds["H_max"].values, ds["H_max_linear"].values):
    logging.info("%-22s H_max %.4g linear %.4g", label, h, hl)

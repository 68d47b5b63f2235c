"""Snakemake job: error over H of one group (scheme, method, decomposition; every k) -> NetCDF
(thin: icosim.pendulum.trade.sweep)."""

import logging

from icosim.io.netcdf import write_netcdf
from icosim.pendulum.trade.sweep import sweep_group

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
p = snakemake.params


def log(label, H, rec):
    logging.info(
        "%-22s H=%.1e %-8s err %.2e cpu %.3f s %s",
        *(label, H, rec["status"], rec["error_max"], rec["cpu_seconds"], rec["reason"]),
    )


ds = sweep_group(
    dict(p.settings),
    p.scheme,
    p.method,
    p.decomposition,
    list(p.k),
    list(p.H),
    p.t_end,
    reference=dict(p.reference),
    integrator=dict(p.integrator),
    repeats=p.timing["repeats"],
    repeat_below=p.timing["repeat_below"],
    command="snakemake rule pendulum_sweep",
    log=log,
)
write_netcdf(ds, snakemake.output[0])

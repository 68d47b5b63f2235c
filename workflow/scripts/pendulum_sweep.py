"""Snakemake job: error over H of one (method, decomposition), for every scheme (every k) -> one NetCDF per
scheme (thin: icosim.pendulum.trade.sweep)."""

import logging

from icosim.io.netcdf import write_netcdf
from icosim.pendulum.trade.sweep import sweep_group

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
w, p = snakemake.wildcards, snakemake.params


def log(label, H, rec):
    logging.info(
        "%-22s H=%.1e %-8s err %.2e cpu %.3f s %s",
        *(label, H, rec["status"], rec["error_max"], rec["cpu_seconds"], rec["reason"]),
    )


for scheme, path in zip(p.schemes, snakemake.output, strict=True):
    ds = sweep_group(
        dict(p.settings),
        scheme,
        w.method,
        w.decomposition,
        list(p.k),
        list(p.H),
        p.t_end,
        reference=dict(p.reference),
        integrator=dict(p.integrator),
        repeats=p.timing["repeats"],
        repeat_below=p.timing["repeat_below"],
        command=f"snakemake rule {snakemake.rule}",
        log=log,
    )
    write_netcdf(ds, path)

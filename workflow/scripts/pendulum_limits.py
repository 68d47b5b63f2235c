"""Snakemake job: largest stable H of one (method, decomposition), for every scheme, measured (bisection on
divergence) and predicted by the linear test model -> one NetCDF per scheme
(thin: icosim.pendulum.trade.stability_limit)."""

import logging

from icosim.io.netcdf import write_netcdf
from icosim.pendulum.trade.stability_limit import limits_study

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
w, p = snakemake.wildcards, snakemake.params


def log(label, measured, predicted):
    logging.info(
        "%-22s measured %s H_max %.4g (%d runs); linear %s H_max %.4g",
        *(label, measured.status, measured.H_max, measured.n_evaluations, predicted.status, predicted.H_max),
    )


for scheme, path in zip(p.schemes, snakemake.output, strict=True):
    ds = limits_study(
        dict(p.settings),
        scheme,
        w.method,
        w.decomposition,
        list(p.k),
        limits=dict(p.limits),
        command=f"snakemake rule {snakemake.rule}",
        log=log,
    )
    write_netcdf(ds, path)

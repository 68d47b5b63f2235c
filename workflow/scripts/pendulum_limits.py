"""Snakemake job: largest stable H of one group, measured (bisection on divergence) and predicted by the
linear test model -> NetCDF (thin: icosim.pendulum.trade.stability_limit)."""

import logging

from icosim.io.netcdf import provenance_attrs, write_netcdf
from icosim.pendulum.trade.stability_limit import limits_dataset, limits_group

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
p = snakemake.params
lim = p.limits


def log(label, measured, predicted):
    logging.info(
        "%-22s measured %s H_max %.4g (%d runs); linear %s H_max %.4g",
        *(label, measured.status, measured.H_max, measured.n_evaluations, predicted.status, predicted.H_max),
    )


groups = limits_group(
    dict(p.settings),
    p.scheme,
    p.method,
    p.decomposition,
    list(p.k),
    scan=list(lim["scan"]),
    t_end=lim["t_end"],
    resolution=lim["resolution"],
    log=log,
)
job = {key: p[key] for key in ("settings", "scheme", "method", "decomposition", "k", "limits")}
attrs = provenance_attrs(job, title="Double pendulum: stability limit in H", command="snakemake rule pendulum_limits")
ds = limits_dataset(
    groups,
    scheme=p.scheme,
    method=p.method,
    decomposition=p.decomposition,
    scan=lim["scan"],
    t_end=lim["t_end"],
    resolution=lim["resolution"],
    attrs=attrs,
)
write_netcdf(ds, snakemake.output[0])

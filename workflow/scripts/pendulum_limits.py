"""Snakemake job: largest stable H of one (method, decomposition), for every scheme, measured (bisection on
divergence) and predicted by the linear test model -> one NetCDF per scheme
(thin: icosim.pendulum.trade.stability_limit)."""

import logging

from icosim.io.netcdf import provenance_attrs, write_netcdf
from icosim.pendulum.trade.stability_limit import limits_dataset, limits_group

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
w, p = snakemake.wildcards, snakemake.params
lim = p.limits


def log(label, measured, predicted):
    logging.info(
        "%-22s measured %s H_max %.4g (%d runs); linear %s H_max %.4g",
        *(label, measured.status, measured.H_max, measured.n_evaluations, predicted.status, predicted.H_max),
    )


for scheme, path in zip(p.schemes, snakemake.output, strict=True):
    groups = limits_group(
        dict(p.settings),
        scheme,
        w.method,
        w.decomposition,
        list(p.k),
        scan=list(lim["scan"]),
        t_end=lim["t_end"],
        resolution=lim["resolution"],
        log=log,
    )
    job = {
        "settings": p.settings,
        "scheme": scheme,
        "method": w.method,
        "decomposition": w.decomposition,
        "k": p.k,
        "limits": p.limits,
    }
    attrs = provenance_attrs(
        job, title="Double pendulum: stability limit in H", command=f"snakemake rule {snakemake.rule}"
    )
    ds = limits_dataset(
        groups,
        scheme=scheme,
        method=w.method,
        decomposition=w.decomposition,
        scan=lim["scan"],
        t_end=lim["t_end"],
        resolution=lim["resolution"],
        attrs=attrs,
    )
    write_netcdf(ds, path)

"""Snakemake job: the co-simulation runs of one (method, decomposition), every scheme and k -> one NetCDF each
(thin: icosim.studies.pendulum.datasets)."""

import json
import logging

from icosim.io.netcdf import write_netcdf
from icosim.job import start_job
from icosim.studies.pendulum.datasets import run_job_data

start_job(snakemake.log[0])
w, p = snakemake.wildcards, snakemake.params
jobs = [(scheme, k) for scheme in p.schemes for k in p.k]  # the order of the rule's outputs
for (scheme, k), path in zip(jobs, snakemake.output, strict=True):
    job = {
        "method": w.method,
        "decomposition": w.decomposition,
        "k": int(k),
        **{key: dict(p[key]) for key in ("method_params", "model")},
        "H": p.H,
        "t_end": p.t_end,
        **{key: dict(p[key]) for key in ("integrator", "sensitivities", "corrector", "divergence")},
        "scheme": scheme,
    }
    logging.info("run: %s", json.dumps(job, sort_keys=True))
    result, ds = run_job_data(job, command=f"snakemake rule {snakemake.rule}")
    write_netcdf(ds, path)
    logging.info(
        "%d macro steps in %.2f s; diverged=%d at t=%s (%s); %s",
        result.stats["macro_steps"],
        result.wall_time,
        result.diverged,
        result.t_diverged,
        result.reason or "-",
        result.stats,
    )

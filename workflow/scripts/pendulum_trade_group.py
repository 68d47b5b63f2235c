"""Snakemake job: the trade studies of one (method, decomposition), for every scheme (every k) -> one NetCDF per
study and scheme: error over H (thin: icosim.studies.trade.sweep) and the largest stable H, measured and
predicted by the linear test model (thin: icosim.studies.trade.stability_limit).  One process for both pays
the start-up (interpreter, imports, the compiled integrator) once; each dataset is the one a job per study writes."""

import logging

from icosim.io.netcdf import write_netcdf
from icosim.job import start_job
from icosim.studies.trade.stability_limit import limits_study_data
from icosim.studies.trade.sweep import sweep_group_data

start_job(snakemake.log[0])
w, p, out = snakemake.wildcards, snakemake.params, snakemake.output
common = dict(settings=dict(p.settings), method=w.method, decomposition=w.decomposition, ks=list(p.k))
command = f"snakemake rule {snakemake.rule}"


def log_sweep(label, H, rec):
    logging.info(
        "sweep  %-22s H=%.1e %-8s err %.2e cpu %.3f s %s",
        *(label, H, rec["status"], rec["error_max"], rec["cpu_seconds"], rec["reason"]),
    )


def log_limits(label, measured, predicted):
    logging.info(
        "limits %-22s measured %s H_max %.4g (%d runs); linear %s H_max %.4g",
        *(label, measured.status, measured.H_max, measured.n_evaluations, predicted.status, predicted.H_max),
    )


sweep = dict(H_values=list(p.H), t_end=p.t_end, reference=dict(p.reference), integrator=dict(p.integrator))
timing = dict(repeats=p.timing["repeats"], repeat_below=p.timing["repeat_below"])
for scheme, path in zip(p.schemes, out.sweep, strict=True):
    write_netcdf(sweep_group_data(scheme=scheme, **common, **sweep, **timing, command=command, log=log_sweep), path)
for scheme, path in zip(p.schemes, out.limits, strict=True):
    write_netcdf(
        limits_study_data(scheme=scheme, **common, limits=dict(p.limits), command=command, log=log_limits), path
    )

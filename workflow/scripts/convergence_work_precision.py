"""Snakemake job: time the co-simulation stepping per configuration and H (error from the panel datasets)."""

import json
import logging

from icosim.io.netcdf import open_dataset, provenance_attrs, write_netcdf
from icosim.job import start_job
from icosim.studies.convergence.experiment import Setup
from icosim.studies.convergence.work_precision import work_precision

start_job(snakemake.log[0])
p = snakemake.params
job = {k: p[k] for k in ("entries", "setup", "steps", "repeats", "warmup_steps")}
logging.info("parameters: %s", json.dumps(job, sort_keys=True))
datasets = {}
for path in snakemake.input.panels:
    ds = open_dataset(path)
    key = (ds.attrs["scheme"], ds.attrs["decomposition"], str(ds.attrs["figure"]), ds.attrs["panel"])
    datasets[key] = ds
wp = work_precision(
    p.entries,
    datasets,
    Setup(**p.setup),
    steps=p.steps,
    repeats=p.repeats,
    warmup_steps=p.warmup_steps,
    provenance=provenance_attrs(
        job, title="Work-precision of the coupling configurations", command="snakemake rule convergence_work_precision"
    ),
)
write_netcdf(wp, snakemake.output[0])
for s in range(wp.sizes["configuration"]):
    logging.info(
        "%s: %.3g ms per macro step (median over H)",
        wp["configuration"].values[s],
        1e3 * float(wp["cpu_seconds_per_step"][s].median(skipna=True)),
    )

"""Snakemake job: one FMU scene run (its dataset) and checked (prediction, measured growth, built-in model)
(thin: icosim.fmi.run, icosim.fmi.validation)."""

import logging
from pathlib import Path

from icosim.fmi.run import run_dataset, run_scene
from icosim.fmi.scene import load_scene
from icosim.fmi.validation import scene_validation
from icosim.io.netcdf import write_netcdf
from icosim.job import start_job

start_job(snakemake.log[0])
name = snakemake.wildcards.scene
cache = Path(snakemake.input.units).parent
scene = load_scene(snakemake.input.scene)
run = run_scene(scene, cache=cache)
logging.info("%s: %s after %d macro steps, %.2f s %s", name, run.status, len(run.times) - 1, run.wall_time, run.reason)
# written through xarray, unlike the other writer jobs: without xarray loaded, a process that ran a
# pythonfmu unit aborted at exit ("corrupted double-linked list") in 4 of 16 runs; the cause was
# pythonfmu's double free at exit, which icosim.fmi.units now prevents (docs/fmi.md)
ds = run_dataset(run, command=f"snakemake rule {snakemake.rule}")
write_netcdf(ds, snakemake.output.run)
checked = scene_validation(scene, ds, name=name, builtin=snakemake.params.builtin, cache=cache)
write_netcdf(checked, snakemake.output.validation)
logging.info(
    "predicted rho %s (%s), measured growth %s, difference to the built-in model (%s) %s",
    float(checked["predicted_rho"]),
    checked.attrs["predicted_verdict"],
    float(checked["measured_growth"]),
    snakemake.params.builtin,
    float(checked["builtin_difference"]),
)

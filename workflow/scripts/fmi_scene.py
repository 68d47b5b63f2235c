"""Snakemake job: one FMU scene run (its dataset) and checked (prediction, measured growth, built-in model),
under the supervisor that names a unit that hangs or crashes (thin: icosim.studies.fmi.validation.scene_job)."""

import logging
from pathlib import Path

from icosim.job import start_job
from icosim.problems.fmu.scene import load_scene
from icosim.studies.fmi.validation import scene_job

start_job(snakemake.log[0])
done = scene_job(
    load_scene(snakemake.input.scene),
    name=snakemake.wildcards.scene,
    builtin=snakemake.params.builtin,
    cache=Path(snakemake.input.units).parent,
    run_path=snakemake.output.run,
    validation_path=snakemake.output.validation,
    command=f"snakemake rule {snakemake.rule}",
)
logging.info(done)

"""Snakemake job: the test units built from source into the cache the scene jobs read (thin: icosim.problems.fmu.build)."""

import json
import logging
from pathlib import Path

from icosim.io.netcdf import atomic_path
from icosim.job import start_job
from icosim.problems.fmu.build import build_unit

start_job(snakemake.log[0])
cache = Path(snakemake.output[0]).parent
built = {}
for source in snakemake.params.sources:
    fmu = build_unit(source, cache)
    built[source] = fmu.name
    logging.info("%s -> %s", source, fmu)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(json.dumps(built, indent=1, sort_keys=True) + "\n")

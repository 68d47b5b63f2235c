"""Snakemake job: compile the pendulum's numba kernels into their disk cache once, before the runs
(which would otherwise each compile on a cold cache) -> a JSON record of what was compiled."""

import json
import logging

from icosim.io.integrity import atomic_path
from icosim.job import start_job
from icosim.problems.pendulum.integrator.compiled_step import compile_kernels

start_job(snakemake.log[0])
record = compile_kernels()
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(json.dumps(record, indent=1, allow_nan=False) + "\n")
logging.info(
    "numba %s: kernels ready in %.2f s (%.2f CPU-s)", record["numba"], record["wall_seconds"], record["cpu_seconds"]
)

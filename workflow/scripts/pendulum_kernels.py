"""Snakemake job: compile the pendulum's numba kernels into their disk cache once, before the runs
(which would otherwise each compile on a cold cache) -> a JSON record of what was compiled."""

import json
import logging

from icosim.io.integrity import atomic_path
from icosim.pendulum.integrator.compiled_step import compile_kernels

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
record = compile_kernels()
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(json.dumps(record, indent=1, allow_nan=False) + "\n")
logging.info(
    "numba %s: kernels ready in %.2f s (%.2f CPU-s)", record["numba"], record["wall_seconds"], record["cpu_seconds"]
)

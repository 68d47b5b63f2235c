"""Test session settings.

One BLAS thread: the engine batches thousands of tiny matrices, where BLAS
threading only adds contention (measured 50x slower on a loaded 2-core machine).
This runs before numpy is first imported by the tests.
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
os.environ.setdefault("MPLBACKEND", "Agg")

# the toolchain markers (fmu, slurm, browser): skipped without their toolchain, enforced in CI
pytest_plugins = ["toolchains"]

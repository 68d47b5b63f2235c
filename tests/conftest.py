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


# -- distribution over the xdist workers -------------------------------------------------------------
# pyproject's addopts run the suite with `--dist loadfile --no-loadscope-reorder`: every test file is one
# work unit (its module fixtures built once), handed out in the order the workers collected them.  This
# hook orders the files longest first, so that the few long ones (Snakemake runs, the CI convergence
# datasets, numba compilation) start at once on different workers and the many short ones fill in at the
# end; xdist's own order (most tests first) started them last, leaving one worker alone with them.
# (--dist loadgroup cannot be used: with pytest 9 its group names do not reach the node ids.)
#: Seconds per file (its tests' times in a run of the whole suite from a fresh checkout, rounded); a file
#: not listed counts 0.05 s a test.  Only the order matters: a wrong number costs some balance, never a test.
FILE_SECONDS = {
    "tests/workflow/test_workflow_faults.py": 34,  # a real run of one figure, then one per fault case
    "tests/problems/pendulum/test_pendulum_compiled.py": 32,  # numba compiles the kernels (cold in a fresh checkout), twice more in copies
    "tests/workflow/test_stability_workflow.py": 17,  # some 25 Snakemake runs, one real
    "tests/problems/fmu/test_pythonfmu.py": 12,  # a scene under valgrind (about 9 s)
    "tests/architecture/test_toolchain_markers.py": 11,  # pytest sessions of their own, two under xdist
    "tests/engine/test_engine.py": 9,
    "tests/engine/test_schemes.py": 9,
    "tests/problems/fmu/test_linear_scenes.py": 8,
    "tests/figures/test_figures.py": 7,
    "tests/studies/convergence/test_convergence_claims.py": 6,  # the CI convergence datasets (module fixture)
    "tests/engine/test_limits.py": 6,
    "tests/studies/pendulum/test_pendulum_claims.py": 5,
    "tests/engine/test_engine_precision.py": 5,
    "tests/studies/convergence/test_convergence.py": 5,
    "tests/report/test_report_browser.py": 5,  # where the workflow's report exists
    "tests/problems/pendulum/test_pendulum.py": 4.5,
    "tests/studies/stability/test_panel_readers.py": 4,
    "tests/io/test_dataset_dict.py": 4,
    "tests/studies/stability/test_stability_sweep.py": 4,
    "tests/studies/convergence/test_convergence_errors.py": 4,
    "tests/workflow/test_fmi_workflow.py": 3.5,
    "tests/engine/test_certified.py": 3.3,
    "tests/workflow/test_schemes_workflow.py": 2.7,
    "tests/architecture/test_structure.py": 2.5,
}


def _file_of(item):
    return item.nodeid.split("::", 1)[0]


def pytest_collection_modifyitems(config, items):
    if not hasattr(config, "workerinput"):  # not an xdist worker: a run without xdist keeps its order
        return
    count, first = {}, {}
    for i, item in enumerate(items):
        count[_file_of(item)] = count.get(_file_of(item), 0) + 1
        first.setdefault(_file_of(item), i)
    seconds = {f: FILE_SECONDS.get(f, 0.05 * n) for f, n in count.items()}
    # longest first; a file's tests stay together and in their order
    items.sort(key=lambda item: (-seconds[_file_of(item)], first[_file_of(item)]))

"""The README's test command, this tree and an older commit side by side in one run.

The older commit runs twice, before and after this tree (the baseline is the mean of its two runs).
Each run is ``python -m pytest`` in a clean copy of its tree (``git worktree`` for the older commit,
the tracked and untracked files of the working tree for this one) with the tree's own ``src`` first
on ``PYTHONPATH``, in the same virtual environment.  Prints wall and CPU seconds (pytest and all its
children, ``getrusage``) and the tests each run passed, then the ratios.  Never a timed assertion:
a measurement to quote.

    python benchmarks/test_suite.py [--old COMMIT] [--json FILE] [-- PYTEST ARGS]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import time
from pathlib import Path

from _workflow import tree


def run_tests(commit: str | None, label: str, pytest_args: list) -> dict:
    with tree(commit, whole=True) as workdir:
        env = {**os.environ, "PYTHONPATH": str(workdir / "src"), "MPLBACKEND": "Agg"}
        cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *pytest_args]
        ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, cwd=workdir, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    last = (proc.stdout.strip().splitlines() or [""])[-1]
    counts = {key: int(n) for n, key in re.findall(r"(\d+) (passed|failed|skipped|errors?)", last)}
    print(f"{label}: {last}", flush=True)
    for line in proc.stdout.splitlines():
        if line.startswith(("FAILED", "ERROR")):
            print("   ", line[:300], flush=True)
    return dict(label=label, wall=wall, cpu=cpu, exit=proc.returncode, counts=counts, load=os.getloadavg()[0])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", default="897a1b5", help="the older commit (default: %(default)s)")
    ap.add_argument("--json", help="write the runs to this file")
    ap.add_argument("pytest_args", nargs="*", help="extra arguments for pytest (after --)")
    args = ap.parse_args(argv)
    first = run_tests(args.old, f"commit {args.old} (1)", args.pytest_args)
    new = run_tests(None, "this tree", args.pytest_args)
    second = run_tests(args.old, f"commit {args.old} (2)", args.pytest_args)
    old = {key: (first[key] + second[key]) / 2 for key in ("wall", "cpu")}
    print(f"{'run':<22}{'wall s':>9}{'CPU s':>9}{'exit':>6}{'load':>7}  tests")
    for run in (first, new, second):
        print(
            f"{run['label']:<22}{run['wall']:>9.1f}{run['cpu']:>9.1f}{run['exit']:>6}{run['load']:>7.2f}  {run['counts']}"
        )
    print(
        f"ratio this tree / {args.old} (mean of its two runs): wall {new['wall'] / old['wall']:.2f}, "
        f"CPU {new['cpu'] / old['cpu']:.2f} (the test suite's target: <= 0.5)"
    )
    if args.json:
        Path(args.json).write_text(json.dumps([first, new, second], indent=1))


if __name__ == "__main__":
    main()

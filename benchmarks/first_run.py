"""What the README's two commands take for a newcomer: a fresh clone, its first run and a rerun.

A clone of the committed tree (``git clone``, nothing of this checkout's caches) in a temporary directory,
then, timed one after the other:

1. ``install``: the README's set-up, ``python3 -m venv .venv && .venv/bin/pip install -q -e ".[workflow,test,fmi]"``
   (pip's own cache and the machine's wheel mirror as they are);
2. ``first run``: ``.venv/bin/snakemake -c2`` (the README's replication) with every cache of the project cold --
   numba's compiled kernels (kept beside the package, none in a clone), the FMU test units (built from source into
   ``build/``), and matplotlib's font cache (``MPLCONFIGDIR`` an empty directory);
3. ``rerun``: the same command once more after ``results/``, ``reports/`` and ``.snakemake/`` are removed: the
   caches are warm, the work is the same;
4. ``tests, first`` and ``tests, rerun``: the README's test command's ``pytest`` (the suite on every core), twice.

Printed: wall and CPU seconds of each (CPU of the children, ``getrusage``), the machine (cores, CPU model, memory,
Python) and the load average before each step.  Machines differ by 2x and more, and a loaded machine is slower:
the numbers are this machine's, quoted with it in docs/benchmarks.md; the README quotes them as such.

    python benchmarks/first_run.py [--commit HEAD] [--skip-tests] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def machine() -> dict:
    model = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = ""
    try:
        kb = int(next(x for x in Path("/proc/meminfo").read_text().splitlines() if x.startswith("MemTotal")).split()[1])
        mem = f"{kb / 2**20:.0f} GiB"
    except (OSError, StopIteration, ValueError):
        pass
    return {"cores": os.cpu_count(), "cpu": model, "memory": mem, "python": platform.python_version()}


def timed(label: str, command: str, cwd: Path, env: dict) -> dict:
    load = os.getloadavg()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(["bash", "-c", command], cwd=cwd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    row = {"step": label, "wall_s": round(wall, 1), "cpu_s": round(cpu, 1), "load_before": [round(x, 2) for x in load],
           "status": done.returncode}  # fmt: skip
    print(f"{label:14s} wall {wall:7.1f} s   cpu {cpu:7.1f} s   load before {load[0]:.2f}   exit {done.returncode}")
    if done.returncode:
        print(done.stdout[-3000:], done.stderr[-3000:], sep="\n")
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--commit", default="HEAD", help="the commit to clone (default HEAD)")
    ap.add_argument("--skip-tests", action="store_true", help="time the workflow only")
    ap.add_argument("--json", type=Path, help="write the rows and the machine here")
    args = ap.parse_args(argv)
    info = machine()
    print("machine:", ", ".join(f"{k} {v}" for k, v in info.items()))
    tmp = Path(tempfile.mkdtemp(prefix="icosim-first-run-"))
    rows = []
    try:
        clone = tmp / "icosim"
        subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
        subprocess.run(["git", "-C", str(clone), "checkout", "-q", args.commit], check=True)
        env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHONPATH", "VIRTUAL_ENV", "MPL"))}
        env["MPLCONFIGDIR"] = str(tmp / "matplotlib")  # an empty font cache, as on a new machine
        rows.append(timed("install", 'python3 -m venv .venv && .venv/bin/pip install -q -e ".[workflow,test,fmi]"',
                          clone, env))  # fmt: skip
        rows.append(timed("first run", ".venv/bin/snakemake -c2", clone, env))
        for name in ("results", "reports", ".snakemake"):
            shutil.rmtree(clone / name, ignore_errors=True)
        rows.append(timed("rerun", ".venv/bin/snakemake -c2", clone, env))
        if not args.skip_tests:
            rows.append(timed("tests, first", ".venv/bin/python -m pytest -q -p no:cacheprovider", clone, env))
            rows.append(timed("tests, rerun", ".venv/bin/python -m pytest -q -p no:cacheprovider", clone, env))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if args.json:
        args.json.write_text(json.dumps({"machine": info, "commit": args.commit, "rows": rows}, indent=1))
    return 0 if all(r["status"] == 0 for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())

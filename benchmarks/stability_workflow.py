"""Benchmark: the whole stability part (Figs. 9-20) with `snakemake -c2` from a clean results/.

Copies the workflow (Snakefile, config, workflow, src) into a temporary directory,
runs the stability targets (every panel, figure, the claims and the report section)
and prints

* wall time and CPU-seconds of the whole run (Snakemake and all its jobs, from
  ``getrusage(RUSAGE_CHILDREN)``; CPU-seconds do not depend on other load on the
  machine, wall time does: the load average is printed too);
* from the datasets' attributes: points, points rechecked at high precision (and how
  many of them lie on the undamped axis lr1 = 0), CPU-seconds of the float64 pass and
  of the multiprecision rechecks;
* the goal (issue 3): under 180 s wall on 2 cores at 101 x 101.

    python benchmarks/stability_workflow.py            # default configuration (101 x 101)
    python benchmarks/stability_workflow.py --ci       # config/ci/stability.yaml (coarse)

The summary is also written as JSON to benchmarks/stability_workflow[_ci].json.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
GOAL_SECONDS = 180.0


def copy_workflow(dest: Path):
    for name in ("Snakefile", "pyproject.toml"):
        if (ROOT / name).exists():
            shutil.copy2(ROOT / name, dest / name)
    for name in ("config", "workflow", "src"):
        shutil.copytree(ROOT / name, dest / name, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ci", action="store_true", help="use config/ci/stability.yaml (coarse grids)")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--keep", type=Path, help="run in this (new) directory and keep it")
    ap.add_argument("extra", nargs="*", help="further snakemake options (after --), e.g. -- --scheduler greedy")
    args = ap.parse_args(argv)

    sys.path.insert(0, str(ROOT / "src"))
    from icosim.datasets import open_dataset

    workdir = args.keep or Path(tempfile.mkdtemp(prefix="icosim-stability-bench-"))
    workdir.mkdir(parents=True, exist_ok=True)
    if any(workdir.iterdir()):
        sys.exit(f"{workdir} is not empty: the benchmark starts from a clean results/")
    copy_workflow(workdir)
    snakemake = str(Path(sys.executable).with_name("snakemake"))
    if not Path(snakemake).exists():
        snakemake = shutil.which("snakemake") or "snakemake"
    cmd = [snakemake, "results/report/stability.html", f"-c{args.cores}", "--quiet", "all", *args.extra]
    if args.ci:
        cmd += ["--configfile", "config/ci/stability.yaml"]

    load_before = os.getloadavg()
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=workdir, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    load_after = os.getloadavg()
    if proc.returncode != 0:
        print(proc.stdout[-3000:], proc.stderr[-3000:], sep="\n")
        sys.exit(f"snakemake failed (exit {proc.returncode}); workdir kept: {workdir}")
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)

    keys = (
        "n_points",
        "n_high_precision",
        "n_high_precision_undamped",
        "cpu_seconds_float64",
        "cpu_seconds_mp",
    )
    totals = dict.fromkeys(keys, 0.0)
    files = sorted(glob.glob(str(workdir / "results/stability/fig*/*.nc")))
    for path in files:
        attrs = open_dataset(path).attrs
        for key in keys:
            totals[key] += float(attrs[key])
    compute = totals["cpu_seconds_float64"] + totals["cpu_seconds_mp"]
    summary = {
        "configuration": "ci" if args.ci else "default",
        "cores": args.cores,
        "panels": len(files),
        "wall_seconds": wall,
        "cpu_seconds": cpu,
        "ideal_wall_seconds_on_idle_cores": cpu / args.cores,
        "load_average_before_after": [load_before[0], load_after[0]],
        "points": int(totals["n_points"]),
        "high_precision_points": int(totals["n_high_precision"]),
        "high_precision_points_on_undamped_axis": int(totals["n_high_precision_undamped"]),
        "cpu_seconds_float64": totals["cpu_seconds_float64"],
        "cpu_seconds_mp": totals["cpu_seconds_mp"],
        "cpu_seconds_outside_sweeps": cpu - compute,
        "goal_wall_seconds": GOAL_SECONDS,
    }
    out = ROOT / "benchmarks" / f"stability_workflow{'_ci' if args.ci else ''}.json"
    out.write_text(json.dumps(summary, indent=1))

    s = summary
    print(f"stability part ({s['configuration']} configuration, -c{args.cores}, {s['panels']} panels)")
    print(
        f"  wall {wall:7.1f} s   (load average {load_before[0]:.1f} -> {load_after[0]:.1f}; goal {GOAL_SECONDS:.0f} s)"
    )
    print(f"  CPU  {cpu:7.1f} s   -> {cpu / args.cores:.1f} s wall on {args.cores} idle cores")
    print(
        f"  points {s['points']}, high precision {s['high_precision_points']} "
        f"({s['high_precision_points'] / max(s['points'], 1):.2%}; {s['high_precision_points_on_undamped_axis']} on lr1 = 0)"
    )
    print(
        f"  sweep compute: float64 {s['cpu_seconds_float64']:.1f} CPU-s, mp rechecks {s['cpu_seconds_mp']:.1f} CPU-s "
        f"({s['cpu_seconds_mp'] / max(compute, 1e-12):.0%} of the sweeps, {s['cpu_seconds_mp'] / cpu:.0%} of the run)"
    )
    print(
        f"  outside the sweeps' compute (Snakemake, Python start-up, I/O, figures, claims): {s['cpu_seconds_outside_sweeps']:.1f} CPU-s"
    )
    print(
        f"  goal met on this run: {'yes' if wall <= GOAL_SECONDS else 'no'}; "
        f"on idle cores: {'yes' if cpu / args.cores <= GOAL_SECONDS else 'no'}"
    )
    print(f"  summary: {out}")
    if not args.keep:
        shutil.rmtree(workdir, ignore_errors=True)


if __name__ == "__main__":
    main()

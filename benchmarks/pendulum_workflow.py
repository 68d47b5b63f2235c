"""Benchmark: the pendulum part of the workflow with `snakemake -c2` from a clean results/, side by side.

Copies the workflow (Snakefile, config, workflow, src) into a temporary directory and runs, one
after the other in that copy,

1. the Figs. 6-8 part alone (the 21 runs, reference, summary, figures, claims), then
2. the rest of the pendulum part: the speed-accuracy studies (beyond the paper) and the pendulum
   section of the report (``results/report/pendulum.html``),

so that the wall time of the whole part (the budget: 6 min on 2 cores for the default
configuration, 1 min for the CI one) and the share of the new studies are measured in one run.
For each step: wall time, CPU-seconds of Snakemake and its jobs (``getrusage(RUSAGE_CHILDREN)``,
independent of other load on the machine, unlike wall time: the load average is printed too),
and the CPU-seconds the jobs report for their own runs (the datasets' ``cpu_seconds``).

    python benchmarks/pendulum_workflow.py            # default configuration
    python benchmarks/pendulum_workflow.py --ci       # config/ci/pendulum.yaml

The summary is also written as JSON to benchmarks/pendulum_workflow[_ci].json.
"""

from __future__ import annotations

import argparse
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
BUDGET = {"default": 360.0, "ci": 60.0}
FIGS_6_8 = [
    "results/pendulum/summary.nc",
    "results/pendulum/claims.json",
    "results/pendulum/figures/pendulum_error.png",
]
WHOLE = ["results/report/pendulum.html"]


def copy_workflow(dest: Path):
    for name in ("Snakefile", "pyproject.toml"):
        if (ROOT / name).exists():
            shutil.copy2(ROOT / name, dest / name)
    for name in ("config", "workflow", "src"):
        shutil.copytree(ROOT / name, dest / name, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))


def run(cmd, cwd):
    load = os.getloadavg()[0]
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        print(proc.stdout[-3000:], proc.stderr[-3000:], sep="\n")
        sys.exit(f"snakemake failed (exit {proc.returncode}); workdir kept: {cwd}")
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    return {
        "wall_seconds": wall,
        "cpu_seconds": cpu,
        "load_average_before": load,
        "load_average_after": os.getloadavg()[0],
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ci", action="store_true", help="use config/ci/pendulum.yaml")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--keep", type=Path, help="run in this (new) directory and keep it")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT / "src"))
    import numpy as np

    from icosim.io.netcdf import open_dataset

    workdir = args.keep or Path(tempfile.mkdtemp(prefix="icosim-pendulum-bench-"))
    workdir.mkdir(parents=True, exist_ok=True)
    if any(workdir.iterdir()):
        sys.exit(f"{workdir} is not empty: the benchmark starts from a clean results/")
    copy_workflow(workdir)
    snakemake = str(Path(sys.executable).with_name("snakemake"))
    if not Path(snakemake).exists():
        snakemake = shutil.which("snakemake") or "snakemake"
    extra = ["--configfile", "config/ci/pendulum.yaml"] if args.ci else []
    steps = {}
    for name, targets in (("figs_6_8", FIGS_6_8), ("trade_and_report_section", WHOLE)):
        steps[name] = run([snakemake, *targets, f"-c{args.cores}", "--quiet", "all", *extra], workdir)
    res = workdir / "results" / "pendulum"
    own = {}
    for name in ("work_precision", "adaptive", "tolerance"):
        ds = open_dataset(res / f"{name}.nc")
        own[name] = float(np.nansum(ds["cpu_seconds"].values)) + (
            float(np.nansum(ds["fixed_cpu_seconds"].values)) if "fixed_cpu_seconds" in ds else 0.0
        )
    configuration = "ci" if args.ci else "default"
    wall = sum(s["wall_seconds"] for s in steps.values())
    cpu = sum(s["cpu_seconds"] for s in steps.values())
    summary = {
        "configuration": configuration,
        "cores": args.cores,
        "steps": steps,
        "pendulum_part_wall_seconds": wall,
        "pendulum_part_cpu_seconds": cpu,
        "ideal_wall_seconds_on_idle_cores": cpu / args.cores,
        "runs_own_cpu_seconds": own,
        "budget_wall_seconds": BUDGET[configuration],
    }
    out = ROOT / "benchmarks" / f"pendulum_workflow{'_ci' if args.ci else ''}.json"
    out.write_text(json.dumps(summary, indent=1))
    print(f"pendulum part ({configuration} configuration, -c{args.cores}), from a clean results/:")
    for name, s in steps.items():
        print(
            f"  {name:26s} wall {s['wall_seconds']:7.1f} s  CPU {s['cpu_seconds']:7.1f} s  "
            f"(load average {s['load_average_before']:.1f} -> {s['load_average_after']:.1f})"
        )
    print(
        f"  {'whole pendulum part':26s} wall {wall:7.1f} s  CPU {cpu:7.1f} s  -> {cpu / args.cores:.1f} s on idle cores"
    )
    print("  the studies' own CPU seconds (sum over runs): " + ", ".join(f"{k} {v:.1f} s" for k, v in own.items()))
    print(
        f"  budget {BUDGET[configuration]:.0f} s wall: {'met' if wall <= BUDGET[configuration] else 'NOT met'} on this run; "
        f"on idle cores: {'met' if cpu / args.cores <= BUDGET[configuration] else 'NOT met'}"
    )
    print(f"  summary: {out}")
    if not args.keep:
        shutil.rmtree(workdir, ignore_errors=True)


if __name__ == "__main__":
    main()

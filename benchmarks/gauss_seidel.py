"""Benchmark: what the Gauss-Seidel additions cost, part by part, side by side in one run.

Two copies of the workflow run from clean ``results/``: one with the default configuration
(Jacobi and both Gauss-Seidel orders), one with ``config/jacobi_only.yaml`` merged over it (the
paper's scheme only, as before the Gauss-Seidel scheme).  For each part (stability, convergence, pendulum)
the Jacobi-only copy builds the part's report section, then the other copy builds the same
section plus the part's Gauss-Seidel outputs (figures, comparison, claims); then both build
everything else (`all`: the report, claims tables, PDFs).  The runs alternate, so load on the machine hits both alike.  Printed per part:
wall time, CPU-seconds of Snakemake and its jobs (``getrusage(RUSAGE_CHILDREN)``, which do not
depend on other load; wall time does: the load average is printed), jobs run, and the
Gauss-Seidel copy's extra CPU against the extra work it was asked for (stability panels,
convergence curves, pendulum macro steps).

    python benchmarks/gauss_seidel.py          # default configuration
    python benchmarks/gauss_seidel.py --ci     # the CI configuration (config/ci/*.yaml)

The summary is also written as JSON to benchmarks/gauss_seidel[_ci].json.
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

import yaml

ROOT = Path(__file__).resolve().parents[1]
CI_FILES = ["config/ci/stability.yaml", "config/ci/convergence.yaml", "config/ci/pendulum.yaml"]


def copy_workflow(dest: Path):
    for name in ("Snakefile", "pyproject.toml"):
        if (ROOT / name).exists():
            shutil.copy2(ROOT / name, dest / name)
    for name in ("config", "workflow", "src"):
        shutil.copytree(ROOT / name, dest / name, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))


def gauss_seidel_targets(part: str) -> list:
    """The part's Gauss-Seidel outputs, read from the default configuration."""
    sys.path.insert(0, str(ROOT / "src"))
    from icosim.engine.schemes import SCHEMES, figure_id

    cfg = {}
    for name in ("stability", "convergence", "pendulum"):
        cfg.update(yaml.safe_load((ROOT / "config" / f"{name}.yaml").read_text()))
    if part == "stability":
        figs = cfg["stability"]["figures"]
        out = [
            f"results/stability/figures/fig{figure_id(f, s)}.png"
            for f, c in figs.items()
            for s in c.get("schemes", ["jacobi"])
            if s != "jacobi"
        ]
        return out + ["results/stability/figures/scheme_comparison.png", "results/stability/claims_gauss_seidel.json"]
    if part == "convergence":
        figs = cfg["convergence"]["figures"]
        out = [
            f"results/convergence/figures/fig{figure_id(f, s)}_{d}.png"
            for f, c in figs.items()
            for s in c.get("schemes", ["jacobi"])
            if s != "jacobi"
            for d in c["decompositions"]
        ]
        return out + ["results/convergence/claims_gauss_seidel.json"]
    p = cfg["pendulum"]
    out = [
        f"results/pendulum/figures/pendulum_k{k}_{SCHEMES[s].suffix}.png"
        for s in p.get("schemes", ["jacobi"])
        if s != "jacobi"
        for k in p["k"]
    ]
    return out + ["results/pendulum/summary_gauss_seidel.nc", "results/pendulum/claims_gauss_seidel.json"]


def run(snakemake, workdir, targets, configfiles, cores):
    cmd = [snakemake, *targets, f"-c{cores}"]
    if configfiles:
        cmd += ["--configfile", *configfiles]
    load = os.getloadavg()[0]
    log = workdir / f"benchmark_{len(list(workdir.glob('benchmark_*.log')))}.log"
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    with open(log, "w") as fh:
        proc = subprocess.run(cmd, cwd=workdir, stdout=fh, stderr=subprocess.STDOUT, text=True)
    wall = time.perf_counter() - t0
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        print(log.read_text()[-3000:])
        sys.exit(f"snakemake failed (exit {proc.returncode}) in {workdir}; log {log}")
    return {
        "wall_seconds": wall,
        "cpu_seconds": (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime),
        "load_average_before": load,
    }


def work_done(workdir: Path) -> dict:
    """What the part computed: stability panels, convergence curves x step sizes, pendulum macro steps."""
    sys.path.insert(0, str(ROOT / "src"))
    from icosim.io.netcdf import open_dataset

    panels = list((workdir / "results/stability").glob("fig*/*.nc"))
    curves = 0
    for path in (workdir / "results/convergence").glob("*/fig*.nc"):
        ds = open_dataset(path)
        curves += ds.sizes["index"] * ds.sizes["k"]
    steps, integrations = 0, 0
    for path in (workdir / "results/pendulum").glob("*_k*.nc"):
        a = open_dataset(path).attrs
        steps += int(a.get("n_macro_steps", 0))
        integrations += int(a.get("n_integrations", 0))
    return {
        "stability_panels": len(panels),
        "convergence_curves": curves,
        "pendulum_macro_steps": steps,
        "pendulum_integrations": integrations,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ci", action="store_true", help="the CI configuration (config/ci/*.yaml)")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--keep", type=Path, help="run in this (new) directory and keep the two copies")
    args = ap.parse_args(argv)

    base = args.keep or Path(tempfile.mkdtemp(prefix="icosim-gs-bench-"))
    base.mkdir(parents=True, exist_ok=True)
    trees = {"jacobi": base / "jacobi_only", "with_gauss_seidel": base / "with_gauss_seidel"}
    for tree in trees.values():
        tree.mkdir()
        copy_workflow(tree)
    configs = {
        "jacobi": (CI_FILES if args.ci else []) + ["config/jacobi_only.yaml"],
        "with_gauss_seidel": CI_FILES if args.ci else [],
    }
    snakemake = str(Path(sys.executable).with_name("snakemake"))
    if not Path(snakemake).exists():
        snakemake = shutil.which("snakemake") or "snakemake"

    parts = {}
    for part in ("stability", "convergence", "pendulum", "report"):
        # last: the report and every other target of `all` (claims tables, PDFs, ...)
        section = "all" if part == "report" else f"results/report/{part}.html"
        extra = [] if part == "report" else gauss_seidel_targets(part)
        parts[part] = {
            "jacobi": run(snakemake, trees["jacobi"], [section], configs["jacobi"], args.cores),
            "with_gauss_seidel": run(
                snakemake, trees["with_gauss_seidel"], [section, *extra], configs["with_gauss_seidel"], args.cores
            ),
        }
    work = {name: work_done(tree) for name, tree in trees.items()}
    summary = {
        "configuration": "ci" if args.ci else "default",
        "cores": args.cores,
        "parts": parts,
        "work": work,
        "total": {
            name: {key: sum(parts[p][name][key] for p in parts) for key in ("wall_seconds", "cpu_seconds")}
            for name in trees
        },
    }
    out = ROOT / "benchmarks" / f"gauss_seidel{'_ci' if args.ci else ''}.json"
    out.write_text(json.dumps(summary, indent=1))

    print(f"Gauss-Seidel additions ({summary['configuration']} configuration, -c{args.cores})")
    print(f"{'part':12s} {'Jacobi only':>22s} {'with Gauss-Seidel':>22s} {'CPU ratio':>10s}")
    for part, r in parts.items():
        j, g = r["jacobi"], r["with_gauss_seidel"]
        print(
            f"{part:12s} {j['wall_seconds']:8.1f} s wall {j['cpu_seconds']:7.1f} CPU"
            f" {g['wall_seconds']:8.1f} s wall {g['cpu_seconds']:7.1f} CPU {g['cpu_seconds'] / max(j['cpu_seconds'], 1e-9):9.2f}x"
            f"   (load {j['load_average_before']:.1f} / {g['load_average_before']:.1f})"
        )
    tj, tg = summary["total"]["jacobi"], summary["total"]["with_gauss_seidel"]
    print(
        f"{'total':12s} {tj['wall_seconds']:8.1f} s wall {tj['cpu_seconds']:7.1f} CPU"
        f" {tg['wall_seconds']:8.1f} s wall {tg['cpu_seconds']:7.1f} CPU {tg['cpu_seconds'] / max(tj['cpu_seconds'], 1e-9):9.2f}x"
    )
    wj, wg = work["jacobi"], work["with_gauss_seidel"]
    print("work asked for (Gauss-Seidel copy / Jacobi-only copy):")
    for key in wj:
        print(f"  {key:24s} {wg[key]:10d} / {wj[key]:<10d} = {wg[key] / max(wj[key], 1):.2f}x")
    print(f"summary: {out}")
    if not args.keep:
        shutil.rmtree(base, ignore_errors=True)


if __name__ == "__main__":
    main()

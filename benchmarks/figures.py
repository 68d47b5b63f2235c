"""The workflow's figure jobs, two trees side by side in one run (what drawing and saving the figures costs).

Each tree (an older commit, and the working tree or ``--new COMMIT``) is a clean copy that first runs the
whole workflow once, untimed, for its datasets (the CI configuration with ``--ci``).  Then only the figure
jobs run again, ``snakemake -c<cores> --force <every file of every rule whose name holds "figure">``
(the jobs' own process start, imports, dataset reads, drawing and saving, and Snakemake's own process),
the trees alternating, the older first and last (old, new, old, ... ``--rounds`` runs of the newer tree),
so that a drift of the machine's load falls on both.  Prints wall and CPU seconds (Snakemake and its
jobs, ``getrusage`` of the children) per run, the mean per tree and the ratios.  Never a timed
assertion: a measurement to quote.

    python benchmarks/figures.py [--old COMMIT] [--new COMMIT] [--ci] [--rounds 2] [--cores 2] [--json FILE]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import subprocess
from pathlib import Path

from _workflow import run_workflow, snakemake_binary, tree


def configs(workdir: Path, ci: bool) -> list[str]:
    """The tree's CI configuration files (config/ci/*.yaml, relative), or none."""
    return sorted(str(p.relative_to(workdir)) for p in (workdir / "config/ci").glob("*.yaml")) if ci else []


def figure_files(workdir: Path, ci: bool) -> list[str]:
    """Every output file of the figure rules (``snakemake --summary``: file, date, rule, ...)."""
    cmd = [snakemake_binary(), "--summary", "all"]
    if ci:
        cmd += ["--configfile", *configs(workdir, ci)]
    out = subprocess.run(
        cmd, cwd=workdir, capture_output=True, text=True, check=True, env={**os.environ, "PYTHONPATH": ""}
    ).stdout
    rows = [line.split("\t") for line in out.splitlines()[1:]]
    return sorted(row[0] for row in rows if len(row) > 2 and "figure" in row[2])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", default="HEAD", help="the older commit (default: %(default)s)")
    ap.add_argument("--new", help="a commit to run as the newer tree instead of the working tree")
    ap.add_argument("--ci", action="store_true", help="the reduced CI configuration (config/ci/*.yaml) for both")
    ap.add_argument("--rounds", type=int, default=2, help="timed runs of the newer tree (the older: one more)")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--json", help="write the runs to this file")
    args = ap.parse_args(argv)
    with contextlib.ExitStack() as stack:
        trees = {"old": stack.enter_context(tree(args.old)), "new": stack.enter_context(tree(args.new))}
        labels = {"old": f"commit {args.old}", "new": f"commit {args.new}" if args.new else "this tree"}
        files = {}
        for key, workdir in trees.items():
            setup = run_workflow(
                workdir, [], label=f"{labels[key]}: datasets", cores=args.cores, configfiles=configs(workdir, args.ci)
            )
            files[key] = figure_files(workdir, args.ci)
            print(f"{labels[key]}: whole workflow {setup.wall:.1f} s, {len(files[key])} figure files", flush=True)
        runs = []
        for key in ["old", "new"] * args.rounds + ["old"]:
            workdir = trees[key]
            run = run_workflow(
                workdir,
                files[key],
                label=labels[key],
                cores=args.cores,
                configfiles=configs(workdir, args.ci),
                keep_results=True,
                args=["--force"],
            )
            runs.append(dict(tree=key, label=labels[key], wall=run.wall, cpu=run.cpu, load=run.load[0]))
            print(
                f"{labels[key]:<24} wall {run.wall:7.1f} s   CPU {run.cpu:7.1f} s   load {run.load[0]:.2f}", flush=True
            )
    mean = {
        key: {
            m: sum(r[m] for r in runs if r["tree"] == key) / sum(r["tree"] == key for r in runs)
            for m in ("wall", "cpu")
        }
        for key in ("old", "new")
    }
    config = "CI" if args.ci else "default"
    print(f"the figure jobs ({config} configuration, -c{args.cores}), mean per tree:")
    for key in ("old", "new"):
        print(f"  {labels[key]:<24} wall {mean[key]['wall']:7.1f} s   CPU {mean[key]['cpu']:7.1f} s")
    print(
        f"ratio {labels['new']} / {labels['old']}: wall {mean['new']['wall'] / mean['old']['wall']:.2f}, "
        f"CPU {mean['new']['cpu'] / mean['old']['cpu']:.2f}"
    )
    if args.json:
        Path(args.json).write_text(json.dumps(dict(runs=runs, mean=mean), indent=1))


if __name__ == "__main__":
    main()

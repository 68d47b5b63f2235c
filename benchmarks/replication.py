"""Benchmark of the full replication, this tree and an older commit side by side in one run (the replication speed target).

The older commit runs twice, before and after this tree (two identical trees timed one after the other
differ by about 10 %); the baseline is the mean of its two runs.  For each run, from a clean copy
(``git worktree`` for the older commit) and a clean ``results/``, the workflow runs part by part, one
``snakemake -c2`` after the other:

* stability: ``results/report/stability.html`` (the panels, figures, claims and section);
* convergence: ``results/report/convergence.html``;
* pendulum: ``results/report/pendulum.html``;
* report: everything else (``all``: the page and what only it needs).

Prints per part the wall and CPU seconds (Snakemake and all its jobs, ``getrusage``), the jobs' total,
and the numerical-kernel CPU seconds the datasets record (``cpu_seconds_*`` of the stability panels,
``seconds_total`` of the convergence curves, ``wall_time_s``/``cpu_seconds`` of the pendulum runs),
so the kernel share of CPU and the overhead (interpreter starts, imports, Snakemake) can be read; then
the ratio of the two trees' totals.  Wall time depends on other load (the load average is printed);
CPU seconds much less.  Never a timed assertion: a measurement to quote.

    python benchmarks/replication.py [--old COMMIT] [--new COMMIT] [--same-work] [--ci] [--cores 2] [--json FILE] [--keep DIR]

``--keep DIR`` keeps each run's ``results/`` and ``reports/`` under ``DIR/<run>/`` (for
``tools/compare_results.py --layout ... --tolerances``).

``--ci`` uses the reduced CI configuration (config/ci/*.yaml) for both trees: a quick check of the
benchmark itself, not the number to quote.

``--same-work`` compares the same work, which is what the replication speed target is about: both trees build exactly
the files the older tree's full replication produces (``snakemake --summary`` of its ``all``: datasets,
figures, claims tables; not its report pages, whose content differs between the trees), part by part,
each tree from a clean ``results/``.  The newer tree's extra studies (Gauss-Seidel, trade studies, ...) are then not in
the comparison.
"""

from __future__ import annotations

import argparse
import glob
import json
import shutil
import subprocess
from pathlib import Path

from _workflow import run_workflow, snakemake_binary, tree

from icosim.io.netcdf import open_dataset

PARTS = (
    ("stability", ["results/report/stability.html"]),
    ("convergence", ["results/report/convergence.html"]),
    ("pendulum", ["results/report/pendulum.html"]),
    ("report", ["all"]),
)
#: Dataset attributes holding numerical-kernel seconds, per part's result folder.
KERNEL_KEYS = {
    "stability": ("cpu_seconds_float64", "cpu_seconds_certify", "cpu_seconds_mp"),
    "convergence": ("seconds_total",),
    "pendulum": ("cpu_seconds", "wall_time_s"),
}
CI_CONFIGS = ["config/ci/stability.yaml", "config/ci/convergence.yaml", "config/ci/pendulum.yaml"]


def kernel_seconds(workdir, part: str) -> float:
    """The kernel seconds the part's datasets record (first key present per dataset; 0 if none)."""
    total = 0.0
    for path in sorted(glob.glob(str(workdir / f"results/{part}/**/*.nc"), recursive=True)):
        with open_dataset(path) as ds:
            present = [k for k in KERNEL_KEYS[part] if k in ds.attrs]
            if part == "stability":
                total += sum(float(ds.attrs[k]) for k in present)
            elif present:
                total += float(ds.attrs[present[0]])
    return total


#: Files of a replication that the same-work comparison builds (not logs, not the report pages).
SAME_WORK_SUFFIXES = (".nc", ".png", ".pdf", ".json", ".tsv")


def replication_files(commit, configs) -> list[tuple[str, list[str]]]:
    """The files the tree's full replication produces (``snakemake --summary``, nothing run), as
    (part, targets) in PARTS order, for the parts that have any."""
    with tree(commit) as workdir:
        cmd = [snakemake_binary(), "--summary", "all"] + (["--configfile", *configs] if configs else [])
        out = subprocess.run(cmd, cwd=workdir, capture_output=True, text=True, check=True).stdout
    paths = [line.split("\t")[0] for line in out.splitlines()[1:] if line.startswith("results/")]
    parts = []
    for part, _ in PARTS:
        files = sorted(
            p
            for p in paths
            if p.startswith(f"results/{part}/") and p.endswith(SAME_WORK_SUFFIXES) and "/logs/" not in p
        )
        if files:
            parts.append((part, files))
    return parts


def run_tree(commit, label, configs, cores, parts_targets=PARTS, keep=None) -> dict:
    """Run the parts, (name, targets), one after the other, the first from a clean results/; with ``keep``
    (a directory) its results/ and reports/ are copied there."""
    parts = {}
    with tree(commit) as workdir:
        first = True
        for part, targets in parts_targets:
            # run_workflow clears results/ before a run: only before the first part
            run = run_workflow(
                workdir, targets, label=f"{label}: {part}", cores=cores, configfiles=configs, keep_results=not first
            )
            first = False
            kernel = kernel_seconds(workdir, part) if part in KERNEL_KEYS else 0.0
            parts[part] = dict(wall=run.wall, cpu=run.cpu, kernel=kernel, load=run.load[0])
        if keep is not None:
            for name in ("results", "reports"):
                if (workdir / name).exists():
                    shutil.copytree(workdir / name, Path(keep) / name, dirs_exist_ok=True)
    total = {key: sum(p[key] for p in parts.values()) for key in ("wall", "cpu", "kernel")}
    return dict(label=label, parts=parts, total=total)


def _mean(a: dict, b: dict, label: str) -> dict:
    """The mean of two runs of the same tree, part by part."""
    parts = {
        part: {key: (a["parts"][part][key] + b["parts"][part][key]) / 2 for key in a["parts"][part]}
        for part in a["parts"]
    }
    total = {key: (a["total"][key] + b["total"][key]) / 2 for key in a["total"]}
    return dict(label=label, parts=parts, total=total)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", default="897a1b5", help="the older commit to compare with (default: %(default)s)")
    ap.add_argument("--ci", action="store_true", help="the reduced CI configuration for both trees")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--same-work", action="store_true", help="both trees build exactly the older tree's files")
    ap.add_argument("--json", help="write the summary to this file")
    ap.add_argument("--keep", type=Path, help="keep each run's results/ and reports/ under this directory")
    ap.add_argument("--new", help="a commit to run as the newer tree instead of the working tree (a fixed snapshot)")
    args = ap.parse_args(argv)
    configs = CI_CONFIGS if args.ci else []
    files = replication_files(args.old, configs) if args.same_work else PARTS
    keep = (lambda name: args.keep / name) if args.keep else (lambda name: None)  # noqa: E731
    old_label = f"commit {args.old}"
    first = run_tree(args.old, f"{old_label} (1)", configs, args.cores, files, keep("old"))
    new = run_tree(args.new, f"commit {args.new}" if args.new else "this tree", configs, args.cores, files, keep("new"))
    second = run_tree(args.old, f"{old_label} (2)", configs, args.cores, files)
    old = _mean(first, second, f"{old_label} mean")
    rows = [first, new, second, old]
    if args.same_work:
        scope = f"the same work ({sum(len(f) for _, f in files)} files {args.old} produces)"
    else:
        scope = "full replication"
    print(f"{scope}, {'CI' if args.ci else 'default'} configuration, -c{args.cores}, part after part")
    print(f"{'tree':<26}{'part':<13}{'wall s':>9}{'CPU s':>9}{'kernel s':>10}{'kernel %':>10}{'load':>7}")
    for row in rows:
        for part, p in list(row["parts"].items()) + [("total", {**row["total"], "load": float("nan")})]:
            share = 100 * p["kernel"] / p["cpu"] if p["cpu"] else 0.0
            print(
                f"{row['label']:<26}{part:<13}{p['wall']:>9.1f}{p['cpu']:>9.1f}{p['kernel']:>10.1f}"
                f"{share:>9.0f}%{p['load']:>7.2f}"
            )
    print(f"ratio this tree / {args.old} (mean of its two runs), per part and in total:")
    for part in list(new["parts"]) + ["total"]:
        n, o = (new["total"], old["total"]) if part == "total" else (new["parts"][part], old["parts"][part])
        print(f"  {part:<13} wall {n['wall'] / o['wall']:.2f}   CPU {n['cpu'] / o['cpu']:.2f}")
    print("(the replication speed target: wall and CPU <= 0.30 on the same machine)")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()

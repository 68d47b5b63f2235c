"""Benchmark of the full replication, this tree and an older commit side by side in one run (the replication speed target).

The older commit runs twice, before and after this tree (two identical trees timed one after the other
differ by about 10 %); the baseline is the mean of its two runs.  Each run starts from a clean copy
(``git worktree`` for the older commit) and a clean ``results/``.

By default each tree runs the README's command exactly: one ``snakemake -c2`` (no target: ``all``),
the whole DAG in one run.  Its wall seconds and CPU seconds (Snakemake and all its jobs, ``getrusage``
of the children) are the speed target's numbers.  The CPU seconds per part are measured inside that
run (benchmarks/_job_cpu.py): every Python process of the run records at exit its own and its children's
CPU and its argv, through a ``sitecustomize.py`` put first on ``PYTHONPATH``; a job counts for a part
by its script's name (``stability_*``, ``convergence_*``, ``pendulum_*``; the claims script, shared by the
parts, by its rule's name), any other job for ``rest`` (the report page, the FMU scenes, the older tree's
Gauss-Seidel section), Snakemake's own CPU for ``snakemake``, and what its children used beyond their
records for ``unrecorded`` (mostly each job's interpreter exit after its record: the record is written
by an exit handler, before the modules' teardown).  The parts' sum is printed against the total (they
agree but for Snakemake's own exit, a fraction of a second; much less means processes escaped the
records).  Parts have no wall time of their own in one run: their jobs run interleaved.

``--by-part`` runs instead the earlier method, part after part, one ``snakemake -c2`` after the other
(each with its own DAG build and its own serial tail, which the one command does not pay), wall and CPU
per part:

* stability: ``results/report/stability.html`` (the panels, figures, claims and section);
* convergence: ``results/report/convergence.html``;
* pendulum: ``results/report/pendulum.html``;
* report: everything else (``all``: the page and what only it needs).

Per part the numerical-kernel CPU seconds the datasets record are printed too (``cpu_seconds_*`` of
the stability panels, ``seconds_total`` of the convergence curves, ``wall_time_s``/``cpu_seconds`` of the
pendulum runs), so the kernel share of CPU and the overhead (interpreter starts, imports, Snakemake) can
be read; then the ratios of the two trees.  Wall time depends on other load (the load average is
printed); CPU seconds much less.  Never a timed assertion: a measurement to quote.

    python benchmarks/replication.py [--old COMMIT] [--new COMMIT] [--by-part] [--same-work] [--ci] [--cores 2] [--json FILE] [--keep DIR]

``--keep DIR`` keeps each run's ``results/`` and ``reports/`` under ``DIR/<run>/`` (for
``tools/compare_results.py --tolerances``).

``--ci`` uses the reduced CI configuration (each tree's config/ci/*.yaml) for both trees: a quick check
of the benchmark itself, not the number to quote.

``--same-work`` compares the same work: both trees build exactly the files the older tree's full
replication produces (``snakemake --summary`` of its ``all``: datasets, figures, claims tables; not its
report pages, whose content differs between the trees), each tree from a clean ``results/``, in one
run (with ``--by-part``: part after part).  The newer tree's extra studies (Gauss-Seidel, trade
studies, ...) are then not in the comparison.

``--json FILE`` writes one entry per run (and the older tree's mean): ``label``, ``method`` (``one run``
or ``by part``), ``parts`` (per part ``cpu``, ``kernel``; one run: ``jobs``; by part: ``wall``, ``load``),
``rules`` (one run: per rule ``cpu`` and ``jobs``, a job's processes counted for its rule) and ``total``
(``wall``, ``cpu``, ``kernel``; one run: ``attributed``, ``processes``, ``load``).
"""

from __future__ import annotations

import argparse
import glob
import json
import shutil
import subprocess
import tempfile
from pathlib import Path

import _job_cpu
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
#: Below this share of the total CPU the attributed CPU is reported as processes escaping the records.
ATTRIBUTED_FLOOR = 0.95


def ci_configs(workdir: Path, ci: bool) -> list[str]:
    """The tree's CI configuration files (config/ci/*.yaml, relative), or none."""
    return sorted(str(p.relative_to(workdir)) for p in (workdir / "config/ci").glob("*.yaml")) if ci else []


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


def replication_files(commit, ci) -> list[tuple[str, list[str]]]:
    """The files the tree's full replication produces (``snakemake --summary``, nothing run), as
    (part, targets) in PARTS order, for the parts that have any."""
    with tree(commit) as workdir:
        configs = ci_configs(workdir, ci)
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


def _keep(workdir: Path, keep):
    """Copy the run's results/ and reports/ to ``keep`` (a directory), if given."""
    if keep is not None:
        for name in ("results", "reports"):
            if (workdir / name).exists():
                shutil.copytree(workdir / name, Path(keep) / name, dirs_exist_ok=True)


def run_tree_by_part(commit, label, ci, cores, parts_targets=PARTS, keep=None) -> dict:
    """Run the parts, (name, targets), one after the other, the first from a clean results/; with ``keep``
    (a directory) its results/ and reports/ are copied there."""
    parts = {}
    with tree(commit) as workdir:
        configs = ci_configs(workdir, ci)
        first = True
        for part, targets in parts_targets:
            # run_workflow clears results/ before a run: only before the first part
            run = run_workflow(
                workdir, targets, label=f"{label}: {part}", cores=cores, configfiles=configs, keep_results=not first
            )
            first = False
            kernel = kernel_seconds(workdir, part) if part in KERNEL_KEYS else 0.0
            parts[part] = dict(wall=run.wall, cpu=run.cpu, kernel=kernel, load=run.load[0])
        _keep(workdir, keep)
    total = {key: sum(p[key] for p in parts.values()) for key in ("wall", "cpu", "kernel")}
    return dict(label=label, method="by part", parts=parts, total=total)


def run_tree(commit, label, ci, cores, targets=(), keep=None) -> dict:
    """One ``snakemake -c<cores> [targets]`` (no target: ``all``) from a clean results/, its total wall and CPU,
    and the CPU per part as the run's processes recorded it; with ``keep`` (a directory) its results/ and
    reports/ are copied there."""
    with tree(commit) as workdir, tempfile.TemporaryDirectory(prefix="icosim-job-cpu-") as tmp:
        hook = _job_cpu.hook_dir(Path(tmp) / "hook")
        records = Path(tmp) / "records"
        records.mkdir()
        env = {"PYTHONPATH": str(hook), _job_cpu.ENV: str(records)}
        run = run_workflow(
            workdir, list(targets), label=label, cores=cores, configfiles=ci_configs(workdir, ci), env=env
        )
        got = _job_cpu.attribute(_job_cpu.load(records))
        parts = {
            part: dict(p, kernel=kernel_seconds(workdir, part) if part in KERNEL_KEYS else 0.0)
            for part, p in got["parts"].items()
        }
        _keep(workdir, keep)
    if got["roots"] != 1:
        print(f"{label}: {got['roots']} processes without a recorded ancestor (expected 1: Snakemake)")
    total = dict(
        wall=run.wall,
        cpu=run.cpu,
        kernel=sum(p["kernel"] for p in parts.values()),
        attributed=sum(p["cpu"] for p in parts.values()),
        processes=got["processes"],
        load=run.load[0],
    )
    return dict(label=label, method="one run", parts=parts, rules=got["rules"], total=total)


def _mean(a: dict, b: dict, label: str) -> dict:
    """The mean of two runs of the same tree, part by part (the numbers both runs have)."""

    def mean(x, y):
        return {k: (x[k] + y[k]) / 2 for k in x if k in y and isinstance(x[k], (int, float))}

    parts = {part: mean(a["parts"][part], b["parts"][part]) for part in a["parts"]}
    mean_run = dict(label=label, method=a["method"], parts=parts, total=mean(a["total"], b["total"]))
    if "rules" in a and "rules" in b:
        empty = dict(cpu=0.0, jobs=0)
        mean_run["rules"] = {
            r: mean(a["rules"].get(r, empty), b["rules"].get(r, empty)) for r in a["rules"] | b["rules"]
        }
    return mean_run


def print_by_part(rows, new, old, old_name):
    """The table of the part-after-part runs and the ratios, per part and in total."""
    print(f"{'tree':<26}{'part':<13}{'wall s':>9}{'CPU s':>9}{'kernel s':>10}{'kernel %':>10}{'load':>7}")
    for row in rows:
        for part, p in list(row["parts"].items()) + [("total", {**row["total"], "load": float("nan")})]:
            share = 100 * p["kernel"] / p["cpu"] if p["cpu"] else 0.0
            print(
                f"{row['label']:<26}{part:<13}{p['wall']:>9.1f}{p['cpu']:>9.1f}{p['kernel']:>10.1f}"
                f"{share:>9.0f}%{p['load']:>7.2f}"
            )
    print(f"ratio this tree / {old_name} (mean of its two runs), per part and in total:")
    for part in list(new["parts"]) + ["total"]:
        n, o = (new["total"], old["total"]) if part == "total" else (new["parts"][part], old["parts"][part])
        print(f"  {part:<13} wall {n['wall'] / o['wall']:.2f}   CPU {n['cpu'] / o['cpu']:.2f}")


def print_one_run(rows, new, old, old_name):
    """The table of the single runs (total wall and CPU, CPU per part), the attributed CPU against the
    total, and the ratios."""
    print(f"{'tree':<26}{'part':<13}{'wall s':>9}{'CPU s':>9}{'jobs':>6}{'kernel s':>10}{'kernel %':>10}{'load':>7}")
    for row in rows:
        for part, p in row["parts"].items():
            share = f"{100 * p['kernel'] / p['cpu']:>9.0f}%" if p["cpu"] and p["kernel"] else f"{'':>10}"
            kernel = f"{p['kernel']:>10.1f}" if part in KERNEL_KEYS else f"{'':>10}"
            jobs = f"{p['jobs']:>6.0f}" if part not in ("snakemake", "unrecorded") else f"{'':>6}"
            print(f"{row['label']:<26}{part:<13}{'':>9}{p['cpu']:>9.1f}{jobs}{kernel}{share}".rstrip())
        t = row["total"]
        jobs = sum(p["jobs"] for p in row["parts"].values())
        share = f"{100 * t['kernel'] / t['cpu']:>9.0f}%" if t["cpu"] else f"{'':>10}"
        print(f"{row['label']:<26}{'attributed':<13}{'':>9}{t['attributed']:>9.1f}{jobs:>6.0f}")
        print(
            f"{row['label']:<26}{'total':<13}{t['wall']:>9.1f}{t['cpu']:>9.1f}{'':>6}{t['kernel']:>10.1f}{share}",
            end="",
        )
        print(f"{t['load']:>7.2f}")
    print(
        "unrecorded: what Snakemake's children used beyond their own records, mostly each job's interpreter"
        " exit after its record (the teardown of its modules, a few tenths of a second with the scientific stack)"
    )
    shares = [row["total"]["attributed"] / row["total"]["cpu"] for row in rows]
    print(
        "attributed / total CPU: "
        + ", ".join(f"{100 * s:.1f} %" for s in shares)
        + " (the rest: Snakemake's own exit after its record"
        + ("" if min(shares) >= ATTRIBUTED_FLOOR else "; below 95 %: processes escaped the records")
        + ")"
    )
    print(f"ratio this tree / {old_name} (mean of its two runs):")
    print(f"  {'total':<13} wall {new['total']['wall'] / old['total']['wall']:.2f}", end="")
    print(f"   CPU {new['total']['cpu'] / old['total']['cpu']:.2f}")
    for part, n in new["parts"].items():
        o = old["parts"][part]["cpu"]
        print(f"  {part:<13} CPU  {n['cpu'] / o:.2f}" if o else f"  {part:<13} CPU  {n['cpu']:.1f} s against none")


def print_rules(new, old, old_name):
    """CPU seconds and jobs per rule in the two trees (the older tree's the mean of its runs), largest first;
    the rules are each tree's own (they were renamed and split between the trees)."""
    print(f"CPU per rule: this tree | {old_name} (mean of its two runs)")
    left = sorted(new.get("rules", {}).items(), key=lambda item: -item[1]["cpu"])
    right = sorted(old.get("rules", {}).items(), key=lambda item: -item[1]["cpu"])
    for i in range(max(len(left), len(right))):
        cells = []
        for side in (left, right):
            if i < len(side):
                name, r = side[i]
                cells.append(f"{name:<44}{r['cpu']:>8.1f}{r['jobs']:>6.0f}")
            else:
                cells.append(" " * 58)
        print(" | ".join(cells).rstrip())


def main(argv=None):
    ap = argparse.ArgumentParser(
        description=__doc__.splitlines()[0]
        + " By default each tree runs one `snakemake -c<cores>` (all), the CPU per part measured inside it."
    )
    ap.add_argument("--old", default="897a1b5", help="the older commit to compare with (default: %(default)s)")
    ap.add_argument("--ci", action="store_true", help="the reduced CI configuration (config/ci/*.yaml) for both trees")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument(
        "--by-part",
        action="store_true",
        help="the earlier method: one snakemake run per part, one after the other, wall and CPU per part",
    )
    ap.add_argument(
        "--same-work",
        action="store_true",
        help="both trees build exactly the older tree's files (in one run; with --by-part part after part)",
    )
    ap.add_argument("--json", help="write the summary to this file")
    ap.add_argument("--keep", type=Path, help="keep each run's results/ and reports/ under this directory")
    ap.add_argument("--new", help="a commit to run as the newer tree instead of the working tree (a fixed snapshot)")
    args = ap.parse_args(argv)
    files = replication_files(args.old, args.ci) if args.same_work else None
    if args.by_part:
        run, work = run_tree_by_part, (files or PARTS)
    else:
        run, work = run_tree, [f for _, targets in files for f in targets] if files else []
    keep = (lambda name: args.keep / name) if args.keep else (lambda name: None)  # noqa: E731
    old_label = f"commit {args.old}"
    first = run(args.old, f"{old_label} (1)", args.ci, args.cores, work, keep("old"))
    new = run(args.new, f"commit {args.new}" if args.new else "this tree", args.ci, args.cores, work, keep("new"))
    second = run(args.old, f"{old_label} (2)", args.ci, args.cores, work)
    old = _mean(first, second, f"{old_label} mean")
    rows = [first, new, second, old]
    if args.same_work:
        scope = f"the same work ({sum(len(f) for _, f in files)} files {args.old} produces)"
    else:
        scope = "full replication"
    config = "CI" if args.ci else "default"
    if args.by_part:
        print(f"{scope}, {config} configuration, -c{args.cores}, part after part")
        print_by_part(rows, new, old, args.old)
    else:
        print(f"{scope}, {config} configuration, one `snakemake -c{args.cores}` per tree from a clean results/")
        print_one_run(rows, new, old, args.old)
        print_rules(new, old, args.old)
    print("(the replication speed target: wall and CPU <= 0.30 on the same machine)")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()

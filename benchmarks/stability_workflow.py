"""Benchmark of the stability part (Figs. 9-20), this tree and an older commit side by side in one run.

``snakemake -c2 results/report/stability.html`` from a clean results/, one run after the other:

* this tree (certified verdicts: float64, then ball arithmetic for the points float64 cannot
  decide, the band around 1 and the audit sample);
* an older commit (default ``06f2834``: float64, then 128-digit mpmath for the points float64
  cannot decide), from a ``git worktree``.

Prints wall and CPU seconds of each run (Snakemake and all its jobs, ``getrusage``; CPU seconds do
not depend on other load, wall time does: the load average is printed too), their ratios (the target
of the certified rechecks: the wall time of the stability part not above the old one), and from the datasets' attributes the
points rechecked and the CPU seconds of the float64 pass and of the rechecks.

    python benchmarks/stability_workflow.py [--old COMMIT] [--ci] [--json FILE]
"""

from __future__ import annotations

import argparse
import glob
import json

from _workflow import run_workflow, tree

from icosim.io.netcdf import open_dataset

TARGET = ["results/report/stability.html"]
KEYS = ("n_points", "n_high_precision", "n_certified", "n_audited", "n_marginal", "n_overturned")
CPU_KEYS = ("cpu_seconds_float64", "cpu_seconds_certify", "cpu_seconds_mp")


def dataset_totals(workdir) -> dict:
    """Sums of the panels' attributes (0 for those an older tree does not write)."""
    totals = dict.fromkeys(KEYS + CPU_KEYS, 0.0)
    files = sorted(glob.glob(str(workdir / "results/stability/fig*/*.nc")))
    for path in files:
        with open_dataset(path) as ds:
            for key in totals:
                totals[key] += float(ds.attrs.get(key, 0))
    totals["panels"] = len(files)
    return totals


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", default="06f2834", help="the older commit to compare with (default: %(default)s)")
    ap.add_argument("--ci", action="store_true", help="config/ci/stability.yaml (coarse grids) for both trees")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--json", help="write the summary to this file")
    args = ap.parse_args(argv)
    configs = ["config/ci/stability.yaml"] if args.ci else []
    rows = []
    for label, commit in (("this tree (certified)", None), (f"commit {args.old} (mpmath rechecks)", args.old)):
        with tree(commit) as workdir:
            run = run_workflow(workdir, TARGET, label=label, cores=args.cores, configfiles=configs)
            rows.append(dict(label=label, wall=run.wall, cpu=run.cpu, load=run.load[0], **dataset_totals(workdir)))
    new, old = rows
    print(f"stability part, {'CI' if args.ci else 'default'} configuration, -c{args.cores}")
    print(
        f"{'':38s} {'wall s':>8s} {'CPU s':>8s} {'load':>5s} {'rechecked':>9s} {'f64 CPU s':>9s} {'recheck CPU s':>13s}"
    )
    for r in rows:
        recheck = r["cpu_seconds_certify"] + r["cpu_seconds_mp"]
        print(
            f"{r['label']:38s} {r['wall']:8.1f} {r['cpu']:8.1f} {r['load']:5.1f} {int(r['n_high_precision']):9d} "
            f"{r['cpu_seconds_float64']:9.1f} {recheck:13.1f}"
        )
    print(
        f"new / old: wall {new['wall'] / old['wall']:.2f}, CPU {new['cpu'] / old['cpu']:.2f} "
        f"(goal: wall not above the old one); this tree certified {int(new['n_certified'])} of "
        f"{int(new['n_points'])} points ({int(new['n_audited'])} audited, {int(new['n_marginal'])} marginal, "
        f"{int(new['n_overturned'])} float64 verdicts overturned)"
    )
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()

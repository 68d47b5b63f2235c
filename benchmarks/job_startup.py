"""What a workflow job costs before its library work: its script's imports, Snakemake's preamble, Snakemake's parse.

For each script of ``workflow/scripts`` (or those named), a fresh interpreter runs only the script's top-level
imports (``python -c "<imports>"``, ``PYTHONPATH`` the tree's ``src``); its CPU seconds (user + system, the best
of ``--repeat`` runs) less a bare interpreter's are the imports' cost, with the heavy packages they load.
Beside them: the bare interpreter, the modules the ``script:`` preamble imports to unpickle its ``snakemake``
object, and ``snakemake -n`` (the Snakefile's parse and the DAG) of the tree.  The jobs per script come from that
dry run's job table (a rule counts for the script its name starts with; every ``*_claims`` rule runs
``claims.py``), so the last line is the imports' CPU over the whole workflow.  With ``--old COMMIT`` the same for
another commit, side by side.

Imports done inside the library's functions at run time are not counted: they are the job's work.

    python benchmarks/job_startup.py [--old COMMIT] [--repeat 5] [SCRIPT ...]
"""

from __future__ import annotations

import argparse
import ast
import json
import os
import resource
import subprocess
import sys
from pathlib import Path

from _workflow import ROOT, snakemake_binary, tree

HEAVY = ("numpy", "scipy", "xarray", "pandas", "netCDF4", "matplotlib", "PIL", "numba", "fmpy", "mpmath", "flint")
#: what the ``script:`` preamble imports (snakemake.script.PythonScript.generate_preamble)
PREAMBLE = "import pickle, snakemake.script, snakemake.logging, snakemake.iocontainers"
#: rules whose script is not the one their name starts with
SCRIPT_OF_RULE = {"report": "report_page"}


def top_level_imports(script: Path) -> str:
    tree_ = ast.parse(script.read_text(encoding="utf-8"))
    return "\n".join(ast.unparse(n) for n in tree_.body if isinstance(n, (ast.Import, ast.ImportFrom)))


def child_cpu(cmd, *, cwd, env, repeat) -> float:
    """Best CPU seconds (user + system) of ``repeat`` runs of ``cmd``."""
    best = float("inf")
    for _ in range(repeat):
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run(cmd, cwd=cwd, env=env, check=True, capture_output=True)
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        best = min(best, r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime)
    return best


def loaded(code: str, *, cwd, env) -> list[str]:
    probe = f"{code}\nimport sys, json\nprint(json.dumps(sorted({{m.split('.')[0] for m in sys.modules}})))"
    out = subprocess.run([sys.executable, "-c", probe], cwd=cwd, env=env, check=True, capture_output=True, text=True)
    mods = set(json.loads(out.stdout.splitlines()[-1]))
    return [m for m in HEAVY if m in mods]


def job_counts(workdir: Path, scripts) -> dict:
    """Jobs per script in a dry run of the whole workflow from an empty ``results/``."""
    out = subprocess.run(
        [snakemake_binary(), "-n", "--quiet", "rules", "--directory", str(workdir), "-s", str(workdir / "Snakefile")],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    counts: dict = {}
    for line in out.splitlines():
        parts = line.split()
        if parts[:1] == ["total"]:  # the job table is printed twice
            break
        if len(parts) != 2 or not parts[1].isdigit() or parts[0] in ("all", "total", "job"):
            continue
        rule, n = parts[0], int(parts[1])
        script = "claims" if rule.endswith("_claims") else SCRIPT_OF_RULE.get(rule)
        if script is None:
            script = max((s for s in scripts if rule == s or rule.startswith(s + "_")), key=len, default=None)
        if script is not None:
            counts[script] = counts.get(script, 0) + n
    return counts


def measure(workdir: Path, names, repeat: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(workdir / "src"), OPENBLAS_NUM_THREADS="1")
    run = dict(cwd=workdir, env=env, repeat=repeat)
    bare = child_cpu([sys.executable, "-c", "pass"], **run)
    scripts = sorted(p.stem for p in (workdir / "workflow/scripts").glob("*.py"))
    rows = {}
    for name in names or scripts:
        code = top_level_imports(workdir / "workflow/scripts" / f"{name}.py")
        cpu = child_cpu([sys.executable, "-c", code], **run) - bare
        rows[name] = {"cpu": cpu, "heavy": loaded(code, cwd=workdir, env=env)}
    preamble = child_cpu([sys.executable, "-c", PREAMBLE], **run) - bare
    dry = child_cpu([snakemake_binary(), "-n", "--quiet", "all"], **dict(run, repeat=1))
    return {"bare": bare, "preamble": preamble, "dry_run": dry, "rows": rows, "jobs": job_counts(workdir, scripts)}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scripts", nargs="*", help="script names (default: every script of workflow/scripts)")
    ap.add_argument("--old", help="another commit, measured the same way")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    results = {"this tree": measure(ROOT, args.scripts, args.repeat)}
    if args.old:
        with tree(args.old) as old:
            results[args.old] = measure(Path(old), args.scripts, args.repeat)
    labels = list(results)
    print("| script | jobs | " + " | ".join(f"{lb}: import CPU-s | heavy packages" for lb in labels) + " |")
    print("|---|---|" + "---|---|" * len(labels))
    first = results[labels[0]]
    for name in first["rows"]:
        cells = [f"{r['rows'][name]['cpu']:.2f} | {' '.join(r['rows'][name]['heavy'])}" for r in results.values()]
        print(f"| {name} | {first['jobs'].get(name, 0)} | " + " | ".join(cells) + " |")
    for lb, r in results.items():
        total = sum(r["jobs"].get(n, 0) * row["cpu"] for n, row in r["rows"].items())
        jobs = sum(r["jobs"].get(n, 0) for n in r["rows"])
        print(
            f"\n{lb}: bare interpreter {r['bare']:.2f} CPU-s, the script preamble's imports {r['preamble']:.2f}, "
            f"`snakemake -n` {r['dry_run']:.2f}; the scripts' imports over {jobs} jobs {total:.1f} CPU-s "
            f"(with interpreter and preamble {total + jobs * (r['bare'] + r['preamble']):.1f})"
        )


if __name__ == "__main__":
    main()

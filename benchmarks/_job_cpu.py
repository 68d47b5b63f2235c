"""CPU seconds per part inside one Snakemake run: every Python process records its own CPU at exit.

:func:`hook_dir` writes a ``sitecustomize.py`` into a directory; with that directory first on
``PYTHONPATH`` (both trees' ``workflow/rules/common.smk`` keep an existing ``PYTHONPATH`` when they put
``src`` on it; the venv has no ``sitecustomize`` of its own) and :data:`ENV` naming an output
directory, every Python process of the run (Snakemake and each job it starts, and what they start)
writes, at exit, one small JSON file of its own: pid, start time, the chain of its ancestors' pids and
start times, argv, the job's rule (``snakemake.rule`` in a ``script:`` job), its own CPU seconds
(``RUSAGE_SELF``) and its waited-for children's (``RUSAGE_CHILDREN``: a compiler under a job, ...).
Without :data:`ENV` the hook does nothing.

:func:`attribute` then gives each process its exclusive CPU (its own and its children's minus what its
recorded descendants recorded themselves: no second count along a chain) and a part:

* a job (``python .snakemake/scripts/tmpXXXX.<script>.py``) by its script's name, ``stability_*``,
  ``convergence_*``, ``pendulum_*``; a script of no part (``claims.py``, shared by every part) by its
  rule's name (``stability_claims``, ...); anything else (the report page, the FMU scenes, the older
  tree's Gauss-Seidel section) is ``rest``;
* Snakemake's own CPU (DAG, scheduling; ``RUSAGE_SELF``) is ``snakemake``;
* what Snakemake's children used beyond their records is ``unrecorded``: each job's interpreter exit
  after its record (its exit handler runs before the teardown of its modules), a non-Python process
  Snakemake starts;
* any other Python process, the part of its nearest recorded ancestor (a Python process started by a
  job, with the exit after its record, counts for the job's part).

The parts' sum is the root Snakemake process's own total; only the root's own exit after its record
is in none.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

#: The environment variable naming the directory the records are written to (unset: no records).
ENV = "ICOSIM_JOB_CPU_DIR"
PARTS = ("stability", "convergence", "pendulum")
SCRIPTS_DIR = ".snakemake/scripts/"

SITECUSTOMIZE = f'''"""Written by benchmarks/_job_cpu.py: records this process's CPU seconds at exit when {ENV} is set."""

import os

if os.environ.get("{ENV}"):

    def _icosim_stat(pid):
        """(parent pid, start time in clock ticks) of a process, from /proc."""
        with open(f"/proc/{{pid}}/stat") as fh:
            fields = fh.read().rpartition(")")[2].split()
        return int(fields[1]), int(fields[19])

    def _icosim_record_cpu():
        import json
        import resource
        import sys

        own = resource.getrusage(resource.RUSAGE_SELF)
        children = resource.getrusage(resource.RUSAGE_CHILDREN)
        try:
            pid = os.getpid()
            parent, start = _icosim_stat(pid)
            ancestors = []
            while parent > 1 and len(ancestors) < 64:
                try:
                    grandparent, parent_start = _icosim_stat(parent)
                except OSError:  # gone meanwhile: the chain stops there
                    break
                ancestors.append([parent, parent_start])
                parent = grandparent
            rule = getattr(getattr(sys.modules.get("__main__"), "snakemake", None), "rule", None)
            record = dict(
                pid=pid,
                start=start,
                ancestors=ancestors,
                argv=list(sys.argv),
                rule=rule if isinstance(rule, str) else None,
                self=own.ru_utime + own.ru_stime,
                children=children.ru_utime + children.ru_stime,
            )
            path = os.path.join(os.environ["{ENV}"], f"{{pid}}-{{start}}")
            with open(path + ".tmp", "w") as fh:
                json.dump(record, fh)
            os.replace(path + ".tmp", path + ".json")
        except Exception:  # never let the measurement fail a job
            pass

    import atexit

    atexit.register(_icosim_record_cpu)  # registered first: runs last
'''


def hook_dir(directory: Path) -> Path:
    """Write the ``sitecustomize.py`` into ``directory`` (to put first on ``PYTHONPATH``); returns it."""
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "sitecustomize.py").write_text(SITECUSTOMIZE)
    return directory


def _is_snakemake(argv) -> bool:
    return bool(argv) and (Path(argv[0]).name == "snakemake" or argv[:2] == ["-m", "snakemake"])


def job_script(argv) -> str | None:
    """The script's name of a ``script:`` job's process (``stability_panels``), else None."""
    if not argv or SCRIPTS_DIR not in argv[0].replace(os.sep, "/"):
        return None
    name = Path(argv[0]).name  # tmpXXXXXXXX.<script>.py
    return name.partition(".")[2].removesuffix(".py") or None


def job_part(script: str, rule: str | None) -> str:
    """The part of a job: by its script's name, else (a script shared by the parts) by its rule's."""
    for name in (script, rule or ""):
        for part in PARTS:
            if name.startswith(part + "_"):
                return part
    return "rest"


def load(directory: Path) -> list[dict]:
    """The records written during a run."""
    return [json.loads(p.read_text()) for p in sorted(Path(directory).glob("*.json"))]


def attribute(records: list[dict]) -> dict:
    """Exclusive CPU seconds and job processes per part (``stability``, ``convergence``, ``pendulum``,
    ``rest``, ``snakemake``, ``unrecorded``) and per rule (a job's rule, else its script's name; the processes
    a job starts count for it), and the root's total: ``{"parts": {part: {"cpu", "jobs"}}, "rules": {rule:
    {"cpu", "jobs"}}, "root_cpu", "processes", "roots"}``."""
    by_key = {(r["pid"], r["start"]): r for r in records}
    parent = {}
    for key, r in by_key.items():
        parent[key] = next((tuple(a) for a in r["ancestors"] if tuple(a) in by_key), None)
    recorded_below = dict.fromkeys(by_key, 0.0)
    for key, up in parent.items():
        if up is not None:
            recorded_below[up] += by_key[key]["self"] + by_key[key]["children"]

    owner_of = {}

    def owner(key):
        """The process a record counts for: its nearest job at or above it, else its root."""
        if key not in owner_of:
            if job_script(by_key[key]["argv"]) is not None or parent[key] is None:
                owner_of[key] = key
            else:
                owner_of[key] = owner(parent[key])
        return owner_of[key]

    def part(key):
        r = by_key[owner(key)]
        script = job_script(r["argv"])
        if script is not None:
            return job_part(script, r["rule"])
        return "snakemake" if _is_snakemake(r["argv"]) else "rest"

    def rule(key):
        r = by_key[owner(key)]
        script = job_script(r["argv"])
        return (r["rule"] or script) if script is not None else None

    parts = {name: dict(cpu=0.0, jobs=0) for name in (*PARTS, "rest", "snakemake", "unrecorded")}
    rules: dict[str, dict] = {}
    for key, r in by_key.items():
        name = part(key)
        is_job = job_script(r["argv"]) is not None
        if name == "snakemake":  # its children's unrecorded CPU is no CPU of Snakemake's own
            parts[name]["cpu"] += r["self"]
            parts["unrecorded"]["cpu"] += r["children"] - recorded_below[key]
        else:
            cpu = r["self"] + r["children"] - recorded_below[key]
            parts[name]["cpu"] += cpu
            if rule(key) is not None:
                entry = rules.setdefault(rule(key), dict(cpu=0.0, jobs=0))
                entry["cpu"] += cpu
                entry["jobs"] += is_job
        parts[name]["jobs"] += is_job
    roots = [key for key, up in parent.items() if up is None]
    root_cpu = sum(by_key[k]["self"] + by_key[k]["children"] for k in roots)
    return dict(parts=parts, rules=rules, root_cpu=root_cpu, processes=len(by_key), roots=len(roots))

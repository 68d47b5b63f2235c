"""Run (part of) the workflow from a clean copy and time it: the current tree or an older commit.

Shared by the benchmark scripts that compare trees side by side in one run (never in tests).
An older commit is checked out with ``git worktree`` into a temporary directory; its jobs import
its own ``src`` (``workflow/rules/common.smk`` puts the checkout's ``src`` on ``PYTHONPATH``).
"""

from __future__ import annotations

import contextlib
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]


@dataclass
class Run:
    label: str
    wall: float
    cpu: float
    load: tuple
    workdir: Path


def _copy_working_tree(dest: Path, whole: bool):
    """The workflow's files of the working tree, or (``whole``) every file git tracks or would track."""
    if not whole:
        for name in ("Snakefile", "pyproject.toml"):
            shutil.copy2(ROOT / name, dest / name)
        for name in ("config", "workflow", "src", "profiles", "fmus"):  # fmus/: the FMU scenes' unit sources
            shutil.copytree(ROOT / name, dest / name, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
        return
    listed = subprocess.run(
        ["git", "-C", str(ROOT), "ls-files", "-co", "--exclude-standard", "-z"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split("\0")
    for rel in filter(None, listed):
        if (ROOT / rel).is_file():
            (dest / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / rel, dest / rel)


@contextlib.contextmanager
def tree(commit: str | None, whole: bool = False):
    """A clean copy of the workflow: the working tree (``commit=None``) or ``git worktree`` of a commit.
    With ``whole``, the working tree's copy holds every file (tests, tools, docs), as a worktree does."""
    tmp = Path(tempfile.mkdtemp(prefix="icosim-bench-"))
    path = tmp / "tree"
    # the configurations name the other tools' units beside the clone (../shared): the copy sees the same
    if (ROOT.parent / "shared").exists():
        (tmp / "shared").symlink_to((ROOT.parent / "shared").resolve())
    try:
        if commit is None:
            path.mkdir()
            _copy_working_tree(path, whole)
            yield path
        else:
            subprocess.run(
                ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(path), commit],
                check=True,
                capture_output=True,
            )
            try:
                yield path
            finally:
                subprocess.run(
                    ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(path)], capture_output=True
                )
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def snakemake_binary() -> str:
    exe = Path(sys.executable).with_name("snakemake")
    return str(exe) if exe.exists() else (shutil.which("snakemake") or "snakemake")


def run_workflow(
    workdir: Path,
    targets,
    *,
    label: str,
    cores: int = 2,
    configfiles=(),
    overrides=None,
    keep_results=False,
    env=None,
    args=(),
) -> Run:
    """``snakemake -c<cores> <targets>`` in ``workdir`` from a clean results/ (unless ``keep_results``: a later
    part of the same run); wall and CPU seconds of the run (Snakemake and every process it waited for).

    ``overrides`` (a nested mapping) is written to a config file given after ``configfiles``.  Snakemake runs
    with an empty ``PYTHONPATH`` (the tree's ``common.smk`` puts its own ``src`` first), or with ``env``'s
    variables (one may be ``PYTHONPATH``) added to the environment.  ``args`` are further options of
    Snakemake (e.g. ``--force``).
    """
    if not keep_results:
        shutil.rmtree(workdir / "results", ignore_errors=True)
    files = [str(f) for f in configfiles]
    if overrides:
        path = workdir / "benchmark_overrides.yaml"
        path.write_text(yaml.safe_dump(overrides))
        files.append(str(path))
    cmd = [snakemake_binary(), *args, *targets, f"-c{cores}", "--quiet", "all"]
    if files:
        cmd += ["--configfile", *files]
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(
        cmd, cwd=workdir, capture_output=True, text=True, env={**os.environ, "PYTHONPATH": "", **(env or {})}
    )
    wall = time.perf_counter() - t0
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        print(proc.stdout[-3000:], proc.stderr[-3000:], sep="\n")
        raise SystemExit(f"{label}: snakemake failed (exit {proc.returncode}) in {workdir}")
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    return Run(label, wall, cpu, os.getloadavg(), workdir)

"""Helpers shared by the test modules (no test module imports another).

* :func:`copy_workflow` and :func:`snakemake`: run the workflow on a copy in a temporary
  directory, never on the checkout's results/;
* :func:`scheduled`: the outputs a dry run schedules for a rule;
* :func:`validate_config`: a part's configuration against its schema, with the method
  definitions filled in from the registry as the workflow does.
"""

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import yaml

from icosim.methods.schema import with_methods

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
if not Path(SNAKEMAKE).exists():
    SNAKEMAKE = shutil.which("snakemake") or "snakemake"


def copy_workflow(dest: Path) -> Path:
    """A copy of the workflow (Snakefile, config, workflow, src) in ``dest``."""
    for name in ("Snakefile", "pyproject.toml"):
        if (ROOT / name).exists():
            shutil.copy2(ROOT / name, dest / name)
    for name in ("config", "workflow", "src"):
        shutil.copytree(ROOT / name, dest / name, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    return dest


def snakemake(workdir: Path, *args, check=True):
    """Run Snakemake on the workflow in ``workdir``; with ``check``, a failure raises with its output."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    proc = subprocess.run(
        [SNAKEMAKE, "--directory", str(workdir), "--snakefile", str(workdir / "Snakefile"), *args],
        capture_output=True,
        text=True,
        cwd=workdir,
        env=env,
        timeout=600,
    )
    if check and proc.returncode != 0:
        raise AssertionError(f"snakemake {' '.join(args)} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
    return proc


def scheduled(proc, rule):
    """Outputs of the jobs of `rule` in a dry-run listing."""
    text = proc.stdout + proc.stderr
    blocks = re.split(r"\n(?=\S*rule \w+:)", text)
    outs = []
    for block in blocks:
        m = re.search(r"rule (\w+):", block)
        if m and m.group(1) == rule:
            out = re.search(r"output: ([^\n]+)", block)
            outs += [o.strip() for o in out.group(1).split(",")] if out else []
    return outs


def validate_config(part_config: dict, part: str):
    """Validate like ``validate_part`` of workflow/rules/common.smk (raises on a bad configuration)."""
    from snakemake.utils import validate

    schema = yaml.safe_load((ROOT / "workflow" / "schemas" / f"{part}.schema.yaml").read_text())
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"{part}.schema.json"
        path.write_text(json.dumps(with_methods(schema)))
        validate(part_config, str(path))

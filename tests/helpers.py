"""Helpers shared by the test modules (no test module imports another).

* :func:`copy_workflow` and :func:`snakemake`: run the workflow on a copy in a temporary
  directory, never on the checkout's results/;
* :func:`scheduled`: the outputs a dry run schedules for a rule;
* :func:`scheduled_jobs`: the same for every rule whose name starts with a prefix (the rules made
  per figure, e.g. ``stability_panels_fig9``);
* :func:`validate_config`: a part's configuration against its schema, with the method
  definitions filled in from the registry as the workflow does;
* :func:`predict_all` and :func:`correct_all`: every subsystem of a problem predicted or
  corrected (the problems advance one subsystem at a time; the scheme lives in the macro step);
* :func:`growth_rate`: the growth factor per macro step of plain time stepping (an
  independent route to the spectral radius).
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

from icosim.engine.schema import with_registries

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
if not Path(SNAKEMAKE).exists():
    SNAKEMAKE = shutil.which("snakemake") or "snakemake"


def copy_workflow(dest: Path) -> Path:
    """A copy of the workflow (Snakefile, config, workflow, src, profiles) in ``dest``."""
    for name in ("Snakefile", "pyproject.toml"):
        if (ROOT / name).exists():
            shutil.copy2(ROOT / name, dest / name)
    for name in ("config", "workflow", "src", "profiles"):
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
    blocks = re.split(r"\n(?=\S*rule [\w-]+:)", text)
    outs = []
    for block in blocks:
        m = re.search(r"rule ([\w-]+):", block)
        if m and m.group(1) == rule:
            out = re.search(r"output: ([^\n]+)", block)
            outs += [o.strip() for o in out.group(1).split(",")] if out else []
    return outs


def scheduled_jobs(proc, prefix: str) -> dict:
    """``{rule: outputs}`` of the jobs in a dry-run listing whose rule name starts with ``prefix``.

    Rule names may hold a hyphen (the per-figure rules of a figure such as ``df-baumgarte``).
    """
    text = proc.stdout + proc.stderr
    jobs = {}
    for block in re.split(r"\n(?=\S*rule [\w-]+:)", text):
        m = re.search(r"rule ([\w-]+):", block)
        if m and m.group(1).startswith(prefix):
            out = re.search(r"output: ([^\n]+)", block)
            outs = jobs.setdefault(m.group(1), [])
            if out:
                outs += [o.strip() for o in out.group(1).split(",")]
    return jobs


def validate_config(part_config: dict, part: str):
    """Validate like ``validate_part`` of workflow/rules/common.smk (raises on a bad configuration)."""
    from snakemake.utils import validate

    schema = yaml.safe_load((ROOT / "workflow" / "schemas" / f"{part}.schema.yaml").read_text())
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"{part}.schema.json"
        path.write_text(json.dumps(with_registries(schema)))
        validate(part_config, str(path))


def predict_all(prob, state, history):
    """Outputs ``y`` of every subsystem after the predictor (extrapolation polynomials)."""
    return prob.stack([prob.predict(i, state, history)[1] for i in range(2)])


def correct_all(prob, state, history, e_new):
    """``(state, y)`` of every subsystem after the corrector with the interpolation polynomials through ``e_new``."""
    ends, ys = zip(*(prob.correct(i, state, history, e_new) for i in range(2)))
    return prob.join(list(ends)), prob.stack(list(ys))


def growth_rate(prob, method, n_chunks=30, chunk=20, seed=0, **step_kw):
    """Average growth factor per macro step of plain time stepping.

    Power iteration: run ``chunk`` steps, record the growth of the norm of
    (state, coupling history), rescale, repeat; the second half is averaged,
    which also averages out the oscillation of a complex dominant pair.
    ``step_kw`` go to the macro step (e.g. ``scheme``).
    """
    import numpy as np

    from icosim.engine.macrostep import simulate

    rng = np.random.default_rng(seed)
    state = rng.standard_normal((2, 2))
    hist = rng.standard_normal((prob.k + 1, prob.n_coupling))
    logs = []
    for _ in range(n_chunks):
        norm0 = np.linalg.norm(prob.pack(state, hist))
        traj = simulate(prob, method, state / norm0, hist / norm0, chunk, **step_kw)
        assert traj.diverged_at is None
        state = traj.states[-1]
        hist = np.stack([traj.coupling[-1 - j] for j in range(prob.k + 1)])
        logs.append(np.log(np.linalg.norm(prob.pack(state, hist))))
    return float(np.exp(np.mean(logs[n_chunks // 2 :]) / chunk))

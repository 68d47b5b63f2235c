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
* :func:`engine_schemes`: a scheme of every method at each decomposition it allows;
* :func:`growth_rate`: the growth factor per macro step of plain time stepping (an
  independent route to the spectral radius);
* :func:`fmu_instance`: a test unit of ``fmus/`` built and instantiated through fmpy's low-level
  API, its log messages collected.
"""

import atexit
import copy
import functools
import json
import os
import re
import shutil
import subprocess
import tempfile
import typing
from pathlib import Path

import yaml
from snakemake_fork import SNAKEMAKE, SnakemakeForkServer

from icosim.engine.schema import with_registries

ROOT = Path(__file__).resolve().parents[1]


def copy_workflow(dest: Path) -> Path:
    """A copy of the workflow (Snakefile, config, workflow, src, profiles) in ``dest``."""
    for name in ("Snakefile", "pyproject.toml"):
        if (ROOT / name).exists():
            shutil.copy2(ROOT / name, dest / name)
    for name in ("config", "workflow", "src", "profiles"):
        shutil.copytree(ROOT / name, dest / name, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    return dest


def snakemake(workdir: Path, *args, check=True):
    """Run Snakemake on the workflow in ``workdir``; with ``check``, a failure raises with its output.

    Each call is a new Snakemake process, forked from one that has imported Snakemake already
    (:mod:`snakemake_fork`); ``ICOSIM_TEST_SNAKEMAKE_FORK=0`` runs the ``snakemake`` command instead.
    """
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    argv = [SNAKEMAKE, "--directory", str(workdir), "--snakefile", str(workdir / "Snakefile"), *args]
    if os.environ.get("ICOSIM_TEST_SNAKEMAKE_FORK", "1") != "0":
        proc = SnakemakeForkServer.get().run(argv, cwd=workdir, env=env, timeout=600)
    else:
        proc = subprocess.run(argv, capture_output=True, text=True, cwd=workdir, env=env, timeout=600)
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
    """Validate like ``validate_part`` of workflow/rules/common.smk (raises on a bad configuration).

    The schema's ``$defs`` are filled from the registries as they are at each call (a test may register
    or remove entries); the JSON file for a given content is written once per test process.
    """
    from snakemake.utils import validate

    text = json.dumps(with_registries(_schema(part)))
    validate(part_config, str(_schema_file(part, text)))


def _schema(part: str) -> dict:
    """The parsed schema file (parsed once; a fresh copy each call)."""
    return copy.deepcopy(_parsed_schema(part))


@functools.cache
def _parsed_schema(part: str) -> dict:
    return yaml.safe_load((ROOT / "workflow" / "schemas" / f"{part}.schema.yaml").read_text())


@functools.cache
def _schema_file(part: str, text: str) -> Path:
    tmp = Path(tempfile.mkdtemp(prefix="icosim-schema-"))
    atexit.register(shutil.rmtree, tmp, ignore_errors=True)
    path = tmp / f"{part}.schema.json"
    path.write_text(text)
    return path


def predict_all(prob, state, history):
    """Outputs ``y`` of every subsystem after the predictor (extrapolation polynomials)."""
    return prob.stack([prob.predict(i, state, history)[1] for i in range(prob.graph.n_subsystems)])


def correct_all(prob, state, history, e_new):
    """``(state, y)`` of every subsystem after the corrector with the interpolation polynomials through ``e_new``."""
    ends, ys = zip(*(prob.correct(i, state, history, e_new) for i in range(prob.graph.n_subsystems)))
    return prob.join(list(ends)), prob.stack(list(ys))


def pair_jacobians(prob, state, history, e, y, fixed=(None, None), algebraic=True):
    """``d residuals / d e`` of a two-subsystem problem's joint, the subsystems responding as ``fixed`` says
    (``None``: through the corrector; an end state: finished, algebraically, or with ``algebraic=False`` not
    at all): the one stage that closes the joint (:mod:`icosim.engine.stages`), built directly, so that a
    pattern a scheme refuses can be looked at too."""
    from icosim.engine.residuals import Conditions
    from icosim.engine.stages import Stage

    corrected = tuple(i for i in range(2) if fixed[i] is None)
    finished = tuple(i for i in range(2) if fixed[i] is not None)
    held = () if algebraic else finished  # a finished subsystem that does not respond saw the prediction
    stage = Stage(1, corrected, (0,), corrected, finished, Conditions(prob.graph, (0,), (0, 1), held))
    ys = [None, None] if y is None else [y[..., i : i + 1, :, :] for i in range(2)]
    return prob.jacobians(state, history, e, ys, list(fixed), stage, algebraic)


def engine_schemes():
    """A coupling scheme of every method at each decomposition it allows: ``(method, decomposition)`` pairs."""
    from icosim import baumgarte, projection, weighted_multiplier

    return [
        (baumgarte(mu=1, index=1), "ff"),
        (baumgarte(mu=1, index=2), "fd"),
        (weighted_multiplier(1, 1), "ff"),
        (weighted_multiplier(0.5, 0.25), "fd"),
        (projection(), "ff"),
        (projection(), "fd"),
        (projection(), "dd"),
    ]


def growth_rate(prob, method, n_chunks=30, chunk=20, seed=0, **step_kw):
    """Average growth factor per macro step of plain time stepping.

    Power iteration: run ``chunk`` steps, record the growth of the norm of
    (state, coupling history), rescale, repeat; the second half is averaged,
    which also averages out the oscillation of a complex dominant pair.
    ``step_kw`` go to the macro step (e.g. ``scheme``).  A problem with leading
    batch axes (array coefficients) runs every point at once, each from the same
    start and with its own norm: an array of growth factors, one per point.
    """
    import numpy as np

    from icosim.engine.run import simulate

    rng = np.random.default_rng(seed)
    state = rng.standard_normal((2, 2))
    hist = rng.standard_normal((prob.k + 1, prob.n_coupling))
    logs = []
    for _ in range(n_chunks):
        norm0 = np.linalg.norm(prob.pack(state, hist), axis=-1)[..., None, None]
        traj = simulate(prob, method, state / norm0, hist / norm0, chunk, **step_kw)
        assert traj.diverged_at is None
        state = traj.states[-1]
        hist = np.stack([traj.coupling[-1 - j] for j in range(prob.k + 1)], axis=-2)
        logs.append(np.log(np.linalg.norm(prob.pack(state, hist), axis=-1)))
    rate = np.exp(np.mean(logs[n_chunks // 2 :], axis=0) / chunk)
    return float(rate) if np.ndim(rate) == 0 else rate


#: Where the tests build the units of ``fmus/`` (once per content; ``build/`` is not tracked).
FMU_CACHE = ROOT / "build" / "fmus"


class LogMessage(typing.NamedTuple):
    """A message a unit sent through its logger: the instance name (FMI 2.0; ``None`` for FMI 3.0), the status
    (0 OK .. 4 fatal) and the text."""

    instance: str | None
    status: int
    text: str


def fmu_instance(unit, unzipdir, messages=None, name="unit"):
    """The test unit ``fmus/<unit>`` built into :data:`FMU_CACHE`, unpacked into ``unzipdir`` and instantiated
    through fmpy's low-level API (``FMU2Slave`` or ``FMU3Slave``, co-simulation), not yet initialised.  What it
    logs is appended to the list ``messages`` as :class:`LogMessage`.  The caller frees the instance."""
    from fmpy import extract, read_model_description

    from icosim.problems.fmu.build import build_unit

    fmu = build_unit(ROOT / "fmus" / unit, FMU_CACHE)
    md = read_model_description(str(fmu))
    messages = [] if messages is None else messages
    common = dict(
        guid=md.guid,
        unzipDirectory=extract(str(fmu), unzipdir=str(unzipdir)),
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName=name,
    )
    if md.fmiVersion.startswith("3."):
        from fmpy.fmi3 import FMU3Slave

        def log3(env, status, category, message):
            messages.append(LogMessage(None, status, message.decode()))

        slave = FMU3Slave(**common)
        slave.instantiate(logMessage=log3)
        return slave
    from fmpy.fmi2 import FMU2Slave, defaultCallbacks, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

    def log2(env, instance, status, category, message):
        messages.append(LogMessage(instance.decode(), status, message.decode()))

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(log2)
    callbacks.allocateMemory, callbacks.freeMemory = defaultCallbacks.allocateMemory, defaultCallbacks.freeMemory
    slave = FMU2Slave(**common)
    slave.instantiate(callbacks=callbacks)
    slave.test_callbacks = callbacks  # alive as long as the instance
    return slave


def scheme_panel_spec(figure, scheme, row, k, n=5):
    """A small stability panel of one coupling scheme (Baumgarte ff, float64 only; row 2 with am21 = 10),
    as the scheme comparison reads them."""
    from icosim.studies.stability.panels import PanelSpec

    return PanelSpec.from_params(
        dict(
            figure=figure,
            row=row,
            k=k,
            view="full",
            method="baumgarte",
            method_params={"index": 1, "mu": 1.0},
            decomposition="ff",
            am21=10.0 if row == 2 else 1.0,
            alr21=1.0,
            ali21=1.0,
            lr1=[-2.0, 0.0],
            li1=[0.0, 2.0],
            n=n,
            policy="float64",
            scheme=scheme,
        )
    )

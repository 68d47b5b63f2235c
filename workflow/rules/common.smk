# Shared helpers for all parts of the workflow.  The library lives in src/icosim and
# knows nothing of Snakemake; rules are thin and call it from workflow/scripts/.
import json
import os
import sys
import tempfile
from pathlib import Path

from snakemake.exceptions import WorkflowError
from snakemake.logging import logger
from snakemake.utils import validate

validate(config, "../schemas/config.schema.yaml")

# Jobs import icosim from this checkout (also when it is not installed editable, and in
# the conda environment of workflow/envs/icosim.yaml); the variable is set here, not
# required from the user.  One BLAS thread per job: jobs already fill the cores.
os.environ.update(
    PYTHONPATH=os.pathsep.join(
        [str(Path(workflow.basedir) / "src")]
        + [p for p in [os.environ.get("PYTHONPATH")] if p]
    )
)
for _var in (
    "MPLBACKEND",
    "OPENBLAS_NUM_THREADS",
    "OMP_NUM_THREADS",
    "MKL_NUM_THREADS",
):
    os.environ.setdefault(_var, "Agg" if _var == "MPLBACKEND" else "1")


# The library, read at parse time: configurations are checked before any job runs.
sys.path.insert(0, str(Path(workflow.basedir) / "src"))
from icosim.engine.methods import METHODS  # noqa: E402
from icosim.engine.schema import with_registries  # noqa: E402
from icosim.engine.decompositions import DECOMPOSITIONS  # noqa: E402
from icosim.engine.schemes import SCHEMES  # noqa: E402
from icosim.labels import figure_label  # noqa: E402
from icosim.sources import library_digest, module_closure, script_closure  # noqa: E402
from icosim.io.integrity import quarantine_corrupt, remove_stale_parts  # noqa: E402
from icosim.io.yamlio import load_yaml  # noqa: E402

# A dataset whose SHA-256 no longer matches the one recorded when it was written is set aside
# (x.nc -> x.nc.corrupt) before the DAG is built, so this run computes it again instead of trusting it.
if workflow.is_main_process:
    for _moved in quarantine_corrupt("results"):
        logger.warning(
            f"icosim: {_moved} did not match its SHA-256: set aside, it will be recomputed"
        )


onstart:
    # temporaries of a killed run (under the lock this run now holds: no other run is writing them)
    for _part in remove_stale_parts("results"):
        logger.info(f"icosim: removed {_part}, left by an interrupted run")


def validate_part(part_config, schema):
    """Validate against a schema whose registry $defs (methods, decompositions, schemes) are filled in
    (icosim.engine.schema)."""
    path = Path(workflow.basedir) / "workflow" / "schemas" / schema
    with open(path) as fh:
        filled = with_registries(load_yaml(fh))
    with tempfile.TemporaryDirectory() as tmp:
        materialised = Path(tmp) / path.name
        materialised.write_text(json.dumps(filled))
        validate(part_config, str(materialised))


def _relative(paths):
    return [str(p.relative_to(workflow.basedir)) for p in paths]


def lib(*modules):
    """Library source files the named modules rest on (their transitive icosim imports).
    Names are relative to the package ('stability.panels')."""
    return _relative(
        module_closure([f"icosim.{m}" for m in modules], Path(workflow.basedir) / "src")
    )


def script_lib(script):
    """Library source files a workflow script rests on, read from its imports."""
    return _relative(
        script_closure(
            Path(workflow.basedir) / "workflow" / "scripts" / f"{script}.py",
            Path(workflow.basedir) / "src",
        )
    )


def script_library(script):
    """The `library` parameter of a rule: the digest of the library files its script rests on.

    Snakemake does not see the modules a script imports; with their digest as a parameter, editing
    one reruns exactly what imports it (icosim.sources.library_digest says why not as inputs)."""
    return library_digest(script_lib(script), workflow.basedir)


# The engine every numerical result rests on: the macro step, its problems and methods,
# and the stability analysis.
ENGINE = lib("engine.macrostep", "engine.spectral", "problems.linear.problem", "engine.methods")


def engine_library(script):
    """script_library of a job that computes numerical results: it must rest on the whole ENGINE."""
    files = script_lib(script)
    missing = sorted(set(ENGINE) - set(files))
    if missing:
        raise WorkflowError(
            f"{script}.py does not import the engine ({', '.join(missing)})"
        )
    return library_digest(files, workflow.basedir)


# Wildcard constraints from the engine's registries: a method, decomposition or scheme added to its
# registry is a valid value of its wildcard.
METHOD_NAMES = "|".join(METHODS)
DECOMPOSITION_NAMES = "|".join(DECOMPOSITIONS)
SCHEME_NAMES = "|".join(SCHEMES)


def figure_title(figure, scheme, title, detail=""):
    """"Fig. 9<detail>: <title>" with the paper's scheme, "Fig. 9<detail>, Gauss–Seidel 1→2: <title>" with another."""
    label = "" if scheme == "jacobi" else f", {SCHEMES[scheme].label}"
    return f"{figure_label(figure)}{detail}{label}: {title}"


# Filled by each part's .smk file: every final target, and each part's report section
# (an HTML fragment) keyed by part name.
ALL_TARGETS = []
REPORT_SECTIONS = {}

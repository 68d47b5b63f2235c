# Shared helpers for all parts of the workflow.  The library lives in src/icosim and
# knows nothing of Snakemake; rules are thin and call it from workflow/scripts/.
import os
from pathlib import Path

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


def lib(*modules):
    """Library source files a rule depends on.

    Snakemake does not see modules that a script imports, so rules list the
    modules they use as input: editing one reruns exactly what depends on it.
    A name may be a module ('stability') or a subpackage ('figures').
    """
    out = []
    for name in modules:
        path = Path(workflow.basedir) / "src" / "icosim" / name
        if path.is_dir():
            out += sorted(
                str(p.relative_to(workflow.basedir)) for p in path.rglob("*.py")
            )
        else:
            out.append(f"src/icosim/{name}.py")
    return out


# The engine every numerical result rests on.
ENGINE = lib(
    "__init__",
    "model",
    "lagrange",
    "backend",
    "subsystems",
    "coupling",
    "macrostep",
    "oscillator",
    "stability",
    "exact",
    "datasets",
)

# Filled by each part's .smk file: every final target, and each part's report section
# (an HTML fragment) keyed by part name.
ALL_TARGETS = []
REPORT_SECTIONS = {}

"""icosim: implicit co-simulation methods with algebraic constraints.

A replication of Schweizer et al., *Implicit co-simulation methods: stability
and convergence analysis for solver coupling approaches with algebraic
constraints*: the linear two-mass test model, three coupling methods
(Baumgarte, weighted multiplier, projection), three decompositions
(force/force, force/displacement, displacement/displacement), Lagrange
approximation of any order k, the Jacobi (parallel) and Gauss-Seidel
(sequential) coupling schemes, and the spectral radius of the recurrence in
float64 and at arbitrary precision.

The map of the package is in docs/layout.md; the engine is
:mod:`icosim.engine.macrostep` driving a :class:`icosim.engine.problem.CosimulationProblem`
with a coupling method of the registry :mod:`icosim.engine.methods`.
"""

from typing import TYPE_CHECKING

# The public names are loaded on first use (PEP 562): a Snakemake job importing, say,
# icosim.studies.trade.sweep starts without the linear model, scipy.linalg and mpmath.
# The imports below are never executed; they are what type checkers and icosim.sources
# read (every job that imports icosim still lists the whole engine as its input).
if TYPE_CHECKING:
    from .engine.methods import make_method
    from .engine.methods.baumgarte import baumgarte
    from .engine.methods.projection import projection
    from .engine.methods.weighted import weighted_multiplier
    from .engine.schemes import JACOBI, GaussSeidel, Jacobi, get_scheme
    from .errors import ParameterError
    from .problems.linear.model import Coefficients, PhysicalModel, TestModel
    from .problems.linear.problem import LinearCosimulation
    from .problems.linear.spectral import (
        amplification_matrix,
        spectral_radius,
        spectral_radius_float64,
        spectral_radius_mp,
    )

_LAZY = {
    "LinearCosimulation": ".problems.linear.problem",
    "make_method": ".engine.methods",
    "baumgarte": ".engine.methods.baumgarte",
    "projection": ".engine.methods.projection",
    "weighted_multiplier": ".engine.methods.weighted",
    "Coefficients": ".problems.linear.model",
    "ParameterError": ".errors",
    "PhysicalModel": ".problems.linear.model",
    "TestModel": ".problems.linear.model",
    "JACOBI": ".engine.schemes",
    "GaussSeidel": ".engine.schemes",
    "Jacobi": ".engine.schemes",
    "get_scheme": ".engine.schemes",
    "amplification_matrix": ".problems.linear.spectral",
    "spectral_radius": ".problems.linear.spectral",
    "spectral_radius_float64": ".problems.linear.spectral",
    "spectral_radius_mp": ".problems.linear.spectral",
}


def __getattr__(name):
    if name == "__version__":
        from .version import package_version

        globals()["__version__"] = value = package_version()
        return value
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(_LAZY[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'icosim' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY) | {"__version__"})


__all__ = [
    "Coefficients",
    "GaussSeidel",
    "JACOBI",
    "Jacobi",
    "LinearCosimulation",
    "ParameterError",
    "PhysicalModel",
    "TestModel",
    "amplification_matrix",
    "baumgarte",
    "get_scheme",
    "make_method",
    "projection",
    "spectral_radius",
    "spectral_radius_float64",
    "spectral_radius_mp",
    "weighted_multiplier",
]

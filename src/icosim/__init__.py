"""icosim: implicit co-simulation methods with algebraic constraints.

A replication of Schweizer et al., *Implicit co-simulation methods: stability
and convergence analysis for solver coupling approaches with algebraic
constraints*: the linear two-mass test model, three coupling methods
(Baumgarte, weighted multiplier, projection), three decompositions
(force/force, force/displacement, displacement/displacement), Lagrange
approximation of any order k, the Jacobi (parallel) and Gauss-Seidel
(sequential) coupling schemes, and the spectral radius of the recurrence in
float64 and at arbitrary precision.

The map of the package is in the README (section "Layout"); the engine is
:mod:`icosim.macrostep` driving a :class:`icosim.problem.CosimulationProblem`
with a coupling method of the registry :mod:`icosim.methods`.
"""

from importlib.metadata import PackageNotFoundError, version

from .linear_problem import LinearCosimulation
from .methods import make_method
from .methods.baumgarte import baumgarte
from .methods.projection import projection
from .methods.weighted import weighted_multiplier
from .model import Coefficients, ParameterError, PhysicalModel, TestModel
from .schemes import JACOBI, GaussSeidel, Jacobi, get_scheme
from .stability import amplification_matrix, spectral_radius, spectral_radius_float64, spectral_radius_mp

try:
    __version__ = version("icosim")
except PackageNotFoundError:  # running from a source tree
    __version__ = "0+unknown"

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

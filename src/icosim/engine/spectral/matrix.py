"""The one-step amplification matrix of the linear test model (Sect. 2, Eqs. 21-23).

The matrix is obtained from the very macro-step algorithm that the time
stepper runs (:func:`icosim.engine.macrostep.macro_step`), by linearity: the step is
applied to every unit vector of the packed state
``(x1, v1, x2, v2, e_N, ..., e_N-k)``.  The paper's ``5(k+1)``-dimensional
companion form additionally carries old subsystem states that no equation
reads; they only add zero eigenvalues, so the spectral radius is the same.

>>> import numpy as np
>>> from icosim import TestModel, make_method
>>> M = amplification_matrix(TestModel(-0.5, 1.0), make_method("projection"), "ff", k=0)
>>> M.shape
(5, 5)
>>> float(np.max(np.abs(np.linalg.eigvals(M)))) < 1
True
"""

from __future__ import annotations

import numpy as np

from ...problems.linear.model import Coefficients
from ...problems.linear.problem import LinearCosimulation
from .. import layout
from ..backends import Float64
from ..decompositions import get_decomposition
from ..macrostep import macro_step
from ..methods import CouplingMethod
from ..schemes import JACOBI, get_scheme

__all__ = ["amplification_matrix", "as_coefficients"]


def _problem(coefficients: Coefficients, decomposition, k, backend, batch_axis=True):
    if batch_axis:  # room for the basis vectors the step is applied to
        coefficients = coefficients.map(lambda a: layout.batched(backend.asarray(a)[..., None]))
    return LinearCosimulation(coefficients, decomposition, k, backend)


def _matrix_from_problem(problem: LinearCosimulation, method: CouplingMethod, scheme=JACOBI):
    be = problem.backend
    n = problem.n_state
    eye = np.full((n, n), be.const(0), dtype=be.dtype)
    for i in range(n):
        eye[i, i] = be.const(1)
    state, history = problem.unpack(eye)
    s1, h1, _ = macro_step(problem, method, state, history, scheme=scheme)
    rows = problem.pack(s1, h1)  # row j: image of unit vector j
    return np.swapaxes(rows, -1, -2)


def amplification_matrix(coefficients, method: CouplingMethod, decomposition, k: int, backend=None, *, scheme=JACOBI):
    """The matrix ``M`` with ``w_N+1 = M w_N`` (leading axes follow the coefficients).

    ``coefficients`` is a :class:`~icosim.problems.linear.model.Coefficients` or a
    :class:`~icosim.problems.linear.model.TestModel` / :class:`~icosim.problems.linear.model.PhysicalModel`;
    ``scheme`` the coupling scheme (:mod:`icosim.engine.schemes`, default Jacobi).
    """
    scheme = get_scheme(scheme)
    be = backend or Float64()
    decomposition = get_decomposition(decomposition)
    method.check_decomposition(decomposition)
    scheme.check_decomposition(decomposition)
    coefficients = as_coefficients(coefficients)
    with be.context():  # Arb's working precision (a no-op for float64 and mpmath)
        return _matrix_from_problem(_problem(coefficients, decomposition, k, be), method, scheme)


def as_coefficients(c) -> Coefficients:
    """:class:`~icosim.problems.linear.model.Coefficients` of a test model, physical model or coefficients."""
    return c if isinstance(c, Coefficients) else c.coefficients()

"""The one-step amplification matrix of a linear co-simulation problem (Sect. 2, Eqs. 21-23).

The matrix is obtained from the very macro-step algorithm that the time stepper runs
(:func:`icosim.engine.macrostep.macro_step`), by linearity: the step is applied to every unit vector of the
packed state (for the two-mass model ``(x1, v1, x2, v2, e_N, ..., e_N-k)``).  The paper's
``5(k+1)``-dimensional companion form additionally carries old subsystem states that no equation reads; they
only add zero eigenvalues, so the spectral radius is the same.  The model is the family's
(:mod:`icosim.engine.spectral.family`); :func:`icosim.problems.linear.spectral.amplification_matrix` takes the
two-mass model's parameters.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..backends import Float64
from ..macrostep import CouplingRule, macro_step
from ..schemes import JACOBI, Scheme, get_scheme

if TYPE_CHECKING:
    from ..backends import Backend
    from ..methods.base import CouplingMethod
    from .family import LinearFamily

__all__ = ["amplification_matrix", "matrix_of"]


def matrix_of(problem: Any, method: CouplingRule | None, scheme: str | Scheme = JACOBI) -> np.ndarray:
    """``M`` of ``problem`` (a linear problem with a trailing axis for the basis vectors): the macro step of every
    unit vector of its packed state, the images as columns; ``method`` None: explicit coupling (connections only)."""
    be = problem.backend
    n = problem.n_state
    eye = np.full((n, n), be.const(0), dtype=be.dtype)
    for i in range(n):
        eye[i, i] = be.const(1)
    state, history = problem.unpack(eye)
    s1, h1, _ = macro_step(problem, method, state, history, scheme=scheme)
    rows = problem.pack(s1, h1)  # row j: image of unit vector j
    return np.swapaxes(rows, -1, -2)


def amplification_matrix(
    family: LinearFamily,
    method: CouplingMethod | None,
    *,
    backend: Backend | None = None,
    scheme: str | Scheme = JACOBI,
    exact: bool | None = None,
) -> np.ndarray:
    """The matrix ``M`` with ``w_N+1 = M w_N`` at every point of ``family`` (leading axes: the grid's).

    ``backend`` the arithmetic (float64 by default); ``exact`` (default: whenever the backend is not float64)
    takes the points' parameters exactly (:meth:`~icosim.engine.spectral.family.LinearFamily.problem`);
    ``scheme`` the coupling scheme (:mod:`icosim.engine.schemes`, default Jacobi).
    """
    scheme = get_scheme(scheme)
    be = backend or Float64()
    family.check(method, scheme)
    exact = not isinstance(be, Float64) if exact is None else exact
    with be.context():  # Arb's working precision (a no-op for float64 and mpmath)
        return matrix_of(family.problem(be, exact=exact), method, scheme)

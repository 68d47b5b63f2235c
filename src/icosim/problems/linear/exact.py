"""Exact monolithic solution of the two-mass oscillator (Eq. 4) and consistent starts.

With the rigid link, ``x1 = x2 = x`` and
``(m1 + m2) x'' = -(c1 + c2) x - (d1 + d2) x'``; the constraint force follows
from subsystem 1, ``lambda = m1 x'' + c1 x + d1 x'``.  In the engine's
dimensionless variables (time in macro steps, see :mod:`icosim.problems.linear.model`)
that is ``(1 + am21) x'' = -(k1 + am21 k2) x - (delta1 + am21 delta2) x'`` and
``lambda_bar = x'' + k1 x + delta1 x'``.
"""

from __future__ import annotations

import numpy as np

from ...engine.decompositions import get_decomposition
from .model import Coefficients

__all__ = ["MonolithicSolution", "consistent_start", "monolithic_matrix", "exact_coupling"]


def monolithic_matrix(c: Coefficients, backend=None):
    """``A`` with ``(x, v)' = A (x, v)`` for the rigidly coupled system (time in macro steps).

    In the backend's arithmetic (float64 by default), so the same matrix serves
    the float64 reference and the ball-arithmetic defect of
    :mod:`icosim.studies.convergence.errors`.
    """
    if backend is None:
        zero, one, dtype = 0.0, 1.0, float
    else:
        zero, one, dtype = backend.const(0), backend.const(1), backend.dtype
    total = one + c.am21
    return np.array(
        [[zero, one], [-(c.k1 + c.am21 * c.k2) / total, -(c.delta1 + c.am21 * c.delta2) / total]], dtype=dtype
    )


def exact_coupling(name: str, c: Coefficients, x, v, a):
    """The exact value of the coupling variable ``name`` for the exact ``x, v, a`` (any arithmetic):
    the constraint force ``lambda_c = a + k1 x + delta1 v`` or a prescribed acceleration (``a_tilde...``: the
    joint's acceleration ``a``, whichever subsystem it is taken from)."""
    if name == "lambda_c":
        return a + c.k1 * x + c.delta1 * v
    if name.startswith("a_tilde"):
        return a
    raise ValueError(f"unknown coupling variable {name!r}")


class MonolithicSolution:
    """Exact solution for scalar coefficients and initial ``(x0, v0)`` at ``t = 0``.

    Times are dimensionless (in macro steps) and may be negative: the history
    of the coupling variables before ``T_0`` is taken from this solution.
    """

    def __init__(self, coefficients: Coefficients, x0: float, v0: float):
        self.coefficients = coefficients
        self.A = monolithic_matrix(coefficients)
        self.s0 = np.array([x0, v0], dtype=float)

    def state(self, t):
        """``(x, v, a, lambda)`` at the times ``t`` (array), stacked on the last axis."""
        s = expm_2x2(self.A, t) @ self.s0
        x, v = s[..., 0], s[..., 1]
        a = self.A[1, 0] * x + self.A[1, 1] * v
        lam = exact_coupling("lambda_c", self.coefficients, x, v, a)
        return np.stack([x, v, a, lam], axis=-1)


def expm_2x2(A, t):
    """``exp(t A)`` for a real 2x2 matrix at many times ``t`` (closed form).

    With ``sigma = tr(A)/2`` and ``D = sigma^2 - det(A)``:
    ``exp(tA) = exp(sigma t) [c(t) I + s(t) (A - sigma I)]`` where
    ``c = cos(wt), s = sin(wt)/w`` for ``D = -w^2 < 0`` and
    ``c = cosh(wt), s = sinh(wt)/w`` for ``D = w^2 >= 0``; ``s`` is evaluated
    as ``t sinc`` resp. ``t sinh(x)/x``, so critical damping (``w -> 0``) is
    exact.  Much faster than a batched ``scipy.linalg.expm`` of ``t A``.
    """
    t = np.asarray(t, dtype=float)[..., None, None]
    A = np.asarray(A, dtype=float)
    sigma = np.trace(A) / 2
    disc = sigma**2 - np.linalg.det(A)
    w = np.sqrt(abs(disc))
    x = w * t
    if disc < 0:
        c, sfac = np.cos(x), t * np.sinc(x / np.pi)
    else:
        c = np.cosh(x)
        sfac = t * np.where(x == 0, 1.0, np.sinh(x) / np.where(x == 0, 1.0, x))
    return np.exp(sigma * t) * (c * np.eye(2) + sfac * (A - sigma * np.eye(2)))


def consistent_start(problem, solution: MonolithicSolution):
    """Initial state and coupling history of ``problem`` taken from the exact solution.

    Both subsystems start at the exact ``(x0, v0)``; the history holds the
    exact coupling variables at ``T_0, T_-1, ..., T_-k``: the constraint force
    ``lambda`` (ff), ``lambda`` and the acceleration (fd), the acceleration (dd).
    """
    k = problem.k
    exact = solution.state(-np.arange(k + 1, dtype=float))  # T_0, T_-1, ...
    dec = get_decomposition(problem.decomposition.name)
    c = solution.coefficients
    history = np.stack([exact_coupling(name, c, *exact[:, :3].T) for name in dec.variables], axis=-1)
    state = np.array([solution.s0, solution.s0])
    be = problem.backend
    return be.asarray(state), be.asarray(history)

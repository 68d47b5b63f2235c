"""The coupling solves of small systems (:meth:`icosim.engine.methods.base.CouplingMethod.corrected_coupling`):
closed forms for sizes 1 and 2, LU for larger ones, and a float64 matrix factored once for many right-hand sides
(:class:`KeptFactors`: held by the problem whose Jacobians they are)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .. import layout

__all__ = ["solve_small", "Factored", "KeptFactors"]


class Factored:
    """A float64 coupling matrix ``J`` (one point or a stack) made ready for many right-hand sides: sizes 1 and 2
    as :func:`solve_small` (closed forms), a larger single matrix LU-factored once (LAPACK ``getrf``, then
    ``getrs`` per right-hand side: the two halves of ``gesv``, which :func:`numpy.linalg.solve` calls for each
    right-hand side, so the same numbers).  A singular matrix raises as there."""

    def __init__(self, J: np.ndarray) -> None:
        self.J = J
        self.lu = None
        if J.shape[-1] > 2 and J.ndim == 2:
            from scipy.linalg.lapack import dgetrf  # here: most jobs solve no system larger than 2

            lu, piv, info = dgetrf(J)
            if info > 0:
                raise np.linalg.LinAlgError("Singular matrix")
            self.lu = (lu, piv)

    def solve(self, b: np.ndarray) -> np.ndarray:
        if self.lu is None or b.ndim != 1:
            return solve_small(self.J, b)
        from scipy.linalg.lapack import dgetrs

        return dgetrs(*self.lu, b)[0]


class KeptFactors:
    """The factored coupling matrices of one set of Jacobians that a problem hands every step (constant
    sensitivities), by the combination of levels they were formed with (another method on the same Jacobians
    combines others).  The problem that keeps the Jacobians holds it; a method fills it
    (:meth:`~icosim.engine.methods.base.CouplingMethod.corrected_coupling`).

    Their first solve is direct (a factorisation pays only where it is used again); every later one is by the
    combination's factor, made once."""

    __slots__ = ("used", "by_levels")

    def __init__(self) -> None:
        self.used = False
        self.by_levels: dict[tuple, Factored] = {}


def solve_small(J: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve ``J x = b`` for stacks of small systems, float64 or mpmath objects.

    Sizes 1 and 2 use closed forms, so a singular point yields inf/nan for that
    point only instead of aborting a whole grid (the precision policy then
    catches it).  Larger systems use LU (numpy; a float64 matrix that serves many right-hand sides, factored
    once: :func:`_factored_once`) or mpmath's ``lu_solve``.
    """
    n = J.shape[-1]
    if n > 2 and J.dtype == np.float64 and b.dtype == np.float64 and _serves_many(J, b):
        return _factored_once(J, b)
    if J.shape[:-1] != b.shape:  # (a single point's shapes agree: no broadcast to pay for)
        J, b = np.broadcast_arrays(J, b[..., None])
        b = b[..., 0]
    if n == 1:
        return b / J[..., 0]
    if n == 2:
        a, bb, c, d = J[..., 0, 0], J[..., 0, 1], J[..., 1, 0], J[..., 1, 1]
        det = a * d - bb * c
        x0 = (d * b[..., 0] - bb * b[..., 1]) / det
        x1 = (a * b[..., 1] - c * b[..., 0]) / det
        if np.ndim(det) == 0:  # one point: the pair as numpy.stack would make it
            return np.array([x0, x1])
        return layout.stack([x0, x1], axis=-1)
    if J.dtype != object:
        return np.linalg.solve(J, b[..., None])[..., 0]
    out = np.empty(b.shape, dtype=object)
    for idx in np.ndindex(b.shape[:-1]):
        out[idx] = _gauss(J[idx].tolist(), b[idx].tolist())
    return out


#: Right-hand sides per matrix from which :func:`solve_small` factors each matrix once.
MANY = 16


def _serves_many(J: np.ndarray, b: np.ndarray) -> bool:
    """Whether each matrix of ``J`` serves at least :data:`MANY` right-hand sides of ``b`` (the basis vectors an
    amplification matrix is formed from: one coupling matrix per point)."""
    lead = np.broadcast_shapes(J.shape[:-2], b.shape[:-1])
    return math.prod(lead) >= MANY * math.prod(J.shape[:-2])


def _factored_once(J: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``J x = b`` with each matrix of ``J`` factored once (:class:`Factored`) and every right-hand side it serves
    solved alone."""
    n = J.shape[-1]
    lead = np.broadcast_shapes(J.shape[:-2], b.shape[:-1])
    J = J.reshape((1,) * (len(lead) - J.ndim + 2) + J.shape)
    b = np.broadcast_to(b, lead + (n,))
    out = np.empty(lead + (n,))
    for jdx in np.ndindex(*J.shape[:-2]):
        factored = Factored(J[jdx])
        # the right-hand sides this matrix serves: every index along the axes it is broadcast over
        served = tuple(slice(None) if m == 1 else i for i, m in zip(jdx, J.shape[:-2]))
        rhs, x = b[served], out[served]
        for idx in np.ndindex(*rhs.shape[:-1]):
            x[idx] = factored.solve(rhs[idx])
    return out


def _gauss(A: list[list[Any]], y: list[Any]) -> list[Any]:
    """Gaussian elimination with partial pivoting in the numbers' own arithmetic
    (so mpmath values keep their context's precision and Arb balls their bounds).

    The pivot is chosen by the float magnitude: comparing two Arb balls is
    undecided when they overlap, and any nonzero pivot is correct (the size only
    affects how wide the balls grow)."""
    n = len(y)
    A = [row[:] + [y[i]] for i, row in enumerate(A)]
    for col in range(n):
        piv = max(range(col, n), key=lambda r: float(abs(A[r][col])))
        A[col], A[piv] = A[piv], A[col]
        for r in range(col + 1, n):
            f = A[r][col] / A[col][col]
            A[r] = [a - f * p for a, p in zip(A[r], A[col])]
    x = [None] * n
    for r in range(n - 1, -1, -1):
        x[r] = (A[r][n] - sum(A[r][c] * x[c] for c in range(r + 1, n))) / A[r][r]
    return x

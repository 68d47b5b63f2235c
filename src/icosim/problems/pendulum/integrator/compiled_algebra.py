"""Small dense algebra for the compiled integrator (:mod:`icosim.problems.pendulum.integrator.compiled`), as numba loops.

Matrices of order n <= 6 (the links' Newton matrices), so plain loops: numba's LAPACK bindings
(``np.linalg.solve``) would cost about 10 CPU-s of compilation in every process that finds no
cached kernel, and array expressions inflate the compiled code; both made the cold start 25 s.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["all_finite", "inverse", "matvec", "nan_maximum"]


@numba.njit(cache=True)
def matvec(A, x, out):
    """``out = A @ x`` summed in index order (both real or both complex)."""
    n = x.shape[0]
    for i in range(n):
        s = A[i, 0] * x[0]
        for j in range(1, n):
            s += A[i, j] * x[j]
        out[i] = s


@numba.njit(cache=True)
def all_finite(x):
    """``np.all(np.isfinite(x))`` for a 1-d array (pass ``a.ravel()``)."""
    for v in x:
        if not np.isfinite(v):
            return False
    return True


@numba.njit(cache=True)
def nan_maximum(a, b):
    """``np.maximum(a, b)`` for scalars: NaN if either is NaN."""
    if a != a or b != b:
        return a + b
    return a if a >= b else b


@numba.njit(cache=True)
def inverse(M, out):
    """``out = M^-1`` (real or complex) by LU with partial pivoting: LAPACK's gesv (getrf, then getrs
    on the identity), written out.  False for an exactly zero pivot (where gesv reports a singular
    matrix).  The operations in OpenBLAS's order where it matters for round-off: pivot by
    ``|re| + |im|``, columns scaled by the pivot's reciprocal, triangular solves column-oriented with
    the diagonal's inverse (the complex reciprocal is numba's).
    """
    n = M.shape[0]
    A = M.copy()
    piv = np.empty(n, np.int64)
    for j in range(n):
        # the pivot as i?amax picks it: largest |re| + |im| (|x| for real x), first of equals
        p, largest = j, abs(A[j, j].real) + abs(A[j, j].imag)
        for i in range(j + 1, n):
            size = abs(A[i, j].real) + abs(A[i, j].imag)
            if size > largest:
                p, largest = i, size
        piv[j] = p
        if A[p, j] == 0:
            return False
        if p != j:
            for c in range(n):
                A[j, c], A[p, c] = A[p, c], A[j, c]
        reciprocal = 1.0 / A[j, j]  # getf2 scales the column by the pivot's reciprocal
        for i in range(j + 1, n):
            A[i, j] *= reciprocal
            for c in range(j + 1, n):
                A[i, c] -= A[i, j] * A[j, c]
    out[:] = 0.0
    for i in range(n):
        out[i, i] = 1.0
    for j in range(n):  # the row interchanges of the right-hand side (laswp)
        p = piv[j]
        if p != j:
            for c in range(n):
                out[j, c], out[p, c] = out[p, c], out[j, c]
    for c in range(n):  # L y = P b (unit lower), then U x = y, column by column, as trsm orders them
        for k in range(n):
            for i in range(k + 1, n):
                out[i, c] -= out[k, c] * A[i, k]
        for k in range(n - 1, -1, -1):
            out[k, c] *= 1.0 / A[k, k]  # OpenBLAS's trsm multiplies by the diagonal's inverse
            for i in range(k):
                out[i, c] -= out[k, c] * A[i, k]
    return True

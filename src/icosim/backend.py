"""Arithmetic backends: float64 (batched over parameter grids) and mpmath.

The co-simulation algorithm is written once with NumPy array operations
(``+ - * /``, ``@``, indexing).  With the float64 backend the arrays are float64
and carry arbitrary leading batch axes (a whole parameter grid at once).  With
the multiprecision backend they are NumPy *object* arrays of ``mpf`` numbers
from a private :class:`mpmath.MPContext`, so the very same code runs at, say,
128 significant digits without touching mpmath's global precision.  Only the
matrix exponential and the eigenvalues differ between the two.
"""

from __future__ import annotations

import math
from fractions import Fraction

import mpmath
import numpy as np
import scipy.linalg

__all__ = ["Float64", "Multiprecision", "get_backend", "FLOAT64_DIGITS"]

#: Decimal digits float64 carries reliably (``numpy.finfo(float).precision``).
FLOAT64_DIGITS = int(np.finfo(float).precision)


class Float64:
    """IEEE double precision; every routine is vectorised over leading axes."""

    name = "float64"
    digits = FLOAT64_DIGITS
    dtype = np.float64
    eps = float(np.finfo(float).eps)

    def asarray(self, x):
        return np.asarray(x, dtype=float)

    def const(self, q):
        """A constant (int, Fraction, float) in this arithmetic."""
        return float(q)

    def expm(self, M, decay=0.0):
        # scipy's expm accepts stacks (..., n, n): one call for a whole grid.
        # ``decay`` is ignored: float64 cannot add guard digits (the precision
        # policy detects the points where that matters).
        return scipy.linalg.expm(M)

    def eigvals(self, M):
        return np.linalg.eigvals(M)

    def __repr__(self):
        return "Float64()"


class Multiprecision:
    """mpmath arithmetic with ``digits`` significant decimal digits."""

    name = "mpmath"
    dtype = object

    def __init__(self, digits: int = 128):
        if isinstance(digits, bool) or int(digits) != digits or digits < 16:
            raise ValueError(f"digits must be an integer >= 16, got {digits!r}")
        self.digits = int(digits)
        self.ctx = mpmath.MPContext()
        self.ctx.dps = self.digits
        self.eps = self.ctx.eps

    def _mpf(self, v):
        if isinstance(v, Fraction):
            return self.ctx.mpf(v.numerator) / v.denominator
        if isinstance(v, complex):
            return self.ctx.mpc(v)
        return self.ctx.mpf(v)

    def asarray(self, x):
        a = np.asarray(x, dtype=object)
        out = np.empty(a.shape, dtype=object)
        for idx in np.ndindex(a.shape):
            out[idx] = self._mpf(a[idx])
        return out

    def const(self, q):
        return self._mpf(q)

    def _each_matrix(self, M, fn, out_shape):
        M = np.asarray(M, dtype=object)
        batch = M.shape[:-2]
        out = np.empty(batch + out_shape, dtype=object)
        for idx in np.ndindex(batch):
            out[idx] = fn(self.ctx.matrix(M[idx].tolist()))
        return out

    def expm(self, M, decay=0.0):
        """Matrix exponential with ``digits`` significant digits in *every* entry.

        Scaling and squaring is accurate relative to the norm of the result,
        so entries of size ``exp(-decay)`` (a heavily damped subsystem) lose
        ``decay / ln 10`` digits.  They are computed with that many guard
        digits, so that 128 digits mean 128 significant digits.
        """
        n = np.shape(M)[-1]
        guard = 10 + int(math.ceil(max(float(decay), 0.0) / math.log(10)))

        def one(m):
            with self.ctx.extradps(guard):
                e = self.ctx.expm(m)
            return np.array([[+v for v in row] for row in e.tolist()], dtype=object)

        return self._each_matrix(M, one, (n, n))

    def eigvals(self, M):
        n = np.shape(M)[-1]

        def one(m):
            return np.array(self.ctx.eig(m, left=False, right=False), dtype=object)

        return self._each_matrix(M, one, (n,))

    def __repr__(self):
        return f"Multiprecision(digits={self.digits})"


def get_backend(digits: int | None = None):
    """float64 for ``digits`` None (or <= 15), otherwise mpmath with ``digits``."""
    if digits is None or digits <= FLOAT64_DIGITS:
        return Float64()
    return Multiprecision(digits)

"""Arithmetic backends: float64 (batched over parameter grids), mpmath, and Arb balls.

The co-simulation algorithm is written once with NumPy array operations
(``+ - * /``, ``@``, indexing).  With the float64 backend the arrays are float64
and carry arbitrary leading batch axes (a whole parameter grid at once).  With
the multiprecision backend they are NumPy *object* arrays of ``mpf`` numbers
from a private :class:`mpmath.MPContext`, so the very same code runs at, say,
128 significant digits without touching mpmath's global precision.  With the
ball backend (:class:`Ball`, python-flint's Arb) they are object arrays of
balls whose radii are proven error bounds.  Only the matrix exponential and
the eigenvalues differ between them.  Arithmetic runs inside
``backend.context()`` (Arb's precision is a global setting; the other
backends need nothing).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager, nullcontext
from fractions import Fraction
from typing import Any, TypeAlias

import numpy as np

from .bounds import check_digits, guard_digits

__all__ = ["Float64", "Multiprecision", "Ball", "FLOAT64_DIGITS"]

#: Decimal digits float64 carries reliably (``numpy.finfo(float).precision``).
FLOAT64_DIGITS = int(np.finfo(float).precision)


class Float64:
    """IEEE double precision; every routine is vectorised over leading axes."""

    name = "float64"
    digits = FLOAT64_DIGITS
    dtype = np.float64
    eps = float(np.finfo(float).eps)

    def context(self) -> AbstractContextManager[Float64]:
        return nullcontext(self)

    def asarray(self, x: Any) -> np.ndarray:
        return np.asarray(x, dtype=float)

    def const(self, q: float | Fraction) -> float:
        """A constant (int, Fraction, float) in this arithmetic."""
        return float(q)

    def expm(self, M: np.ndarray, decay: float = 0.0) -> np.ndarray:
        # scipy's expm accepts stacks (..., n, n): one call for a whole grid.
        # ``decay`` is ignored: float64 cannot add guard digits (the precision
        # policy detects the points where that matters).
        return _expm_float64(np.ascontiguousarray(M, dtype=float))

    def eigvals(self, M: np.ndarray) -> np.ndarray:
        return np.linalg.eigvals(M)

    def __repr__(self) -> str:
        return "Float64()"


#: Recent float64 exponentials by the bytes of their argument.  The panels of a figure share their
#: subsystems' matrices (subsystem 1 depends on the grid and k only, subsystem 2 also on the row, not on
#: the scheme), so one job forms each exponential once; the cached result is the one scipy returned
#: (read-only), so nothing changes but the time.
_EXPM_CACHE: dict = {}
_EXPM_CACHE_SIZE = 64


def _expm_float64(M: np.ndarray) -> np.ndarray:
    import hashlib

    import scipy.linalg  # here, not at the top: jobs that never form expm start faster

    if M.size < 64:  # small: hashing costs about as much as the exponential
        return scipy.linalg.expm(M)
    key = (M.shape, hashlib.blake2b(M.tobytes(), digest_size=20).digest())
    E = _EXPM_CACHE.pop(key, None)
    if E is None:
        E = scipy.linalg.expm(M)
        E.setflags(write=False)
    _EXPM_CACHE[key] = E  # most recent last
    while len(_EXPM_CACHE) > _EXPM_CACHE_SIZE:
        del _EXPM_CACHE[next(iter(_EXPM_CACHE))]
    return E


class Multiprecision:
    """mpmath arithmetic with ``digits`` significant decimal digits."""

    name = "mpmath"
    dtype = object
    #: :meth:`expm` adds guard digits for the decay of a damped subsystem
    uses_decay = True

    def __init__(self, digits: int = 128) -> None:
        self.digits = check_digits(digits)  # 16 .. icosim.engine.bounds.MAX_DIGITS
        import mpmath  # here, not at the top: float64-only jobs start faster

        self.ctx = mpmath.MPContext()
        self.ctx.dps = self.digits
        self.eps = self.ctx.eps

    def context(self) -> AbstractContextManager[Multiprecision]:
        return nullcontext(self)  # a private MPContext: nothing global to set

    def _mpf(self, v: Any) -> Any:
        """Exact for int, float, Fraction and mpf (then rounded to ``digits``); a decimal string is read
        at the working precision (correctly rounded), so ``"0.3"`` means 3/10."""
        if isinstance(v, np.ndarray | np.generic):
            v = v.item()
        if isinstance(v, Fraction):
            return self.ctx.mpf(v.numerator) / v.denominator
        if isinstance(v, complex):
            return self.ctx.mpc(v)
        return self.ctx.mpf(v)

    def asarray(self, x: Any) -> np.ndarray:
        a = np.asarray(x, dtype=object)
        out = np.empty(a.shape, dtype=object)
        for idx in np.ndindex(a.shape):
            out[idx] = self._mpf(a[idx])
        return out

    def const(self, q: Any) -> Any:
        return self._mpf(q)

    def _each_matrix(self, M: Any, fn: Callable[[Any], np.ndarray], out_shape: tuple[int, ...]) -> np.ndarray:
        M = np.asarray(M, dtype=object)
        batch = M.shape[:-2]
        out = np.empty(batch + out_shape, dtype=object)
        for idx in np.ndindex(batch):
            out[idx] = fn(self.ctx.matrix(M[idx].tolist()))
        return out

    def expm(self, M: Any, decay: float = 0.0) -> np.ndarray:
        """Matrix exponential with ``digits`` significant digits in *every* entry.

        Scaling and squaring is accurate relative to the norm of the result,
        so entries of size ``exp(-decay)`` (a heavily damped subsystem) lose
        ``decay / ln 10`` digits.  They are computed with that many guard
        digits, so that 128 digits mean 128 significant digits.
        """
        n = np.shape(M)[-1]
        guard = guard_digits(decay)  # PrecisionCapError beyond icosim.engine.bounds.MAX_GUARD_DIGITS

        def one(m: Any) -> np.ndarray:
            with self.ctx.extradps(guard):
                e = self.ctx.expm(m)
            return np.array([[+v for v in row] for row in e.tolist()], dtype=object)

        return self._each_matrix(M, one, (n, n))

    def eigvals(self, M: Any) -> np.ndarray:
        n = np.shape(M)[-1]

        def one(m: Any) -> np.ndarray:
            return np.array(self.ctx.eig(m, left=False, right=False), dtype=object)

        return self._each_matrix(M, one, (n,))

    def __repr__(self) -> str:
        return f"Multiprecision(digits={self.digits})"


#: Recent ball exponentials by working precision and a key that determines the matrix (:meth:`Ball.expm`).
_BALL_EXPM_CACHE: dict = {}
_BALL_EXPM_CACHE_SIZE = 16384


class Ball:
    """Arb ball arithmetic (python-flint) with ``bits`` of working precision.

    Every number is a ball ``[mid +/- rad]`` that is guaranteed to contain the
    exact value of the quantity computed from the exact inputs: the radius is a
    proven error bound, propagated through every operation of the engine's
    code (no estimate, no convention).  Arb's precision is a global setting, so
    arithmetic must run inside :meth:`context`.  There is no ``eigvals``:
    eigenvalues of a ball matrix with clusters (the Jordan block of the reduced
    state at 0) cannot be isolated; :mod:`icosim.engine.spectral.certified` encloses
    the spectral radius from the characteristic polynomial instead.
    """

    name = "ball"
    dtype = object

    def __init__(self, bits: int = 128) -> None:
        if isinstance(bits, bool) or int(bits) != bits or bits < 53:
            raise ValueError(f"bits must be an integer >= 53, got {bits!r}")
        import flint

        self._flint = flint
        self.bits = int(bits)
        self.digits = int(self.bits * math.log10(2))

    @contextmanager
    def context(self) -> Iterator[Ball]:
        """Set Arb's working precision to ``bits`` for the arithmetic inside."""
        ctx = self._flint.ctx
        old = ctx.prec
        ctx.prec = self.bits
        try:
            yield self
        finally:
            ctx.prec = old

    def const(self, q: Any) -> Any:
        """``q`` as a ball: exact for int, float, Fraction and mpf; a decimal string is enclosed."""
        arb = self._flint.arb
        if isinstance(q, arb):
            return q
        if isinstance(q, Fraction):
            return arb(q.numerator) / q.denominator
        if isinstance(q, (bool, np.bool_)):
            return arb(int(q))
        if isinstance(q, (int, np.integer)):
            return arb(int(q))
        if isinstance(q, (float, np.floating)):
            return arb(float(q))  # a double is a dyadic rational: exact
        if isinstance(q, str):
            return arb(q)
        if hasattr(q, "man_exp"):  # mpmath mpf: man * 2**exp exactly
            man, exp = q.man_exp
            return arb(self._flint.fmpz(int(man))) * arb(2) ** int(exp)
        raise TypeError(f"cannot make a ball of {type(q).__name__}")

    def asarray(self, x: Any) -> np.ndarray:
        a = np.asarray(x, dtype=object)
        out = np.empty(a.shape, dtype=object)
        for idx in np.ndindex(a.shape):
            out[idx] = self.const(a[idx])
        return out

    def expm(self, M: Any, decay: float = 0.0, keys: np.ndarray | None = None) -> np.ndarray:
        """Matrix exponential with a rigorous error bound (Arb's ``arb_mat_exp``).

        ``decay`` is not needed: a lost digit widens the balls, it is never hidden.  ``keys`` (optional, an
        object array over the batch axes of ``M``): per matrix a hashable value that determines it
        entirely (made with :meth:`identity`); a matrix exponentiated before at the same working precision
        under the same key is taken from a cache.  The balls are the very ones computed then (Arb is
        deterministic), so nothing changes but the time: the points certified in several panels of a
        figure share their subsystems' exponentials.
        """
        M = np.asarray(M, dtype=object)
        out = np.empty(M.shape, dtype=object)
        prec = self._flint.ctx.prec
        for idx in np.ndindex(M.shape[:-2]):
            key = None if keys is None or keys[idx] is None else (prec, keys[idx])
            E = _BALL_EXPM_CACHE.pop(key, None) if key is not None else None
            if E is None:
                E = np.array(self._flint.arb_mat(M[idx].tolist()).exp().tolist(), dtype=object)
            if key is not None:
                _BALL_EXPM_CACHE[key] = E  # most recent last
                if len(_BALL_EXPM_CACHE) > _BALL_EXPM_CACHE_SIZE:
                    del _BALL_EXPM_CACHE[next(iter(_BALL_EXPM_CACHE))]
            out[idx] = E
        return out

    def identity(self, x: Any) -> tuple[Any, Any] | None:
        """A hashable value that determines the ball ``x`` exactly (midpoint and radius), or None (not finite)."""
        try:
            return (x.mid().man_exp(), x.rad().man_exp())
        except Exception:  # noqa: BLE001 -- an infinite or NaN ball has no exact mantissa: not cached
            return None

    def mid(self, x: Any) -> np.ndarray:
        """Midpoints as float64 (the ball's centre, rounded to nearest)."""
        return np.vectorize(lambda v: float(v.mid()), otypes=[float])(np.asarray(x, dtype=object))

    def rad(self, x: Any) -> np.ndarray:
        """Radii as float64, rounded up."""
        return np.vectorize(lambda v: float(v.rad()) * (1 + 2**-52), otypes=[float])(np.asarray(x, dtype=object))

    def __repr__(self) -> str:
        return f"Ball(bits={self.bits})"


#: An arithmetic of the engine (for type checkers): what a problem computes in and the coupling methods
#: convert their exact constants with (``const``).
Backend: TypeAlias = Float64 | Multiprecision | Ball

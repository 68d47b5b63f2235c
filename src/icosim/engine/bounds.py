"""The engine's limits: the largest input it accepts, and the time one parameter point may take.

Every limit is checked before any work starts, so an input beyond one is
refused at once with a message naming the limit, never computed for ever:

* :data:`MAX_K` -- the largest approximation order ``k`` (the paper uses 0-2;
  the recurrence has ``4 + n (k + 1)`` states and Lagrange weights grow like
  ``2^k``, so beyond about 12 nothing is learnt that a smaller ``k`` does not
  show);
* :data:`MAX_DIGITS` -- the largest number of significant digits asked for;
* :data:`MAX_GUARD_DIGITS` -- the most guard digits a heavily damped subsystem
  may add (entries as small as ``exp(-decay)`` need ``decay / ln 10`` of
  them): a point that needs more is *undecided* with that reason, in every
  path (mpmath here, the ball arithmetic in bits, ``MAX_GUARD_BITS``);
* derived quantities (``k1 = lr1^2 + li1^2``, ``beta``, ``gamma``, ...) must be
  finite in float64 (:func:`check_finite`).

:func:`time_budget` bounds the wall time of one point (``--timeout``, the
grids' per-point budget): past it the point is undecided, reason ``timeout``.
"""

from __future__ import annotations

import contextlib
import math
import signal
import threading
from collections.abc import Iterator
from types import FrameType
from typing import Any, NoReturn

import numpy as np

from ..errors import NotFiniteError, ParameterError, PointTimeout, PrecisionCapError

__all__ = [
    "MAX_K",
    "MAX_GRID_N",
    "MAX_DIGITS",
    "MAX_GUARD_DIGITS",
    "MAX_GUARD_BITS",
    "MAX_BITS_LIMIT",
    "check_k",
    "check_digits",
    "MAX_SECONDS",
    "check_finite",
    "check_derived",
    "guard_digits",
    "time_budget",
]

MAX_K = 12
#: The most points per axis of a parameter grid (stability panels, ``icosim map``): 10001^2 points are
#: already about 0.8 GB per float64 array; beyond it a grid is refused before any allocation.
MAX_GRID_N = 10001
MAX_DIGITS = 2000
MAX_GUARD_DIGITS = 5000
MAX_GUARD_BITS = 16384  # ~4932 digits: the ball arithmetic's cap, the same size as MAX_GUARD_DIGITS
#: The largest working precision of the ball arithmetic one may ask for (``max_bits``; MAX_DIGITS in bits, rounded up).
MAX_BITS_LIMIT = 8192
#: The longest time budget one may give a point (``--timeout``, ``certify.point_seconds``): a day.
MAX_SECONDS = 86400.0


def check_k(k: Any, name: str = "k") -> int:
    """``k`` as an int in ``0 .. MAX_K``, or a :class:`ParameterError` naming ``name`` and the limit."""
    try:
        integral = not isinstance(k, bool) and int(k) == k
    except (TypeError, ValueError, OverflowError):
        integral = False
    if not integral or not 0 <= k <= MAX_K:
        raise ParameterError(
            f"{name} must be an integer in 0..{MAX_K} (icosim's largest approximation order; the paper uses 0-2), "
            f"got {k!r}"
        )
    return int(k)


def check_digits(digits: Any, name: str = "digits", smallest: int = 16) -> int:
    """``digits`` as an int in ``smallest .. MAX_DIGITS``, or a :class:`ParameterError` naming ``name``."""
    if isinstance(digits, bool) or not isinstance(digits, (int, np.integer)) or not smallest <= digits <= MAX_DIGITS:
        raise ParameterError(f"{name} must be an integer in {smallest}..{MAX_DIGITS} (icosim's limit), got {digits!r}")
    return int(digits)


def check_finite(name: str, value: Any, source: str = "") -> None:
    """A derived quantity must be a finite float64 (so it is representable at every precision the engine uses)."""
    with np.errstate(over="ignore", invalid="ignore"):
        try:
            arr = np.asarray(value, dtype=float)
        except OverflowError:  # an exact rational too large for a double
            arr = np.array(np.inf)
    if not np.all(np.isfinite(arr)):
        where = f" (from {source})" if source else ""
        raise NotFiniteError(f"{name}{where} is not a finite float64 number: the input is too large, got {value!r}")


def guard_digits(decay: float) -> int:
    """Guard digits for entries as small as ``exp(-decay)``; :class:`PrecisionCapError` past the cap."""
    guard = 10 + int(math.ceil(max(float(decay), 0.0) / math.log(10)))
    if guard > MAX_GUARD_DIGITS:
        raise PrecisionCapError(
            f"needs {guard} guard digits for exp(-{decay:.3g}) entries (a heavily damped subsystem), "
            f"more than the cap of {MAX_GUARD_DIGITS}"
        )
    return guard


@contextlib.contextmanager
def time_budget(seconds: float | None) -> Iterator[None]:
    """Raise :class:`PointTimeout` in the block after ``seconds`` of wall time (None or 0: no budget).

    Uses ``SIGALRM``, so it works in the main thread only (the command line and the workflow's jobs); elsewhere
    the block runs without a budget, and inside a running budget the outer one holds.
    """
    if not seconds or threading.current_thread() is not threading.main_thread() or not hasattr(signal, "setitimer"):
        yield
        return

    def expired(signum: int, frame: FrameType | None) -> NoReturn:
        raise PointTimeout(f"timeout: more than {seconds:g} s")

    if signal.getitimer(signal.ITIMER_REAL)[0]:  # an enclosing budget is running: it stays the only one
        yield
        return
    previous = signal.signal(signal.SIGALRM, expired)
    try:
        signal.setitimer(signal.ITIMER_REAL, min(float(seconds), MAX_SECONDS))
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


#: The subsystem coefficients of Eq. (71)'s parameters, with the inputs each is formed from.
_DERIVED = (
    ("k1 = lr1^2 + li1^2", "k1", ("lr1", "li1")),
    ("delta1 = -2 lr1", "delta1", ("lr1",)),
    ("k2 = (alr21 lr1)^2 + (ali21 li1)^2", "k2", ("lr1", "li1", "alr21", "ali21")),
    ("delta2 = -2 alr21 lr1", "delta2", ("lr1", "alr21")),
)


def check_derived(model: Any) -> None:
    """The subsystem coefficients of one :class:`~icosim.problems.linear.model.TestModel` point must be finite in float64.

    Raises a :class:`ParameterError` that starts with the input responsible (the largest one the
    overflowing coefficient is formed from), e.g. ``ali21 = 1e+300 makes k2 = ... too large for float64``.
    """
    c = model.coefficients()
    for formula, name, inputs in _DERIVED:
        try:
            ok = math.isfinite(float(getattr(c, name)))
        except OverflowError:  # an exact rational too large for a double
            ok = False
        if not ok:
            culprit = max(inputs, key=lambda n: abs(float(getattr(model, n))))
            raise ParameterError(
                f"{culprit} = {float(getattr(model, culprit)):g} makes {formula} too large for float64 (not finite)"
            )

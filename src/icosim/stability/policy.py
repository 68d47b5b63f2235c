"""The precision policy: float64 first, mpmath where float64 cannot decide.

A point is *trusted* if its float64 result is finite and ``|rho - 1|`` exceeds
its error estimate (:mod:`icosim.stability.spectral`); every other point is
recomputed with mpmath (128 significant digits by default, as in the paper),
and the result records which precision decided each point.

Decision: with multiprecision a point counts as stable if
``rho <= 1 + 10**(-digits/2)``: an eigenvalue 1 of a Jordan block (the free
mass at the origin of the parameter plane) is computed only to about half the
working digits.

The origin of the parameter plane is marginal, and float64 cannot decide it:

>>> from icosim import TestModel, make_method
>>> res = spectral_radius(TestModel(0.0, 0.0), make_method("projection"), "ff", k=0)
>>> int(res.digits), bool(res.stable), res.n_high_precision
(128, True, 1)
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import mpmath
import numpy as np

from ..backend import FLOAT64_DIGITS
from ..model import Coefficients, TestModel
from ..schemes import JACOBI, get_scheme
from .matrix import as_coefficients
from .spectral import spectral_radius_float64, spectral_radius_mp

__all__ = ["spectral_radius", "StabilityResult", "is_stable"]


def is_stable(rho, digits):
    """``rho <= 1`` (with the half-precision allowance for multiprecision results)."""
    rho = np.asarray(rho, dtype=float)
    digits = np.asarray(digits)
    tol = np.where(digits > FLOAT64_DIGITS, 10.0 ** (-(digits // 2).astype(float)), 0.0)
    return rho <= 1 + tol


@dataclass
class StabilityResult:
    """Per point: spectral radius, float64 error estimate, the digits that decided it.

    ``seconds`` and ``cpu_seconds`` split the cost into the float64 pass and the
    multiprecision rechecks (keys ``float64`` and ``mp``).
    """

    rho: np.ndarray
    err: np.ndarray
    digits: np.ndarray
    stable: np.ndarray
    seconds: dict = field(default_factory=dict)
    cpu_seconds: dict = field(default_factory=dict)

    @property
    def n_high_precision(self) -> int:
        return int(np.sum(self.digits > FLOAT64_DIGITS))

    @property
    def n_failed(self) -> int:
        """Points that no precision could decide (``rho`` is nan, ``digits`` -1)."""
        return int(np.sum(self.digits < 0))


def spectral_radius(model, method, decomposition, k, *, digits: int = 128, policy: str = "auto", scheme=JACOBI):
    """Spectral radius over arrays of parameter points with the precision policy.

    Parameters
    ----------
    model : :class:`TestModel` (Eq. 71; its attributes broadcast to the grid),
        or :class:`~icosim.model.PhysicalModel` / :class:`~icosim.model.Coefficients`
        (any damping, overdamped included).
    scheme : the coupling scheme (:mod:`icosim.schemes`; default Jacobi).
    policy : ``"auto"`` (float64, recheck untrusted points at ``digits``),
        ``"float64"`` (no recheck) or ``"mp"`` (every point at ``digits``).

    A point whose multiprecision recheck fails (a singular coupling condition
    in exact arithmetic) gets ``rho = nan`` and ``digits = -1`` instead of
    aborting the grid; :attr:`StabilityResult.n_failed` counts them.
    """
    if policy not in ("auto", "float64", "mp"):
        raise ValueError(f"policy must be 'auto', 'float64' or 'mp', got {policy!r}")
    scheme = get_scheme(scheme)
    if isinstance(model, TestModel):
        names, point_type = ("lr1", "li1", "am21", "alr21", "ali21"), TestModel
    else:  # exact conversion happens per point in spectral_radius_mp
        model = as_coefficients(model)
        names, point_type = ("k1", "delta1", "k2", "delta2", "am21"), Coefficients
    arrays = np.broadcast_arrays(*(np.asarray(getattr(model, n), dtype=float) for n in names))
    shape = arrays[0].shape
    t0, c0 = time.perf_counter(), time.process_time()
    if policy == "mp":
        rho = np.full(shape, np.nan)
        err = np.full(shape, np.inf)
        recheck = np.ones(shape, dtype=bool)
    else:
        rho, err = spectral_radius_float64(point_type(*arrays), method, decomposition, k, scheme=scheme)
        trusted = np.isfinite(rho) & (np.abs(rho - 1) > err)
        recheck = ~trusted if policy == "auto" else np.zeros(shape, dtype=bool)
    digits_used = np.full(shape, FLOAT64_DIGITS, dtype=int)
    t1, c1 = time.perf_counter(), time.process_time()
    for idx in np.ndindex(shape):
        if not recheck[idx]:
            continue
        point = point_type(*(float(a[idx]) for a in arrays))
        try:
            rho[idx] = float(spectral_radius_mp(point, method, decomposition, k, digits, scheme=scheme))
            digits_used[idx] = digits
        except (ArithmeticError, mpmath.libmp.NoConvergence):
            rho[idx], digits_used[idx] = np.nan, -1
    t2, c2 = time.perf_counter(), time.process_time()
    return StabilityResult(
        rho=rho,
        err=err,
        digits=digits_used,
        stable=is_stable(rho, digits_used),
        seconds={"float64": t1 - t0, "mp": t2 - t1},
        cpu_seconds={"float64": c1 - c0, "mp": c2 - c1},
    )

"""Spectral radius of the amplification matrix: float64 with an error estimate, and mpmath.

float64 runs vectorised over the whole parameter grid.  Each float64 value
comes with an error estimate obtained by re-running the same computation with
the inputs disturbed at the size of their rounding errors: the exponential
blocks of both subsystems (absolute error ~ u ||E||, the normwise accuracy of
scaling-and-squaring) and the amplification matrix itself (backward error of
the eigensolver, ~ u ||M||).  The spread of the disturbed spectral radii,
times a safety factor, is the estimate.  A second disturbed run is made only
where the first one's estimate, ``DOUBT`` times over, reaches ``|rho - 1|``
(a fraction of a percent of a grid: the points near 1, which are certified
anyway, and the ill-conditioned ones); elsewhere the verdict does not hang on
it.  It needs no model of *why* float64
fails: cancellation in the corrections (sensitivities that both decay like
``exp(lr)``), underflow, or eigenvalues clustered at 1 near the origin all show
up as a large spread.  The multiprecision path recomputes one point with every
derived quantity formed at ``digits`` significant digits.

>>> from icosim import TestModel, make_method
>>> m, point = make_method("weighted", a=1, b=1), TestModel(-0.05, 0.5)
>>> rho, err = spectral_radius_float64(point, m, "ff", k=2)
>>> rho_mp = spectral_radius_mp(point, m, "ff", k=2, digits=40)
>>> bool(abs(float(rho) - float(rho_mp)) <= err), bool(rho > 1)
(True, True)
"""

from __future__ import annotations

import copy

import numpy as np

from ..backends import Float64, Multiprecision
from ..decompositions import get_decomposition
from ..linear_problem import LinearCosimulation
from ..model import TestModel
from ..schemes import JACOBI, get_scheme
from .matrix import _matrix_from_problem, _problem, as_coefficients

__all__ = ["spectral_radius_float64", "spectral_radius_mp", "SAFETY", "DISTURBANCE", "DOUBT"]


#: Safety factor on the measured spread of disturbed float64 results.
SAFETY = 10.0


#: Disturbance size, in units of the float64 unit roundoff.
DISTURBANCE = 4.0


#: A second disturbed run is made where ``DOUBT`` times the first one's estimate reaches ``|rho - 1|``.
DOUBT = 1000.0


def _spectral_radius_of(M, backend):
    ev = backend.eigvals(M)
    return np.max(np.abs(ev), axis=-1)


def _disturbed(problem: LinearCosimulation, rng, rel):
    """A copy whose exponential blocks carry absolute noise ``rel * max|E|``."""
    p = copy.copy(problem)
    subs = []
    for sub in problem.subsystems:
        s = copy.copy(sub)
        s.__dict__.pop("_node_cache", None)
        E = sub.blocks
        scale = rel * np.max(np.abs(E), axis=(-1, -2), keepdims=True)
        s.set_blocks(E + scale * rng.standard_normal(E.shape))
        subs.append(s)
    p.subsystems = tuple(subs)
    if hasattr(p, "_jac"):
        del p._jac
    return p


def _disturbed_spread(problem, method, scheme, rho, rng, rel):
    """``|rho_d - rho|`` of one disturbed run (exponential blocks and amplification matrix; inf where the
    disturbed matrix is not finite)."""
    be = problem.backend
    Md = _matrix_from_problem(_disturbed(problem, rng, rel), method, scheme)
    ok = np.all(np.isfinite(Md), axis=(-1, -2))
    Md = np.where(ok[..., None, None], Md, 0.0)
    norm = np.max(np.abs(Md), axis=(-1, -2), keepdims=True)
    Md = Md + rel * norm * rng.standard_normal(Md.shape)
    ok &= np.all(np.isfinite(Md), axis=(-1, -2))  # entries near the float64 limit overflow with the noise
    Md = np.where(ok[..., None, None], Md, 0.0)
    rho_d = np.where(ok, _spectral_radius_of(Md, be), np.nan)
    return np.where(ok, np.abs(rho_d - rho), np.inf)


def spectral_radius_float64(
    coefficients, method, decomposition, k, *, error_estimate=True, seed=0, scheme=JACOBI, doubt=DOUBT
):
    """Spectral radius in float64 over arrays of parameter points.

    Returns ``(rho, err)``; ``err`` is the error estimate described in the
    module docstring (``None`` if not requested; ``doubt=np.inf`` makes the
    second disturbed run on every point).  Non-finite values are
    returned as they are (never raised), so one bad point cannot spoil a grid.
    """
    be = Float64()
    scheme = get_scheme(scheme)
    decomposition = get_decomposition(decomposition)
    method.check_decomposition(decomposition)
    scheme.check_decomposition(decomposition)
    coefficients = as_coefficients(coefficients)
    with np.errstate(all="ignore"):
        problem = _problem(coefficients, decomposition, k, be)
        M = _matrix_from_problem(problem, method, scheme)
        finite = np.all(np.isfinite(M), axis=(-1, -2))
        M_safe = np.where(finite[..., None, None], M, 0.0)
        rho = np.where(finite, _spectral_radius_of(M_safe, be), np.nan)
        if not error_estimate:
            return rho, None
        rng = np.random.default_rng(seed)
        rel = DISTURBANCE * be.eps
        spread = _disturbed_spread(problem, method, scheme, rho, rng, rel)
        # the second disturbed run only where the first one's estimate, ``doubt`` times over, reaches |rho - 1|:
        # elsewhere no second spread seen on the project's grids came near deciding (docs/engine.md)
        floor = 2 * rel * np.maximum(rho, 1.0)
        twice = np.isfinite(rho) & np.isfinite(spread) & ~(doubt * (SAFETY * spread + floor) < np.abs(rho - 1))
        if twice.any():
            points = coefficients.map(lambda a: np.broadcast_to(np.asarray(a, dtype=float), rho.shape)[twice])
            again = _disturbed_spread(_problem(points, decomposition, k, be), method, scheme, rho[twice], rng, rel)
            spread[twice] = np.fmax(spread[twice], again)
            spread[twice] = np.where(np.isfinite(again), spread[twice], np.inf)
        err = SAFETY * spread + floor
        err = np.where(np.isfinite(rho), err, np.inf)
    return rho, err


def spectral_radius_mp(coefficients, method, decomposition, k, digits: int = 128, *, scheme=JACOBI):
    """Spectral radius of one parameter point at ``digits`` significant digits.

    The parameters are taken exactly as given -- a float as the binary number
    it is, a :class:`~fractions.Fraction` or decimal string as the decimal
    number (``"-0.3"`` is -3/10, not -0.29999999999999998890) -- and every
    derived quantity is formed in multiprecision, as are the method's exact
    parameters.  Returns an ``mpf`` with ``digits`` significant digits.
    """
    be = Multiprecision(digits)
    decomposition = get_decomposition(decomposition)
    method.check_decomposition(decomposition)
    get_scheme(scheme).check_decomposition(decomposition)
    if isinstance(coefficients, TestModel):
        coefficients = TestModel(
            *(be.const(getattr(coefficients, f)) for f in ("lr1", "li1", "am21", "alr21", "ali21"))
        ).coefficients()
    else:
        coefficients = as_coefficients(coefficients).map(be.const)
    M = _matrix_from_problem(_problem(coefficients, decomposition, k, be), method, get_scheme(scheme))
    return _spectral_radius_of(M, be)

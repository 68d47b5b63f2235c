"""Stability of the co-simulation recurrence (Sect. 2, Eqs. 21-23).

The one-step amplification matrix is obtained from the very macro-step
algorithm that the time stepper runs (:func:`icosim.macrostep.macro_step`),
by linearity: the step is applied to every unit vector of the packed state
``(x1, v1, x2, v2, e_N, ..., e_N-k)``.  The paper's ``5(k+1)``-dimensional
companion form additionally carries old subsystem states that no equation
reads; they only add zero eigenvalues, so the spectral radius is the same.

Precision policy
----------------
float64 first, vectorised over the whole parameter grid.  Each float64 value
comes with an error estimate obtained by re-running the same computation with
the inputs disturbed at the size of their rounding errors: the exponential
blocks of both subsystems (absolute error ~ u ||E||, the normwise accuracy of
scaling-and-squaring) and the amplification matrix itself (backward error of
the eigensolver, ~ u ||M||).  The spread of the disturbed spectral radii,
times a safety factor, is the estimate.  It needs no model of *why* float64
fails: cancellation in the corrections (sensitivities that both decay like
``exp(lr)``), underflow, or eigenvalues clustered at 1 near the origin all show
up as a large spread.  A point is *trusted* if its float64 result is finite and
``|rho - 1|`` exceeds the estimate; every other point is recomputed with
mpmath (128 significant digits by default, as in the paper), and the result
records which precision decided each point.

Decision: with multiprecision a point counts as stable if
``rho <= 1 + 10**(-digits/2)``: an eigenvalue 1 of a Jordan block (the free
mass at the origin of the parameter plane) is computed only to about half the
working digits.
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass, field

import mpmath
import numpy as np

from .backend import FLOAT64_DIGITS, Float64, Multiprecision
from .coupling import CouplingMethod, get_decomposition
from .macrostep import macro_step
from .model import Coefficients, TestModel
from .oscillator import LinearCosimulation

__all__ = [
    "amplification_matrix",
    "spectral_radius_float64",
    "spectral_radius_mp",
    "spectral_radius",
    "StabilityResult",
    "is_stable",
]

#: Safety factor on the measured spread of disturbed float64 results.
SAFETY = 10.0
#: Disturbance size, in units of the float64 unit roundoff.
DISTURBANCE = 4.0


def _problem(coefficients: Coefficients, decomposition, k, backend, batch_axis=True):
    if batch_axis:  # room for the basis vectors the step is applied to
        coefficients = coefficients.map(lambda a: backend.asarray(a)[..., None])
    return LinearCosimulation(coefficients, decomposition, k, backend)


def _matrix_from_problem(problem: LinearCosimulation, method: CouplingMethod):
    be = problem.backend
    n = problem.n_state
    eye = np.full((n, n), be.const(0), dtype=be.dtype)
    for i in range(n):
        eye[i, i] = be.const(1)
    state, history = problem.unpack(eye)
    s1, h1, _ = macro_step(problem, method, state, history)
    rows = problem.pack(s1, h1)  # row j: image of unit vector j
    return np.swapaxes(rows, -1, -2)


def amplification_matrix(coefficients, method: CouplingMethod, decomposition, k: int, backend=None):
    """The matrix ``M`` with ``w_N+1 = M w_N`` (leading axes follow the coefficients).

    ``coefficients`` is a :class:`~icosim.model.Coefficients` or a
    :class:`~icosim.model.TestModel` / :class:`~icosim.model.PhysicalModel`.
    """
    be = backend or Float64()
    decomposition = get_decomposition(decomposition) if isinstance(decomposition, str) else decomposition
    method.check_decomposition(decomposition)
    coefficients = _as_coefficients(coefficients)
    return _matrix_from_problem(_problem(coefficients, decomposition, k, be), method)


def _as_coefficients(c):
    return c if isinstance(c, Coefficients) else c.coefficients()


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


def spectral_radius_float64(coefficients, method, decomposition, k, *, error_estimate=True, seed=0):
    """Spectral radius in float64 over arrays of parameter points.

    Returns ``(rho, err)``; ``err`` is the error estimate described in the
    module docstring (``None`` if not requested).  Non-finite values are
    returned as they are (never raised), so one bad point cannot spoil a grid.
    """
    be = Float64()
    decomposition = get_decomposition(decomposition) if isinstance(decomposition, str) else decomposition
    method.check_decomposition(decomposition)
    coefficients = _as_coefficients(coefficients)
    with np.errstate(all="ignore"):
        problem = _problem(coefficients, decomposition, k, be)
        M = _matrix_from_problem(problem, method)
        finite = np.all(np.isfinite(M), axis=(-1, -2))
        M_safe = np.where(finite[..., None, None], M, 0.0)
        rho = np.where(finite, _spectral_radius_of(M_safe, be), np.nan)
        if not error_estimate:
            return rho, None
        rng = np.random.default_rng(seed)
        rel = DISTURBANCE * be.eps
        spread = np.zeros_like(rho)
        for _ in range(2):
            Md = _matrix_from_problem(_disturbed(problem, rng, rel), method)
            ok = np.all(np.isfinite(Md), axis=(-1, -2))
            Md = np.where(ok[..., None, None], Md, 0.0)
            norm = np.max(np.abs(Md), axis=(-1, -2), keepdims=True)
            Md = Md + rel * norm * rng.standard_normal(Md.shape)
            rho_d = np.where(ok, _spectral_radius_of(Md, be), np.nan)
            spread = np.fmax(spread, np.abs(rho_d - rho))
            spread = np.where(ok, spread, np.inf)
        err = SAFETY * spread + 2 * rel * np.maximum(rho, 1.0)
        err = np.where(np.isfinite(rho), err, np.inf)
    return rho, err


def spectral_radius_mp(coefficients, method, decomposition, k, digits: int = 128):
    """Spectral radius of one parameter point at ``digits`` significant digits.

    ``coefficients`` are converted exactly from their float values, then every
    derived quantity is formed in multiprecision.  Returns an ``mpf``.
    """
    be = Multiprecision(digits)
    decomposition = get_decomposition(decomposition) if isinstance(decomposition, str) else decomposition
    method.check_decomposition(decomposition)
    if isinstance(coefficients, TestModel):
        coefficients = TestModel(
            *(be.const(float(getattr(coefficients, f))) for f in ("lr1", "li1", "am21", "alr21", "ali21"))
        ).coefficients()
    else:
        coefficients = _as_coefficients(coefficients).map(lambda a: be.const(float(a)))
    M = _matrix_from_problem(_problem(coefficients, decomposition, k, be), method)
    return _spectral_radius_of(M, be)


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


def spectral_radius(model, method, decomposition, k, *, digits: int = 128, policy: str = "auto"):
    """Spectral radius over arrays of parameter points with the precision policy.

    Parameters
    ----------
    model : :class:`TestModel` (Eq. 71; its attributes broadcast to the grid),
        or :class:`~icosim.model.PhysicalModel` / :class:`~icosim.model.Coefficients`
        (any damping, overdamped included).
    policy : ``"auto"`` (float64, recheck untrusted points at ``digits``),
        ``"float64"`` (no recheck) or ``"mp"`` (every point at ``digits``).

    A point whose multiprecision recheck fails (a singular coupling condition
    in exact arithmetic) gets ``rho = nan`` and ``digits = -1`` instead of
    aborting the grid; :attr:`StabilityResult.n_failed` counts them.
    """
    if policy not in ("auto", "float64", "mp"):
        raise ValueError(f"policy must be 'auto', 'float64' or 'mp', got {policy!r}")
    if isinstance(model, TestModel):
        names, point_type = ("lr1", "li1", "am21", "alr21", "ali21"), TestModel
    else:  # exact conversion happens per point in spectral_radius_mp
        model = _as_coefficients(model)
        names, point_type = ("k1", "delta1", "k2", "delta2", "am21"), Coefficients
    arrays = np.broadcast_arrays(*(np.asarray(getattr(model, n), dtype=float) for n in names))
    shape = arrays[0].shape
    t0, c0 = time.perf_counter(), time.process_time()
    if policy == "mp":
        rho = np.full(shape, np.nan)
        err = np.full(shape, np.inf)
        recheck = np.ones(shape, dtype=bool)
    else:
        rho, err = spectral_radius_float64(point_type(*arrays), method, decomposition, k)
        trusted = np.isfinite(rho) & (np.abs(rho - 1) > err)
        recheck = ~trusted if policy == "auto" else np.zeros(shape, dtype=bool)
    digits_used = np.full(shape, FLOAT64_DIGITS, dtype=int)
    t1, c1 = time.perf_counter(), time.process_time()
    for idx in np.ndindex(shape):
        if not recheck[idx]:
            continue
        point = point_type(*(float(a[idx]) for a in arrays))
        try:
            rho[idx] = float(spectral_radius_mp(point, method, decomposition, k, digits))
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

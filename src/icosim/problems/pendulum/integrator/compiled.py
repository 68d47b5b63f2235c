"""The links' integrator: Radau IIA (3 stages, order 5) with step-size control, batched, compiled with numba.

The pendulum's subsystems are integrated numerically, as in the paper (Sect. 4: an implicit
Runge-Kutta method with ``rtol = atol = 1e-6``).  Every macro step integrates each link about twice
(predictor batch with the sensitivities, corrector), on a batch of ``B <= 5`` systems of size 2
(link 1) or 6 (link 2); scipy's ``solve_ivp`` (``method='Radau'``) costs about a millisecond per
call in Python overhead alone, and numpy on arrays that small is nearly all per-call overhead too.
So this module is scipy's Radau algorithm (Hairer & Wanner, *Solving ODEs II*, Sect. IV.8; scipy's
``integrate/_ivp/radau.py``, its constants in :mod:`.tableau`) written as loops over scalars and
compiled (``numba.njit(cache=True)``), for a **batch** of systems of the same size that share one
step sequence:

* the collocation equations are solved by simplified Newton iterations in the transformed
  variables (one real and one complex ``n x n`` system per batch member, inverted once per step
  attempt), in lockstep until the slowest member has converged; the Newton tolerance
  (``newton_tol``, relative to the error scale) is tighter than scipy's default, so the stage
  equations are solved to near round-off;
* the error estimate is scipy's (the embedded formula with the real eigenvalue), scaled by
  ``atol + rtol * max(|y|, |y_new|)``; the error norm of a step is the largest RMS norm over the
  members;
* the first trial step is the whole interval (for a macro step usually accepted at once), then
  scipy's predictive (Gustafsson) controller with the same safety factor and bounds ``[0.2, 10]``;
  an error estimate of exactly 0 (a system at rest) grows the step by the largest factor, as scipy's
  does; rejected Newton iterations halve the step after a fresh Jacobian; the Jacobian is by
  forward differences, fresh every step, the first one optionally given (``jac0``);
* failures are a status code here, raised as
  :class:`~icosim.problems.pendulum.integrator.systems.IntegrationError` by the Python side
  (:mod:`icosim.problems.pendulum.integrator.systems`).

Sharing the steps makes the end state a *smooth* function of each member's initial value and
input: finite differences between members (the co-simulation's sensitivities) see the derivative
of one fixed discrete map, not the noise of different step sequences.

The systems are the links' right-hand sides (:mod:`icosim.problems.pendulum.integrator.compiled_links`),
which the co-simulation integrates through :mod:`.compiled_step` (one call per link integration),
and the whole pendulum in minimal coordinates
(:func:`~icosim.problems.pendulum.integrator.systems.monolithic_radau`, the monolithic baseline of the
speed-accuracy study).  The matrix inverses are an LU solve written out
(:mod:`~icosim.problems.pendulum.integrator.compiled_algebra`).  tests/reference_radau.py is the same
algorithm in numpy, the reference the tests compare this module with (the same step sequence and
counters, the numbers up to round-off).

One specialisation per entry point (C-contiguous float64 arrays of fixed ndim,
int64 ids), so a cold disk cache costs one compilation per process.
"""

from __future__ import annotations

import numba
import numpy as np

from .compiled_algebra import all_finite, inverse, matvec, nan_maximum
from .compiled_links import FORCE, batch_rhs, member_rhs
from .kernel_cache import compile_record, drop_stale_cache, gc_paused
from .tableau import EPS, MAX_FACTOR, MIN_FACTOR, MU_COMPLEX, MU_REAL, NEWTON_MAXITER, TI, C, E, T

__all__ = ["warm_up", "compile_kernels"]


drop_stale_cache()  # before the kernels are defined: numba loads their cache as it defines them

#: ``t_rec`` and ``y_rec`` of :func:`_radau` that record nothing.
NOT_RECORDED = (np.empty(0), np.empty((0, 0, 0)))

# status codes of the kernel (0: integrated)
_STEP_TOO_SMALL, _ERROR_NOT_FINITE, _SINGULAR, _TOO_MANY_STEPS, _DERIVATIVE_NOT_FINITE = range(1, 6)

# numba sees module globals as compile-time constants: plain floats and arrays
_MU_COMPLEX_RE, _MU_COMPLEX_IM = MU_COMPLEX.real, MU_COMPLEX.imag
_TI_REAL, _TI_COMPLEX_RE, _TI_COMPLEX_IM = TI[0].copy(), TI[1].copy(), TI[2].copy()


# -- the integrator ------------------------------------------------------------------------------------
@numba.njit(cache=True)
def _fd_jacobian(link, kind, par, H, coef, t, y, f, J):
    """``J[b] = d fun / d y`` at ``(t, y[b])`` by forward differences, step ``sqrt(eps) max(1, |y_j|)``."""
    B, n = y.shape
    Y = np.empty(n)
    F = np.empty(n)
    sqrt_eps = np.sqrt(EPS)
    for j in range(n):  # perturb component j
        for b in range(B):
            h = sqrt_eps * max(1.0, abs(y[b, j]))
            for i in range(n):
                Y[i] = y[b, i]
            Y[j] += h
            member_rhs(link, kind, par, H, t, Y, coef[b], F)
            for i in range(n):
                J[b, i, j] = (F[i] - f[b, i]) / h


@numba.njit(cache=True)
def _predict_factor(h_abs, h_abs_old, error_norm, error_norm_old, have_old):
    if error_norm == 0:  # at rest: +inf, capped at MAX_FACTOR by the caller (as scipy's numpy float is)
        return np.inf
    if not have_old or error_norm_old == 0:
        multiplier = 1.0
    else:
        multiplier = h_abs / h_abs_old * (error_norm_old / error_norm) ** 0.25
    return min(1.0, multiplier) * error_norm**-0.25


@numba.njit(cache=True)
def _rms_max(x, scale):
    """Largest RMS norm over the batch of ``x / scale``."""
    B, n = x.shape
    largest = 0.0
    for b in range(B):
        s = 0.0
        for j in range(n):
            q = x[b, j] / scale[b, j]
            s += q * q
        largest = max(largest, s)
    return np.sqrt(largest / n)


@numba.njit(cache=True)
def _collocation(link, kind, par, H, coef, t, y, h, scale, tol, inv_real, inv_complex, Z):
    """Simplified Newton iterations for the stage increments ``Z`` (3, B, n), in lockstep.

    Returns ``(converged, n_iter, fev)``; ``Z`` is filled (NaN after a non-finite right-hand side).
    """
    B, n = y.shape
    W = np.zeros((3, B, n))
    Z.fill(0.0)
    F = np.empty((3, B, n))
    Y = np.empty((B, n))
    f_real, dW_real = np.empty(n), np.empty(n)
    f_complex, dW_complex = np.empty(n, np.complex128), np.empty(n, np.complex128)
    dW = np.empty((3, n))  # one member's (dW_real, dW_complex.real, dW_complex.imag)
    mu_real = MU_REAL / h
    mu_complex = complex(_MU_COMPLEX_RE / h, _MU_COMPLEX_IM / h)  # = MU_COMPLEX / h in Python
    largest_y = abs(y[0, 0]) / scale[0, 0]  # np.max(np.abs(y) / scale): NaN if any is
    for b in range(B):
        for j in range(n):
            largest_y = nan_maximum(largest_y, abs(y[b, j]) / scale[b, j])
    floor = 10 * EPS * largest_y
    dW_norm_old = rate = 0.0
    have_old = have_rate = False  # an old norm and a rate exist
    fev = 0
    for it in range(NEWTON_MAXITER):
        finite = True
        for i in range(3):
            for b in range(B):
                for j in range(n):
                    Y[b, j] = y[b, j] + Z[i, b, j]
            finite &= batch_rhs(link, kind, par, H, t + h * C[i], Y, coef, F[i])
        fev += 1
        if not finite:
            Z.fill(np.nan)
            return False, it + 1, fev
        largest = 0.0
        for b in range(B):
            for j in range(n):
                f_real[j] = (_TI_REAL[0] * F[0, b, j] + _TI_REAL[1] * F[1, b, j] + _TI_REAL[2] * F[2, b, j]) - (
                    mu_real * W[0, b, j]
                )
                re = _TI_COMPLEX_RE[0] * F[0, b, j] + _TI_COMPLEX_RE[1] * F[1, b, j] + _TI_COMPLEX_RE[2] * F[2, b, j]
                im = _TI_COMPLEX_IM[0] * F[0, b, j] + _TI_COMPLEX_IM[1] * F[1, b, j] + _TI_COMPLEX_IM[2] * F[2, b, j]
                f_complex[j] = complex(re, im) - mu_complex * complex(W[1, b, j], W[2, b, j])
            matvec(inv_real[b], f_real, dW_real)
            matvec(inv_complex[b], f_complex, dW_complex)
            for j in range(n):
                dW[0, j], dW[1, j], dW[2, j] = dW_real[j], dW_complex[j].real, dW_complex[j].imag
            s = 0.0
            for i in range(3):
                for j in range(n):
                    q = dW[i, j] / scale[b, j]
                    s += q * q
                    W[i, b, j] += dW[i, j]  # member b's dW depends on its own W only
            largest = max(largest, s)
        dW_norm = np.sqrt(largest / (3 * n))
        if have_old:
            rate = dW_norm / dW_norm_old
            have_rate = True
        for i in range(3):
            for b in range(B):
                for j in range(n):
                    Z[i, b, j] = T[i, 0] * W[0, b, j] + T[i, 1] * W[1, b, j] + T[i, 2] * W[2, b, j]
        if dW_norm <= floor or (have_rate and rate < 1 and rate / (1 - rate) * dW_norm < tol):
            return True, it + 1, fev
        if have_rate and rate >= 1:
            return False, it + 1, fev
        dW_norm_old, have_old = dW_norm, True
    return False, NEWTON_MAXITER, fev


@numba.njit(cache=True)
def _radau(link, kind, par, H, coef, t0, t1, y0, jac0, rtol, atol, newton_tol, max_steps, t_rec, y_rec):
    """Integrate system ``link`` (of ``kind``, constants ``par``, input ``coef`` (B, K, 2) in ``t / H``)
    from ``t0`` to ``t1`` for the batch of initial values ``y0`` (B, n).

    ``jac0`` (n, n) or empty (0, 0) for none.  ``t_rec`` (m,) and ``y_rec`` (m, B, n) with
    ``m > max_steps`` receive the start and every accepted step (``record_steps``); with ``m = 0``
    nothing is recorded.  Returns ``(y, f, counts, h_next, status, t, h_abs)``:
    ``counts = (n_steps, n_rejected, n_fev, n_jev)``; ``status`` 0 or an error code with the time
    and step size for its message.
    """
    B, n = y0.shape
    counts = np.zeros(4, np.int64)
    direction = 1.0 if t1 >= t0 else -1.0
    t = t0
    span = abs(t1 - t0)
    h_abs = span
    h_abs_old = error_norm_old = 0.0
    have_old = False
    n_steps = n_rej = n_jev = 0
    n_fev = 1
    y = y0.copy()
    f = np.empty((B, n))
    batch_rhs(link, kind, par, H, t, y, coef, f)
    record = t_rec.shape[0] > 0
    if record:
        _record(t_rec, y_rec, 0, t, y)
    if span == 0:
        counts[2] = n_fev
        return y, f, counts, h_abs, 0, t, h_abs
    J = np.empty((B, n, n))
    have_J = jac0.shape[0] > 0
    if have_J:
        for b in range(B):
            for i in range(n):
                for j in range(n):
                    J[b, i, j] = jac0[i, j]
    inv_real = np.empty((B, n, n))
    inv_complex = np.empty((B, n, n), np.complex128)
    M_real = np.empty((n, n))
    M_complex = np.empty((n, n), np.complex128)
    Z = np.empty((3, B, n))
    y_new = np.empty((B, n))
    scale = np.empty((B, n))
    ZE = np.empty((B, n))
    rhs = np.empty(n)
    error = np.empty((B, n))
    error_f = np.empty((B, n))
    y_error = np.empty((B, n))
    error_norm = safety = t_new = 0.0
    while direction * (t1 - t) > 0:
        if not have_J:
            _fd_jacobian(link, kind, par, H, coef, t, y, f, J)
            have_J = True
            n_jev += 1
            n_fev += 1
        min_step = 10 * abs(np.nextafter(t, direction * np.inf) - t)
        rejected = False
        while True:
            if h_abs < min_step:
                return y, f, counts, h_abs, _STEP_TOO_SMALL, t, h_abs
            h = h_abs * direction
            t_new = t + h
            if direction * (t_new - t1) > 0 or abs(t1 - t_new) < min_step:
                t_new = t1
            h = t_new - t
            h_abs = abs(h)
            for b in range(B):
                for j in range(n):
                    scale[b, j] = atol + abs(y[b, j]) * rtol
            mu_real = MU_REAL / h
            mu_complex = complex(_MU_COMPLEX_RE / h, _MU_COMPLEX_IM / h)
            for b in range(B):
                for i in range(n):  # mu * I - J[b]
                    for j in range(n):
                        M_real[i, j] = (mu_real if i == j else 0.0) - J[b, i, j]
                        M_complex[i, j] = (mu_complex if i == j else 0j) - J[b, i, j]
                if not (all_finite(M_real.ravel()) and all_finite(M_complex.ravel())):
                    # e.g. MU / h = inf for h near underflow: an all-NaN inverse, so the Newton iterations fail
                    # and the step is halved to round-off level
                    inv_real[b].fill(np.nan)
                    inv_complex[b].fill(np.nan)
                    continue
                if not (inverse(M_real, inv_real[b]) and inverse(M_complex, inv_complex[b])):
                    return y, f, counts, h_abs, _SINGULAR, t, h_abs  # a zero pivot
            converged, n_iter, fev = _collocation(
                link, kind, par, H, coef, t, y, h, scale, newton_tol, inv_real, inv_complex, Z
            )
            n_fev += fev
            if not converged:
                if all_finite(Z.ravel()) and n_iter >= NEWTON_MAXITER:
                    _fd_jacobian(link, kind, par, H, coef, t, y, f, J)
                    n_jev += 1
                    n_fev += 1
                h_abs *= 0.5
                n_rej += 1
                rejected = True
                continue
            for b in range(B):
                for j in range(n):
                    y_new[b, j] = y[b, j] + Z[2, b, j]
                    ZE[b, j] = (E[0] * Z[0, b, j] + E[1] * Z[1, b, j] + E[2] * Z[2, b, j]) / h
                    rhs[j] = f[b, j] + ZE[b, j]
                matvec(inv_real[b], rhs, error[b])
                for j in range(n):
                    scale[b, j] = atol + nan_maximum(abs(y[b, j]), abs(y_new[b, j])) * rtol
            error_norm = _rms_max(error, scale)
            safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter)
            if rejected and error_norm > 1:
                for b in range(B):
                    for j in range(n):
                        y_error[b, j] = y[b, j] + error[b, j]
                batch_rhs(link, kind, par, H, t, y_error, coef, error_f)
                for b in range(B):
                    for j in range(n):
                        rhs[j] = error_f[b, j] + ZE[b, j]
                    matvec(inv_real[b], rhs, error[b])
                n_fev += 1
                error_norm = _rms_max(error, scale)
            if not np.isfinite(error_norm):
                return y, f, counts, h_abs, _ERROR_NOT_FINITE, t, h_abs
            if error_norm > 1:
                factor = _predict_factor(h_abs, h_abs_old, error_norm, error_norm_old, have_old)
                h_abs *= max(MIN_FACTOR, safety * factor)
                n_rej += 1
                rejected = True
                continue
            break
        factor = _predict_factor(h_abs, h_abs_old, error_norm, error_norm_old, have_old)
        factor = min(MAX_FACTOR, safety * factor)
        h_abs_old, error_norm_old, have_old = h_abs, error_norm, True
        t = t_new
        for b in range(B):
            for j in range(n):
                y[b, j] = y_new[b, j]
        finite = batch_rhs(link, kind, par, H, t, y, coef, f)
        n_fev += 1
        n_steps += 1
        if n_steps > max_steps:
            return y, f, counts, h_abs, _TOO_MANY_STEPS, t, h_abs
        if not finite:
            return y, f, counts, h_abs, _DERIVATIVE_NOT_FINITE, t, h_abs
        if record:
            _record(t_rec, y_rec, n_steps, t, y)
        h_abs = h_abs * factor
        have_J = False  # a fresh Jacobian per step: cheap for these small systems
    counts[0], counts[1], counts[2], counts[3] = n_steps, n_rej, n_fev, n_jev
    return y, f, counts, h_abs, 0, t, h_abs


@numba.njit(cache=True)
def _record(t_rec, y_rec, i, t, y):
    """Row ``i`` of the recorded steps: ``t`` and ``y`` (B, n)."""
    t_rec[i] = t
    for b in range(y.shape[0]):
        for j in range(y.shape[1]):
            y_rec[i, b, j] = y[b, j]


@numba.njit(cache=True)
def _jacobian(link, kind, par, H, coef, t, y):
    """``fun(t, y)`` once and its forward-difference Jacobian (B, n, n)."""
    f = np.empty(y.shape)
    batch_rhs(link, kind, par, H, t, y, coef, f)
    J = np.empty((y.shape[0], y.shape[1], y.shape[1]))
    _fd_jacobian(link, kind, par, H, coef, t, y, f, J)
    return J


# -- the Python side --------------------------------------------------------------
def warm_up() -> None:
    """Compile the kernels, or load them from numba's disk cache, now (about 10 s cold, 0.5 s warm).

    A timed run calls this first, so that its CPU seconds are those of its macro steps alone.
    """
    y, coef, par = np.zeros((1, 2)), np.zeros((1, 1, 2)), np.ones(4)
    with gc_paused():  # numba's compiler: no time in Python's collections
        _jacobian(1, FORCE, par, 1.0, coef, 0.0, y)
        _radau(1, FORCE, par, 1.0, coef, 0.0, 0.0, y, np.empty((0, 0)), 1e-6, 1e-6, 1e-8, 1, *NOT_RECORDED)


def compile_kernels() -> dict:
    """:func:`warm_up` and its record (:func:`~icosim.problems.pendulum.integrator.kernel_cache.compile_record`)."""
    return compile_record(warm_up, {"_jacobian": _jacobian, "_radau": _radau})

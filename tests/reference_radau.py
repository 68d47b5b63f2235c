"""The independent reference of the links' compiled integrator: Radau IIA in numpy, batched over initial values.

The package integrates the links with :mod:`icosim.problems.pendulum.integrator.compiled` (numba).  This
module is the same algorithm written with numpy arrays, and :class:`NumpyPendulum` is the
co-simulation problem with its links integrated by it on their numpy right-hand sides
(:mod:`reference_links`); tests compare the compiled integrator and whole
runs against them (tests/problems/pendulum/test_pendulum_compiled.py) and them against scipy
(tests/problems/pendulum/test_pendulum.py).

The method is scipy's ``Radau`` (Hairer & Wanner, *Solving ODEs II*, Sect. IV.8; scipy's
``integrate/_ivp/radau.py``; constants in :mod:`icosim.problems.pendulum.integrator.tableau`), written for a
**batch** of ``B`` systems of the same small size ``n`` that share one step sequence:

* the collocation equations are solved by simplified Newton iterations in the
  transformed variables (one real and one complex ``n x n`` system per batch
  member, inverted once per step attempt);
* the error estimate is scipy's (the embedded formula with the real
  eigenvalue), scaled by ``atol + rtol * max(|y|, |y_new|)``;
* the batch shares the step sequence: the error norm of a step is the largest
  RMS norm over the members, and the Newton iterations run in lockstep until
  the slowest member has converged.

Sharing the steps makes the end state a *smooth* function of each member's
initial value and input: finite differences between members (the
co-simulation's sensitivities) see the derivative of one fixed discrete map,
not the noise of different step sequences.  For the same reason the Newton
tolerance is tighter than scipy's default (``newton_tol``, relative to the
error scale): the stage equations are solved to near round-off.

Step sequence: the first trial step is ``first_step`` (default: the whole
interval, which for a co-simulation macro step is usually accepted at once),
then scipy's predictive (Gustafsson) controller with the same safety factor
and bounds ``[0.2, 10]``.  Rejected Newton iterations halve the step after a
fresh Jacobian.  The Jacobian is by forward differences unless ``jac`` is
given.
"""

from __future__ import annotations

import math

import numpy as np
from reference_links import numpy_links

from icosim.problems.pendulum.integrator.systems import IntegrationError, RadauResult
from icosim.problems.pendulum.integrator.tableau import (
    EPS,
    MAX_FACTOR,
    MIN_FACTOR,
    MU_COMPLEX,
    MU_REAL,
    NEWTON_MAXITER,
    TI,
    C,
    E,
    T,
)
from icosim.problems.pendulum.problem import PendulumCosimulation

__all__ = ["radau_batch", "fd_jacobian", "NumpyPendulum"]

TI_REAL = TI[0]
TI_COMPLEX = TI[1] + 1j * TI[2]


def _rms_max(x):
    """Largest RMS norm over the batch axis 0 (``x`` is ``(B, n)``)."""
    return float(np.sqrt(np.max(np.einsum("bn,bn->b", x, x)) / x.shape[-1]))


def fd_jacobian(fun, t, y, f):
    """``J[b] = d fun / d y`` at ``(t, y[b])`` by forward differences, shape ``(B, n, n)``."""
    n = y.shape[-1]
    h = np.sqrt(EPS) * np.maximum(1.0, np.abs(y))  # (B, n)
    Y = np.broadcast_to(y, (n,) + y.shape).copy()  # (n, B, n): row j perturbs component j
    idx = np.arange(n)
    Y[idx, :, idx] += h.T
    F = fun(t, Y)  # (n, B, n)
    return np.moveaxis((F - f) / h.T[:, :, None], 0, -1)  # (B, n_out, n_in)


def _predict_factor(h_abs, h_abs_old, error_norm, error_norm_old):
    """scipy's Radau step-size factor.  An error estimate of exactly 0 (a system at rest, e.g. in
    equilibrium) gives +inf, which the caller caps at MAX_FACTOR, as scipy's numpy float would; and
    leaves no history for the next step (a ratio to an old error of 0 would make the next factor 0)."""
    if error_norm == 0:
        return math.inf
    if error_norm_old is None or h_abs_old is None or error_norm_old == 0:
        multiplier = 1.0
    else:
        multiplier = h_abs / h_abs_old * (error_norm_old / error_norm) ** 0.25
    return min(1.0, multiplier) * error_norm**-0.25


def radau_batch(
    fun,
    t0: float,
    t1: float,
    y0,
    *,
    rtol: float = 1e-6,
    atol: float = 1e-6,
    jac=None,
    jac0=None,
    first_step: float | None = None,
    newton_tol: float = 1e-8,
    max_steps: int = 100000,
    record_steps: bool = False,
) -> RadauResult:
    """Integrate ``y' = fun(t, y)`` from ``t0`` to ``t1`` for a batch of initial values.

    Parameters
    ----------
    fun : callable ``fun(t, Y) -> dY``, vectorised: ``Y`` has shape
        ``(..., B, n)`` and ``t`` is a scalar or an array broadcasting against
        ``Y.shape[:-1]`` (the three stages are evaluated in one call with
        ``t`` of shape ``(3, 1)``).
    y0 : ``(B, n)`` initial values (a single ``(n,)`` vector is promoted).
    rtol, atol : tolerances of the local error estimate, as in scipy.
    jac : optional ``jac(t, Y) -> (B, n, n)``; forward differences otherwise.
    jac0 : optional Jacobian (broadcasting to ``(B, n, n)``) for the Newton
        matrix of the first step, e.g. reused from another integration from
        the same initial state; a fresh one is computed if Newton fails.
    first_step : first trial step (default: the whole interval).
    newton_tol : convergence tolerance of the simplified Newton iterations,
        relative to the error scale ``atol + rtol |y|``.
    record_steps : keep the solution at every accepted step
        (:attr:`RadauResult.t_steps`, :attr:`RadauResult.y_steps`).

    Raises
    ------
    IntegrationError
        If the step size falls below round-off level, values stop being finite
        or a Newton matrix is singular.
    """
    if not (np.isfinite(rtol) and np.isfinite(atol) and rtol > 0 and atol > 0):
        raise ValueError(f"rtol and atol must be finite and > 0, got rtol={rtol!r}, atol={atol!r}")
    y = np.array(y0, dtype=float)
    if y.ndim == 1:
        y = y[None, :]
    if y.ndim != 2:
        raise ValueError(f"y0 must have shape (B, n), got {np.shape(y0)}")
    B, n = y.shape
    direction = 1.0 if t1 >= t0 else -1.0
    t = float(t0)
    span = abs(t1 - t0)
    h_abs = span if first_step is None else min(abs(float(first_step)), span)
    h_abs_old = error_norm_old = None
    eye = np.eye(n)
    n_steps = n_rej = n_jev = 0
    n_fev = 1
    f = fun(t, y)
    steps = [(t, y)] if record_steps else None
    if span == 0:
        return RadauResult(y, f, 0, 0, n_fev, 0, h_abs, *_recorded(steps))
    jacobian = (
        (lambda tt, yy, ff: jac(tt, yy)) if jac is not None else (lambda tt, yy, ff: fd_jacobian(fun, tt, yy, ff))
    )
    J = None if jac0 is None else np.broadcast_to(jac0, (B, n, n))
    while direction * (t1 - t) > 0:
        if J is None:
            J = jacobian(t, y, f)
            n_jev += 1
            n_fev += jac is None
        min_step = 10 * abs(np.nextafter(t, direction * np.inf) - t)
        rejected = False
        while True:
            if h_abs < min_step:
                raise IntegrationError(f"step size {h_abs:.3g} below round-off level at t = {t:.17g}")
            h = h_abs * direction
            t_new = t + h
            if direction * (t_new - t1) > 0 or abs(t1 - t_new) < min_step:
                t_new = t1
            h = t_new - t
            h_abs = abs(h)
            scale = atol + np.abs(y) * rtol  # (B, n)
            try:
                inv_real = np.linalg.inv(MU_REAL / h * eye - J)
                inv_complex = np.linalg.inv(MU_COMPLEX / h * eye - J)
            except np.linalg.LinAlgError as exc:
                raise IntegrationError(f"singular Newton matrix at t = {t:.17g}: {exc}") from exc
            converged, n_iter, Z, fev = _collocation(fun, t, y, h, scale, newton_tol, inv_real, inv_complex)
            n_fev += fev
            if not converged:
                if np.all(np.isfinite(Z)) and n_iter >= NEWTON_MAXITER:
                    J = jacobian(t, y, f)
                    n_jev += 1
                    n_fev += jac is None
                h_abs *= 0.5
                n_rej += 1
                rejected = True
                continue
            y_new = y + Z[-1]
            ZE = np.einsum("i,ibn->bn", E, Z) / h
            error = np.einsum("bij,bj->bi", inv_real, f + ZE)
            scale = atol + np.maximum(np.abs(y), np.abs(y_new)) * rtol
            error_norm = _rms_max(error / scale)
            safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter)
            if rejected and error_norm > 1:
                error = np.einsum("bij,bj->bi", inv_real, fun(t, y + error) + ZE)
                n_fev += 1
                error_norm = _rms_max(error / scale)
            if not np.isfinite(error_norm):
                raise IntegrationError(f"non-finite error estimate at t = {t:.17g}")
            if error_norm > 1:
                factor = _predict_factor(h_abs, h_abs_old, error_norm, error_norm_old)
                h_abs *= max(MIN_FACTOR, safety * factor)
                n_rej += 1
                rejected = True
                continue
            break
        factor = _predict_factor(h_abs, h_abs_old, error_norm, error_norm_old)
        factor = min(MAX_FACTOR, safety * factor)
        h_abs_old, error_norm_old = h_abs, error_norm
        t, y = t_new, y_new
        f = fun(t, y)
        n_fev += 1
        n_steps += 1
        if n_steps > max_steps:
            raise IntegrationError(f"more than {max_steps} steps")
        if not np.all(np.isfinite(f)):
            raise IntegrationError(f"non-finite derivative at t = {t:.17g}")
        h_abs = h_abs * factor
        J = None  # a fresh Jacobian per step: cheap for these small systems
        if record_steps:
            steps.append((t, y))
    return RadauResult(y, f, n_steps, n_rej, n_fev, n_jev, h_abs, *_recorded(steps))


def _recorded(steps):
    if steps is None:
        return None, None
    return np.array([t for t, _ in steps]), np.array([y for _, y in steps])


def _collocation(fun, t, y, h, scale, tol, inv_real, inv_complex):
    """Simplified Newton iterations for the stage increments ``Z`` (3, B, n), in lockstep."""
    W = np.zeros((3,) + y.shape)
    Z = W
    tc = (t + h * C)[:, None]  # (3, 1): broadcasts over the batch
    rate = None
    dW_norm_old = None
    floor = 10 * EPS * np.max(np.abs(y) / scale) if y.size else 0.0
    fev = 0
    for it in range(NEWTON_MAXITER):
        F = fun(tc, y + Z)  # (3, B, n)
        fev += 1
        if not np.all(np.isfinite(F)):
            return False, it + 1, np.full_like(Z, np.nan), fev
        f_real = np.einsum("i,ibn->bn", TI_REAL, F) - (MU_REAL / h) * W[0]
        f_complex = np.einsum("i,ibn->bn", TI_COMPLEX, F) - (MU_COMPLEX / h) * (W[1] + 1j * W[2])
        dW_real = np.einsum("bij,bj->bi", inv_real, f_real)
        dW_complex = np.einsum("bij,bj->bi", inv_complex, f_complex)
        dW = np.empty_like(W)
        dW[0], dW[1], dW[2] = dW_real, dW_complex.real, dW_complex.imag
        q = dW / scale
        dW_norm = float(np.sqrt(np.max(np.einsum("ibn,ibn->b", q, q)) / (3 * q.shape[-1])))
        if dW_norm_old is not None:
            rate = dW_norm / dW_norm_old
        W = W + dW
        Z = np.einsum("ij,jbn->ibn", T, W)
        if dW_norm <= floor or (rate is not None and rate < 1 and rate / (1 - rate) * dW_norm < tol):
            return True, it + 1, Z, fev
        if rate is not None and rate >= 1:
            return False, it + 1, Z, fev
        dW_norm_old = dW_norm
    return False, NEWTON_MAXITER, Z, fev


# -- the co-simulation problem on this integrator ---------------------------------------------------
class NumpyPendulum(PendulumCosimulation):
    """:class:`~icosim.problems.pendulum.problem.PendulumCosimulation` with every link integration done by
    :func:`radau_batch` on the link's numpy closure ``link.rhs(coef, H)`` and its outputs by
    ``link.outputs`` (:mod:`reference_links`): what the compiled kernels
    (:mod:`icosim.problems.pendulum.integrator.compiled_step`) compute, by another route.  The counters
    (``stats``, ``jacobian_stats``) count the same events."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.links = numpy_links(self.links)

    def _step_link(self, i, state, e, history, perturb):
        """The samples ``e``, ``history[0..k-1]`` of link ``i``'s input (with ``perturb``, two more members
        whose ``e`` is moved by the forward-difference steps), integrated in one batch."""
        if history.shape[0] < self.k:
            raise ValueError(f"need {self.k} past samples of the coupling variables, got {history.shape[0]}")
        sl = self.inputs[i]
        base = self.corrector_samples(history, e)
        if perturb:
            h = self.fd_step * np.maximum(1.0, np.abs(e))
            idx = np.arange(self.n_coupling)[sl]
            batch = np.broadcast_to(base, (1 + idx.size,) + base.shape).copy()
            batch[1 + np.arange(idx.size), 0, idx] += h[idx]
        else:
            batch = base[None]
        return self._integrate(i, state, batch[:, :, sl])

    def _integrate(self, i, state, samples):
        """Integrate link ``i`` over one macro step for a batch of input samples (B, k+1, n_u) at the
        corrector nodes ``1, 0, ..., -k+1``.  Returns end states (B, n) and outputs (B, 4, 2)."""
        link = self.links[i]
        coef = np.einsum("mj,bju->bmu", self.C_corr, samples)
        y0 = np.broadcast_to(self._split(state)[i], (samples.shape[0], link.n))
        fun = link.rhs(coef, self.H)
        # The Newton matrix of the first Radau step is shared by all integrations
        # of this link from this state (predictor, sensitivities, corrector).
        counts = self._counts
        if self._jac0[i] is not state:
            self._jac0[i] = state
            self._jac0_matrix[i][...] = fd_jacobian(fun, 0.0, y0[:1], fun(0.0, y0[:1]))[0]
            counts[5] += 1
            counts[6] += 2
        r = radau_batch(
            fun, 0.0, self.H, y0, jac0=self._jac0_matrix[i], rtol=self.rtol, atol=self.atol, newton_tol=self.newton_tol
        )
        self.work.subsystem_integrations += 1
        counts[0] += 1
        counts[1] += r.n_steps
        counts[2] += r.n_rejected
        counts[3] += r.n_fev
        counts[4] += r.n_steps > 1 or r.n_rejected > 0
        counts[5] += r.n_jev
        u1 = np.add.reduce(coef, axis=1)  # input at tau = 1
        return r.y, link.outputs(r.y, r.f, u1)

    def _end_outputs(self, i, end, e, perturb):
        """Outputs of link ``i`` at its end state ``end`` for the input ``e`` held at ``T_N+1`` (with
        ``perturb`` also for the two perturbed inputs)."""
        sl = self.inputs[i]
        u1 = np.array(e, dtype=float)[None, sl]
        if perturb:
            h = self.fd_step * np.maximum(1.0, np.abs(u1[0]))
            u1 = np.repeat(u1, 3, axis=0)
            u1[1, 0] += h[0]
            u1[2, 1] += h[1]
        link = self.links[i]
        Y = np.broadcast_to(end, (u1.shape[0], link.n))
        f = link.rhs(u1[:, None, :], self.H)(self.H, Y)  # constant polynomial: u(tau) = u1
        return link.outputs(Y, f, u1)

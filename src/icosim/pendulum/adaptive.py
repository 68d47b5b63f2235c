"""Adaptive macro-step control for constraint coupling (beyond the paper).

Co-simulation masters offer step-size control for explicit coupling (PyFMI's
master, libcosim); for the implicit, constraint-coupled schemes of the paper
none does.  This module adds it to the same macro step
(:func:`icosim.engine.macrostep.macro_step`, unchanged):

**Error estimate.**  The predictor extrapolates the coupling variables with a
polynomial of degree ``k`` (Eq. 9); the corrector computes them from the
coupling conditions.  Their difference ``e_c - e_p`` is the extrapolation
error: for exact samples of a smooth ``e(t)`` on equidistant nodes it is
``H^(k+1) e^(k+1)(T_N)`` to leading order (the Lagrange remainder at
``tau = 1`` with nodes ``0, -1, ..., -k``: ``prod (1 + j) / (k+1)! = 1``), so the
estimate scales like ``H^(k+1)`` (:func:`pc_estimate`, tested against that
constant).  Its norm is ``max_j |e_c,j - e_p,j| / (tol (1 + |e_c,j|))`` (the
coupling variables in SI units: N and m/s^2).

**Drift.**  The joint drift ``|g_c|`` of the accepted state must stay within
``drift_tol`` (m): a step is accepted only if ``max(estimate, |g_c|/drift_tol) <= 1``.
With projection the stored state is on the constraint and the drift
criterion is met by construction.

**Non-equidistant nodes.**  After step-size changes the Lagrange polynomials
run through the actual past macro nodes
(:meth:`icosim.pendulum.problem.PendulumCosimulation.set_macro_step`,
:func:`icosim.engine.lagrange.variable_predictor_nodes`); the starting history is
the monolithic solution at ``T_0, T_0 - H0, ...`` (taken again at the new spacing
when the very first step is rejected: far-away start-up nodes would only
inflate the extrapolation error and with it the estimate).

**Controller.**  A PI controller (:class:`StepController`; Gustafsson's
controller as given by Hairer & Wanner, *Solving ODEs I*, Sect. IV.2, Eq. 2.43c)
with step rejection: ``H_new = H * safety * err^(-beta1/p) * err_prev^(beta2/p)``
with ``p = k + 1``, limited to ``[fac_min, fac_max] H`` and to
``[H_min, H_max]``; no growth right after a rejection; a rejected step is
retried with ``H * max(fac_min, safety * err^(-1/p))``.  A step that exceeds
the divergence bounds or cannot be computed counts as rejected (err = inf);
at ``H_min`` the run stops (status ``diverged`` or ``failed``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..engine.macrostep import macro_step
from ..engine.methods import CouplingMethod
from ..engine.schemes import JACOBI, get_scheme
from ..errors import ParameterError, StepFailure
from .compiled import warm_up
from .model import PendulumParameters, joint_constraint
from .problem import PendulumCosimulation
from .reference import consistent_history
from .runs import _series_row, _SingularSolveAsFailure, divergence_reason, joint_force

__all__ = ["StepController", "AdaptiveResult", "pc_estimate", "run_adaptive"]


@dataclass(frozen=True)
class StepController:
    """PI step-size controller with rejection, for an error estimate that scales like ``H^order``.

    >>> c = StepController(order=2, H_max=1.0)
    >>> c.accepts(0.5), c.accepts(2.0), c.accepts(float("nan"))
    (True, False, False)
    >>> round(c.after_reject(0.1, 4.0), 15)  # 0.1 * 0.9 * 4^(-1/2)
    0.045
    >>> c.after_accept(0.1, 0.0, None)  # an error of zero: the largest growth
    0.2
    """

    order: int
    safety: float = 0.9
    fac_min: float = 0.2
    fac_max: float = 2.0
    beta1: float = 0.7
    beta2: float = 0.4
    H_min: float = 1e-6
    H_max: float = math.inf

    def __post_init__(self):
        if not (isinstance(self.order, int) and self.order >= 1):
            raise ParameterError(f"controller order must be an integer >= 1, got {self.order!r}")
        if not (0 < self.safety <= 1 and 0 < self.fac_min < 1 < self.fac_max):
            raise ParameterError("controller needs 0 < safety <= 1 and 0 < fac_min < 1 < fac_max")
        if not (self.beta1 > 0 and self.beta2 >= 0):
            raise ParameterError("controller needs beta1 > 0 and beta2 >= 0")
        if not (0 < self.H_min < self.H_max):
            raise ParameterError(f"controller needs 0 < H_min < H_max, got {self.H_min!r}, {self.H_max!r}")

    @staticmethod
    def accepts(err: float) -> bool:
        """A step is accepted when its error norm is at most 1 (never when it is not a number)."""
        return bool(err <= 1.0)

    def _clip(self, H):
        return min(max(H, self.H_min), self.H_max)

    def after_accept(self, H: float, err: float, err_prev: float | None, *, after_reject: bool = False) -> float:
        """Size of the next step after an accepted one with error ``err`` (the step before: ``err_prev``)."""
        p = self.order
        if err <= 0:
            fac = self.fac_max
        else:
            fac = self.safety * err ** (-self.beta1 / p)
            if err_prev is not None and self.beta2 > 0:
                fac *= max(err_prev, 1e-4) ** (self.beta2 / p)
        fac = min(max(fac, self.fac_min), self.fac_max)
        if after_reject:
            fac = min(fac, 1.0)
        return self._clip(H * fac)

    def after_reject(self, H: float, err: float) -> float:
        """Size of the retry after a rejected step with error ``err`` (inf or NaN: the largest cut)."""
        fac = self.safety * err ** (-1.0 / self.order) if math.isfinite(err) else self.fac_min
        return max(H * min(max(fac, self.fac_min), self.safety), self.H_min)


def pc_estimate(e_corrected, e_predicted, tol: float) -> float:
    """Norm of the predictor-corrector difference: ``max |e_c - e_p| / (tol (1 + |e_c|))``."""
    e_c = np.asarray(e_corrected, float)
    d = np.abs(e_c - np.asarray(e_predicted, float))
    return float(np.max(d / (tol * (1.0 + np.abs(e_c)))))


@dataclass
class AdaptiveResult:
    """An adaptive run: accepted macro nodes ``t``, series at them, the steps taken and the counts.

    ``H`` holds the accepted step sizes (``H[i] = t[i+1] - t[i]``), ``estimate``
    and ``drift`` the error norm parts of each accepted step; ``status`` is
    ``stable`` (reached the end time), ``diverged`` or ``failed`` (no
    acceptable step even at ``H_min``).
    """

    t: np.ndarray
    series: dict
    H: np.ndarray
    estimate: np.ndarray
    drift: np.ndarray
    status: str
    reason: str
    n_rejected: int
    stats: dict
    jacobian_stats: dict
    cpu_seconds: float
    rejected_H: list = field(default_factory=list)


def run_adaptive(
    params: PendulumParameters,
    method: CouplingMethod,
    decomposition: str,
    k: int,
    *,
    t_end: float,
    tol: float,
    drift_tol: float,
    H0: float,
    controller: dict | None = None,
    rtol: float = 1e-6,
    atol: float = 1e-6,
    fd_step: float = 1e-3,
    newton_tol: float = 1e-8,
    iterations: int = 1,
    corrector_tol: float | None = None,
    max_constraint: float = 1e-2,
    max_multiplier: float = 1e3,
    max_rate: float = 1e2,
    max_steps: int = 200000,
    scheme=JACOBI,
) -> AdaptiveResult:
    """Co-simulate from 0 to ``t_end`` with adaptive macro steps (module docstring).

    ``controller`` are :class:`StepController` settings (``order`` is ``k + 1``).
    The bounds are those of :func:`icosim.pendulum.runs.run_cosimulation`; a
    step beyond them is rejected, and only at ``H_min`` ends the run.
    ``scheme``: the coupling scheme (:mod:`icosim.engine.schemes`; link 1 is subsystem 1).
    """
    scheme = get_scheme(scheme)
    for name, v in (("t_end", t_end), ("tol", tol), ("drift_tol", drift_tol), ("H0", H0)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ParameterError(f"{name} must be a finite number > 0, got {v!r}")
    ctl = StepController(order=int(k) + 1, **(controller or {}))
    if not ctl.H_min <= H0 <= ctl.H_max:
        raise ParameterError(f"H0 = {H0!r} must lie in [H_min, H_max] = [{ctl.H_min!r}, {ctl.H_max!r}]")
    problem = PendulumCosimulation(
        params, decomposition, k, H0, rtol=rtol, atol=atol, fd_step=fd_step, newton_tol=newton_tol
    )
    method.check_decomposition(problem.decomposition)
    solver = _SingularSolveAsFailure(method)
    bounds = dict(max_constraint=max_constraint, max_multiplier=max_multiplier, max_rate=max_rate)
    dec = problem.decomposition.name
    state = params.initial_state()
    history = consistent_history(params, dec, k, H0)
    past = [float(H0)] * k
    lam0 = consistent_history(params, "ff", 0, H0)[0]
    g0 = joint_constraint(params, state)
    rows = [_series_row(params, state, g0, lam0)]
    times, steps, estimates, drifts, rejected_H = [0.0], [], [], [], []
    t, H, err_prev, after_reject = 0.0, float(H0), None, False
    status, reason = "stable", ""
    if problem.compiled:
        warm_up()  # not timed: numba's compilation or cache load
    c0 = time.process_time()
    with np.errstate(all="ignore"):
        while t_end - t > 1e-12 * t_end:
            if len(steps) >= max_steps:
                status, reason = "failed", f"more than {max_steps} macro steps"
                break
            remaining = t_end - t
            H = remaining if H >= remaining else (remaining / 2 if H > remaining / 2 else H)
            problem.set_macro_step(H, past)
            e_p = problem.extrapolate(history)
            failure = None
            try:
                state_new, hist_new, y = macro_step(
                    problem, solver, state, history, scheme=scheme, iterations=iterations, tol=corrector_tol
                )
                diverged = divergence_reason(problem, state_new, hist_new[0], y, **bounds)
            except (StepFailure, np.linalg.LinAlgError) as exc:
                failure, diverged = str(exc) or type(exc).__name__, None
            if failure or diverged:
                est = drift = err = math.inf
            else:
                est = pc_estimate(hist_new[0], e_p, tol)
                g = joint_constraint(params, state_new)
                drift = float(np.max(np.abs(g))) / drift_tol
                err = max(est, drift)
            if not ctl.accepts(err):
                rejected_H.append(H)
                if H <= ctl.H_min * (1 + 1e-9):
                    status = "failed" if failure else "diverged"
                    reason = failure or diverged or f"error norm {err:.3g} > 1 at H_min = {ctl.H_min:g} s"
                    break
                H = ctl.after_reject(H, err)
                after_reject = True
                if not steps:  # no accepted step yet: the start-up history is exact data at any spacing
                    history, past = consistent_history(params, dec, k, H), [H] * k
                continue
            state, history = state_new, hist_new
            t += H
            times.append(t)
            steps.append(H)
            estimates.append(est)
            drifts.append(drift * drift_tol)
            rows.append(_series_row(params, state, y[0, 0] - y[1, 0], joint_force(dec, history[0], y)))
            past = ([H] + past)[:k]
            H_next = ctl.after_accept(H, err, err_prev, after_reject=after_reject)
            err_prev, after_reject = err, False
            H = H_next
    cpu = time.process_time() - c0
    series = {name: np.array([r[name] for r in rows], dtype=float) for name in rows[0]}
    stats = dict(problem.stats, macro_steps=len(steps))
    return AdaptiveResult(
        np.array(times),
        series,
        np.array(steps),
        np.array(estimates),
        np.array(drifts),
        status,
        reason,
        len(rejected_H),
        stats,
        dict(problem.jacobian_stats),
        cpu,
        rejected_H,
    )

"""Adaptive macro steps: the loop that sizes each macro step with :class:`~.controller.StepController`.

Any co-simulation problem (:class:`icosim.engine.problem.CosimulationProblem`)
can be driven that way if it can change the size of its next macro step:

``set_macro_step(H, past_steps)``
    the size ``H`` of the next macro step and the sizes ``H_N-1, ..., H_N-k``
    of the past ones (``k`` of them, newest first).

**Non-equidistant nodes.**  After step-size changes the Lagrange polynomials
run through the actual past macro nodes (the pendulum's
:meth:`icosim.problems.pendulum.problem.PendulumCosimulation.set_macro_step` with
:func:`icosim.engine.lagrange.variable_predictor_nodes`).  The starting history
comes from ``restart(H)``, the history at ``T_0, T_0 - H, ...``; it is taken
again at the new spacing when the very first step is rejected: far-away
start-up nodes would only inflate the extrapolation error and with it the
estimate.

**Retry.**  The driver takes the problem's checkpoint
(:meth:`~icosim.engine.problem.CosimulationProblem.checkpoint`) before each
candidate step and restores it when the step is rejected, so the retry starts
from the state the rejected step started from, also for a problem that holds
state of its own (FMU units).

**Acceptance.**  A step's error norm is the larger of the estimate -- the
predictor-corrector difference (:func:`~.controller.pc_estimate`) unless the
caller passes another (``estimate``, e.g. ECCO's power residual,
:func:`~.controller.power_residual_estimate`) -- and the problem's own part
``extra_error(state)`` (e.g. the pendulum's joint drift over its tolerance); a step
is accepted when it is at most 1.  A step that the observer calls diverged (it
returns a reason) or that cannot be computed (a
:class:`~icosim.errors.StepFailure` or a singular linear solve) counts as
rejected (err = inf); at ``H_min`` the run stops (status ``diverged`` or
``failed``); the reason then says how the error norm fell over the retries
(:func:`_shrinkage`): one that does not shrink with H says the estimate cannot
decide at any step size (a start off the units, or coupling variables a unit
reports that jump with the step's size), not that the tolerance is tight.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...errors import StepFailure
from ..macrostep import CouplingRule, macro_step
from ..schemes import JACOBI, Scheme
from .controller import StepController, pc_estimate

__all__ = ["AdaptiveSteps", "adaptive_macro_steps"]


@dataclass
class AdaptiveSteps:
    """The accepted macro steps of an adaptive run and why it ended.

    ``t`` holds the accepted macro nodes from ``0`` (``H[i] = t[i+1] - t[i]``),
    ``estimate`` and ``extra`` the two parts of each accepted step's error
    norm; ``status`` is ``stable`` (reached the end time), ``diverged`` or
    ``failed`` (no acceptable step even at ``H_min``, or more than
    ``max_steps``); ``cpu_seconds`` are those of the loop (:func:`time.process_time`).
    """

    t: np.ndarray
    H: np.ndarray
    estimate: np.ndarray
    extra: np.ndarray
    status: str
    reason: str
    n_rejected: int
    cpu_seconds: float
    rejected_H: list = field(default_factory=list)


def _shrinkage(retries: list[tuple[float, float]]) -> str:
    """How the error norm fell over the last two of a step's rejected retries ``(H, err)``, for the reason a run
    ends at ``H_min``.

    >>> _shrinkage([(1e-4, 4.0), (1e-6, 3.9)])
    ' (4 at H = 0.0001 s: it falls as H^0.0055, so no step size meets the tolerance: the estimate does not shrink \
with H, a start off the units or coupling variables a unit reports that jump with the step size)'
    """
    finite = [(H, e) for H, e in retries if math.isfinite(e) and e > 0]
    if len(finite) < 2 or finite[-2][0] <= finite[-1][0]:
        return ""
    (H1, e1), (H2, e2) = finite[-2], finite[-1]
    order = math.log(e1 / e2) / math.log(H1 / H2)
    text = f" ({e1:.3g} at H = {H1:g} s: it falls as H^{order:.2g}"
    if order < 0.5:
        text += (
            ", so no step size meets the tolerance: the estimate does not shrink with H, a start off the units "
            "or coupling variables a unit reports that jump with the step size"
        )
    return text + ")"


def adaptive_macro_steps(
    problem: Any,  # a CosimulationProblem that has set_macro_step (module docstring)
    method: CouplingRule,
    state: np.ndarray,
    history: np.ndarray,
    *,
    t_end: float,
    H0: float,
    controller: StepController,
    tol: float,
    restart: Callable,
    method_at: Callable | None = None,
    observe: Callable | None = None,
    extra_error: Callable | None = None,
    estimate: Callable | None = None,
    on_accept: Callable | None = None,
    scheme: str | Scheme = JACOBI,
    iterations: int = 1,
    corrector_tol: float | None = None,
    max_steps: int = 200000,
) -> AdaptiveSteps:
    """Macro steps from ``0`` to ``t_end``, each sized by ``controller`` (module docstring).

    ``state`` and ``history`` are the start (``history`` at the spacing ``H0``);
    ``restart(H)`` gives the starting history at spacing ``H``; ``method_at(H)`` the method of a step of size
    ``H`` (default: ``method`` for every size; a method with dimensional parameters is rebuilt per size);
    ``observe(n, state, history, y)`` a reason why the candidate step ``n`` diverged, or None (the observer
    of :func:`icosim.engine.run.simulate`); ``extra_error(state)`` the problem's
    part of the error norm at an accepted candidate (default: none); ``estimate(H, history, e_p, y)`` the
    estimate's norm of a computed candidate (default: the predictor-corrector difference scaled by ``tol``);
    ``on_accept(state, history, y)`` is called after each accepted step (to store
    series).  ``tol`` scales the predictor-corrector estimate; ``iterations``,
    ``corrector_tol`` and ``scheme`` go to :func:`~icosim.engine.macrostep.macro_step`.
    """
    k = problem.k
    past = [float(H0)] * k
    times: list[float]
    steps: list[float]
    estimates: list[float]
    extras: list[float]
    rejected_H: list[float]
    times, steps, estimates, extras, rejected_H = [0.0], [], [], [], []
    t, H, err_prev, after_reject = 0.0, float(H0), None, False
    retries: list[tuple[float, float]] = []  # (H, error norm) of the rejected tries since the last accepted step
    status, reason = "stable", ""
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
            checkpoint = problem.checkpoint()  # restored when the step is rejected
            try:
                state_new, hist_new, y = macro_step(
                    problem,
                    method if method_at is None else method_at(H),
                    state,
                    history,
                    scheme=scheme,
                    iterations=iterations,
                    tol=corrector_tol,
                )
                diverged = observe(len(steps) + 1, state_new, hist_new, y) if observe is not None else None
            except (StepFailure, np.linalg.LinAlgError) as exc:
                failure, diverged = str(exc) or type(exc).__name__, None
            if failure or diverged:
                est = extra = err = math.inf
            else:
                est = pc_estimate(hist_new[0], e_p, tol) if estimate is None else estimate(H, hist_new, e_p, y)
                extra = extra_error(state_new) if extra_error is not None else 0.0
                err = max(est, extra)
            if not controller.accepts(err):
                problem.restore(checkpoint)
                rejected_H.append(H)
                retries.append((H, err))
                if H <= controller.H_min * (1 + 1e-9):
                    status = "failed" if failure else "diverged"
                    reason = (
                        failure
                        or diverged
                        or (f"error norm {err:.3g} > 1 at H_min = {controller.H_min:g} s" + _shrinkage(retries))
                    )
                    break
                H = controller.after_reject(H, err)
                after_reject = True
                if not steps:  # no accepted step yet: the start-up history is exact data at any spacing
                    history, past = restart(H), [H] * k
                continue
            state, history = state_new, hist_new
            retries.clear()
            t += H
            times.append(t)
            steps.append(H)
            estimates.append(est)
            extras.append(extra)
            if on_accept is not None:
                on_accept(state, history, y)
            past = ([H] + past)[:k]
            H_next = controller.after_accept(H, err, err_prev, after_reject=after_reject)
            err_prev, after_reject = err, False
            H = H_next
    cpu = time.process_time() - c0
    return AdaptiveSteps(
        np.array(times),
        np.array(steps),
        np.array(estimates),
        np.array(extras),
        status,
        reason,
        len(rejected_H),
        cpu,
        rejected_H,
    )

"""The one macro-step algorithm (Sect. 2): predictor, corrected coupling
variables, corrector, projection.  It serves every method, decomposition and
approximation order, the linear test model and the nonlinear pendulum alike.

A *problem* couples two subsystems and must provide:

``backend``
    the arithmetic (:mod:`icosim.backend`).
``extrapolate(history) -> e_p``
    the predicted coupling variables at ``T_N+1`` (Eq. 9/35/59).
``predict(state, history) -> y_p``
    subsystem outputs at ``T_N+1`` after integrating with the extrapolation
    polynomials (step 1).
``residuals(y) -> dict``
    the coupling conditions at ``T_N+1``: ``pos``, ``vel``, ``acc`` (the joint
    constraint on each level, shape ``(..., n_c)``) and ``force`` (balance of
    the multipliers of kinematically driven subsystems, ``(..., n_f)``).
``jacobians(state, history, e, y) -> dict``
    ``d residuals / d e_N+1`` for the same levels, shape ``(..., n, n_e)``
    (constant for the linear model, Eq. 13; numerical for the pendulum).
``correct(state, history, e_new) -> (state_new, y_new)``
    integration with the interpolation polynomials through ``e_new`` (step 3).
``project(state) -> state``
    the projection step (step 4), used by the projection method.
``shift(history, e_new) -> history``
    drop the oldest sample, prepend ``e_new``.

The *method* (:class:`icosim.coupling.CouplingMethod`) only decides how the
corrected coupling variables are formed from ``e_p``, residuals and Jacobians.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["macro_step", "simulate", "Trajectory"]


def macro_step(problem, method, state, history, *, iterations: int = 1, tol: float | None = None):
    """Advance one macro step ``T_N -> T_N+1``.

    Parameters
    ----------
    iterations : number of corrector steps.  The paper's scheme is one
        (semi-implicit; exact for the linear model because the sensitivities
        are constant).  More steps re-linearise about the latest coupling
        variables (fully implicit for nonlinear subsystems).
    tol : stop iterating once the largest absolute residual is below ``tol``.

    Returns
    -------
    state_new, history_new, y_new
    """
    e = problem.extrapolate(history)
    y = problem.predict(state, history)
    for it in range(max(1, iterations)):
        r = problem.residuals(y)
        if it > 0 and tol is not None and _max_abs(r) <= tol:
            break
        J = problem.jacobians(state, history, e, y)
        e = method.corrected_coupling(e, r, J, problem.backend)
        state_new, y = problem.correct(state, history, e)
    if method.projection:
        state_new = problem.project(state_new)
    return state_new, problem.shift(history, e), y


def _max_abs(residuals):
    vals = [np.max(np.abs(np.asarray(v, dtype=float))) for v in residuals.values() if np.size(v)]
    return max(vals) if vals else 0.0


@dataclass
class Trajectory:
    """States, coupling variables and outputs at ``T_0 ... T_n``.

    ``states[n]``, ``coupling[n]`` and ``outputs[n]`` belong to ``T_n``
    (``outputs[0]`` is None: no step has produced it).  ``diverged_at`` is the
    first step whose state was not finite or exceeded ``bound`` (None if none).
    """

    states: list
    coupling: list
    outputs: list
    diverged_at: int | None = None


def simulate(problem, method, state, history, n_steps: int, *, bound: float | None = None, **step_kw):
    """Run ``n_steps`` macro steps from ``state`` and the coupling history.

    Stops early (and records ``diverged_at``) when the state stops being
    finite or its magnitude exceeds ``bound``: an unstable run is reported,
    never silently continued.
    """
    states, coupling, outputs = [state], [history[..., 0, :]], [None]
    diverged = None
    for n in range(n_steps):
        state, history, y = macro_step(problem, method, state, history, **step_kw)
        mag = np.max(np.abs(np.asarray(state, dtype=float)))
        if not np.isfinite(mag) or (bound is not None and mag > bound):
            diverged = n + 1
            break
        states.append(state)
        coupling.append(history[..., 0, :])
        outputs.append(y)
    return Trajectory(states, coupling, outputs, diverged)

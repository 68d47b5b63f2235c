"""The run loop: macro steps one after another (:func:`icosim.engine.macrostep.macro_step`) until the end, a
divergence or a failure, with an observer after each step.

Every run of the package goes through :func:`simulate`: the linear model's, the pendulum's and the FMU scenes'.
The observer sees each step (progress, a problem's own divergence test) and may stop the run; the loop records
the states, coupling variables and outputs (or only the last, for long runs), and a step that fails or diverges
ends the run, recorded, never silently continued.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import StepFailure
from .macrostep import CouplingRule, macro_step
from .schemes import JACOBI

if TYPE_CHECKING:
    from .problem import CosimulationProblem

__all__ = ["simulate", "Trajectory"]


@dataclass
class Trajectory:
    """States, coupling variables and outputs at ``T_0 ... T_n``.

    ``states[n]``, ``coupling[n]`` and ``outputs[n]`` belong to ``T_n``
    (``outputs[0]`` is None: no step has produced it).  The run ends early
    when step ``n`` diverges (``diverged_at = n``) or fails (``failed_at = n``);
    ``reason`` says why and ``error`` holds what a failed step raised.  The
    lists then end at the last good step.  A run that keeps only its last step
    (``record=False``) has lists of length 2: the start and the last step.
    """

    states: list
    coupling: list
    outputs: list
    diverged_at: int | None = None
    failed_at: int | None = None
    reason: str | None = None
    error: BaseException | None = None  # what a failed step raised
    steps: int = 0  # macro steps taken and kept


def simulate(
    problem: CosimulationProblem,
    method: CouplingRule | None,
    state: np.ndarray,
    history: np.ndarray,
    n_steps: int,
    *,
    bound: float | None = None,
    observe: Callable[[int, np.ndarray, np.ndarray, np.ndarray], str | None] | None = None,
    record: bool = True,
    rollback: bool = False,
    **step_kw: Any,
) -> Trajectory:
    """Run ``n_steps`` macro steps from ``state`` and the coupling history.

    A step diverges when its state is not finite, its magnitude exceeds
    ``bound``, or the observer ``observe(n, state, history, y)`` -- called
    after every step ``n``, so it can also show progress -- returns a reason
    (a string); a step fails when it raises :class:`StepFailure` or a singular
    linear system (:class:`numpy.linalg.LinAlgError`).  Either stops the run
    and is recorded: an unstable run is reported, never silently continued.
    ``record=False`` keeps only the start and the last step.  ``rollback``: the
    problem's checkpoint (:meth:`~icosim.engine.problem.CosimulationProblem.checkpoint`)
    is taken before each step and restored when the step fails or diverges, so
    the problem stands where the trajectory ends (a stateful one can go on from
    there).  ``step_kw`` go to
    :func:`~icosim.engine.macrostep.macro_step` (``scheme``, ``iterations``, ``tol``).
    """
    # the problem's plan of the scheme; refuses what it cannot serve (a wrapper of a method reads as the method)
    step_kw["scheme"] = problem.plan(step_kw.get("scheme", JACOBI), method)  # type: ignore[arg-type]
    outputs: list[np.ndarray | None]  # outputs[0]: none yet
    states, coupling, outputs = [state], [history[..., 0, :]], [None]
    diverged = failed = reason = error = None
    done = 0
    for n in range(1, n_steps + 1):
        checkpoint = problem.checkpoint() if rollback else None
        try:
            state, history, y = macro_step(problem, method, state, history, **step_kw)
        except (StepFailure, np.linalg.LinAlgError) as exc:  # e.g. a singular coupling solve
            failed, reason, error = n, str(exc) or type(exc).__name__, exc
            if rollback:
                problem.restore(checkpoint)
            break
        mag = float(np.max(np.abs(np.asarray(state, dtype=float)), initial=0.0))  # not finite where an entry is not
        if not math.isfinite(mag):
            diverged, reason = n, "state not finite"
        elif bound is not None and mag > bound:
            diverged, reason = n, f"|state| > {bound:g}"
        elif observe is not None:
            reason = observe(n, state, history, y)
            diverged = n if reason else None
        if diverged:
            if rollback:
                problem.restore(checkpoint)
            break
        if not record and len(states) > 1:
            states.pop(), coupling.pop(), outputs.pop()
        states.append(state)
        coupling.append(history[..., 0, :])
        outputs.append(y)
        done = n
    return Trajectory(states, coupling, outputs, diverged, failed, reason, error, done)

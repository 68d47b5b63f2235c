"""The one macro-step algorithm (Sect. 2): predictor, corrected coupling variables, corrector, projection.
It serves every method, decomposition, approximation order, coupling scheme (Jacobi, Gauss-Seidel in any
order: :mod:`icosim.engine.schemes`) and number of subsystems and joints (:mod:`icosim.engine.graph`), the
linear models, the nonlinear pendulum and FMU units alike.

A *problem* (:class:`icosim.engine.problem.CosimulationProblem`, whose docstring states the contract)
supplies the subsystems, the coupling conditions and their sensitivities; the *method*
(:class:`icosim.engine.methods.CouplingMethod`) only decides how the corrected coupling variables are formed
from ``e_p``, residuals and Jacobians; the scheme's *stages* (:mod:`icosim.engine.stages`) say which
subsystems advance, which joints close and who responds how.  The step counts its coupling solves and
projections in the problem's :attr:`~icosim.engine.problem.CosimulationProblem.work`.

Signal connections (:class:`~icosim.engine.graph.Connection`, the condition ``u_in = T(y_out)``) are coupled
explicitly: after a stage's subsystems advanced (and, where the stage closes joints, were corrected), the
connections out of them take ``T`` of their outputs at ``T_N+1`` as their variables' new samples
(:meth:`~icosim.engine.problem.CosimulationProblem.connect`); a subsystem of a later stage with an input so fed
integrates with the interpolation polynomial through the new sample (Gauss-Seidel: ``predict`` with ``e_new``), the
others with the extrapolation polynomial (Jacobi: every input extrapolated; ``k = 0`` held).  Joints beside them are
closed by the method as on a graph without connections, the joint units' signal inputs following the same
polynomials in predictor and corrector.  ``method=None`` is explicit coupling: no corrector, so a graph with joints
needs a method.  A problem whose connections are implicit (``implicit_connections``) has them closed by the
corrector instead: their conditions ``e_c = T(y(e_c))`` at ``T_N+1``
(:class:`~icosim.engine.connection_conditions.SignalConditions`) by Newton's rule (:mod:`icosim.engine.methods.newton`),
the Jacobian from perturbed steps formed once per step; ``iterations`` bounds the Newton iterations, ``tol`` tests
them and a step that does not meet it fails (:class:`~icosim.engine.connection_conditions.NotConverged`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from ..errors import ParameterError
from .connection_conditions import NotConverged, SignalConditions
from .joint_signal_conditions import JointSignalConditions, WithSignals
from .methods.newton import NEWTON
from .residuals import Conditions
from .schemes import JACOBI, Scheme
from .stages import Plan, Stage

if TYPE_CHECKING:
    from .backends import Backend
    from .methods.solve import KeptFactors
    from .problem import CosimulationProblem

__all__ = ["macro_step"]


class CouplingRule(Protocol):
    """What :func:`macro_step` reads of its ``method`` (for type checkers): a
    :class:`~icosim.engine.methods.base.CouplingMethod`, or an object that wraps one."""

    @property
    def projection(self) -> bool: ...

    @property
    def n_solves(self) -> int: ...

    def corrected_coupling(
        self,
        e_pred: np.ndarray,
        residuals: Mapping[str, np.ndarray],
        jacobians: Mapping[str, np.ndarray],
        backend: Backend,
        factors: KeptFactors | None = None,
    ) -> np.ndarray: ...


def macro_step(
    problem: CosimulationProblem,
    method: CouplingRule | None,
    state: np.ndarray,
    history: np.ndarray,
    *,
    scheme: str | Scheme | Plan = JACOBI,
    iterations: int = 1,
    tol: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Advance one macro step ``T_N -> T_N+1``.

    Parameters
    ----------
    method : the coupling method of the joints; None: explicit coupling (no corrector), for a graph of
        connections only.
    scheme : :class:`icosim.engine.schemes.Scheme` (or its name): the order of the subsystems, as stages
        (:mod:`icosim.engine.stages`), the problem's plan of it
        (:meth:`~icosim.engine.problem.CosimulationProblem.plan`); or a :class:`~icosim.engine.stages.Plan` on
        the problem's graph.  At each stage its subsystems are predicted with the extrapolation polynomials; the
        joints it closes get corrected coupling variables, from the stage's subsystems' full gradients and the
        finished subsystems' algebraic ones (their outputs re-evaluated with the corrected variables; a scheme
        whose earlier outputs stay as integrated skips that and they do not respond); the stage's subsystems in
        a closed joint are corrected with the interpolation polynomials through them.  A joint not yet closed
        drives its subsystems with its extrapolated variables: the interpolation polynomial through ``e_p`` at
        ``T_N+1`` and the past samples is the extrapolation polynomial.  Jacobi (default, the paper's) is one
        stage: every subsystem, every joint.
    iterations : number of corrector steps.  The paper's scheme is one
        (semi-implicit; exact for the linear model because the sensitivities
        are constant).  More steps re-linearise about the latest coupling
        variables (fully implicit for nonlinear subsystems).  Implicit connections: Newton's iterations at
        most (each one corrector step), the last one tested.
    tol : stop iterating once an iteration changes no coupling variable by
        more than ``tol`` (in the coupling variables' own units).  The change,
        not a residual, is the criterion: the weighted multiplier's corrected
        variables are a weighted mean of three solutions and satisfy none of the
        three conditions on its own; its iteration converges where the weighted
        correction vanishes.  Implicit connections: a variable's change at most
        ``tol (1 + |e_c|)``; not met within ``iterations``: the step fails.

    Returns
    -------
    state_new, history_new, y_new
    """
    graph = problem.graph
    p = scheme if isinstance(scheme, Plan) and scheme.graph is graph else None
    if p is None:  # the problem's own plan (its kept Jacobians are per stage)
        p = problem.plan(scheme.scheme if isinstance(scheme, Plan) else scheme)
    stages = p.stages
    if method is None and any(stage.joints for stage in stages):
        raise ParameterError("joints are coupled implicitly: a graph with joints needs a coupling method")
    e = problem.extrapolate(history)
    ends: list[Any] = [None] * graph.n_subsystems
    ys: list[Any] = [None] * graph.n_subsystems
    fresh: set[int] = set()  # the columns of e that connections set in this macro step
    seen: dict[int, frozenset] = {}  # per subsystem stepped: the columns fresh when it was
    for stage in stages:
        # step 1: the stage's subsystems with the extrapolation polynomials; those in no closed joint are final.
        # One fed by a connection out of an earlier stage: the interpolation polynomial through its new sample.
        for i in stage.units:
            final = i not in stage.corrected
            if fresh and any(col in fresh for _, col in graph.signal_inputs(i)):
                ends[i], ys[i] = problem.predict(i, state, history, final=final, e_new=e)
            else:
                ends[i], ys[i] = problem.predict(i, state, history, final=final)
            seen[i] = frozenset(fresh)
        if stage.conditions is not None:
            # closed by Newton: a subsystem whose input a later stage's connection has set since it stepped
            stale = [i for i in stage.corrected if i in seen and any(
                col in fresh and col not in seen[i] for _, col in graph.signal_inputs(i))] if stage.connections else []  # fmt: skip
            e = _close(problem, method, stage, p, state, history, e, ends, ys, iterations, tol, stale)
        if graph.connections:  # the connections out of the stage's subsystems, as they end it: their new samples
            e, fed = problem.connect(e, ys, stage.units, stage.connections)
            fresh.update(fed)
    y = problem.stack(ys)
    state_new = problem.join(ends)
    if method is not None and method.projection:  # step 4
        state_new = problem.project(state_new)
        problem.work.projections += 1
    return state_new, problem.shift(history, e), y


def _close(
    problem: CosimulationProblem, method: CouplingRule | None, stage: Stage, p: Plan, state: Any, history: Any,
    e: Any, ends: list[Any], ys: list[Any], iterations: int, tol: float | None, stale: Sequence[int] = (),
) -> Any:  # fmt: skip
    """Steps 2 and 3 of ``stage``: its closed joints' (or connections') corrected coupling variables and the
    corrector of its subsystems (``ends`` and ``ys`` updated in place); returns ``e`` with them.  ``stale``: the
    subsystems stepped with inputs other than ``e``'s, stepped again with ``e`` first (Newton's residual and
    Jacobian are formed at ``e``)."""
    graph = problem.graph
    algebraic = p.scheme.reevaluates_leading
    # connections (beside joints or alone): Newton's iteration, the Jacobian formed once
    sc = stage.conditions if isinstance(stage.conditions, (SignalConditions, JointSignalConditions)) else None
    jc = stage.conditions if isinstance(stage.conditions, Conditions) else None
    signals = sc is not None
    # connections alone: Newton's rule; beside joints: the joints' method, the connections' rows in every solve
    rule = method if sc is None else NEWTON if isinstance(sc, SignalConditions) else WithSignals(method)
    assert rule is not None
    cols = stage.column_index
    every = len(stage.columns) == graph.n_coupling  # the stage closes every joint: e itself, in its order
    e_held = e if every else e[..., cols]  # as the stage's predictors and the finished subsystems saw it
    J, converged = None, False
    for i in stale:
        ends[i], ys[i] = problem.correct(i, state, history, e)
    # connections: up to ``iterations`` Newton steps and the test of the last one (no unit steps)
    passes = iterations + 1 if signals else max(1, iterations)
    for it in range(passes):
        # step 2: corrected coupling variables of the closed joints (connections)
        e_s = e if every else e_held if it == 0 else e[..., cols]
        factors = None
        if sc is not None:
            r = sc.residuals(problem, ys, e_s)
            if J is None:  # formed once per macro step, at the predictor (perturbed steps of the units)
                J = sc.jacobians(problem, state, history, e, ys, problem.implicit_work)
        else:
            y_s = problem.stack([ys[i] for i in stage.responders])
            r = problem.residuals(y_s, e_s, jc, e_held)
            J = problem.jacobians(state, history, e, ys, ends, stage, algebraic=algebraic)
            factors = problem.kept_factors(stage, algebraic)
        e_new = rule.corrected_coupling(e_s, r, J, problem.backend, factors)
        problem.work.coupling_solves += rule.n_solves
        if it > 0 and tol is not None:
            converged = not sc.unconverged(e_new, e_s, tol) if sc is not None else _max_abs(e_new - e_s) <= tol
            if converged:
                break  # converged: the corrector already ran with (nearly) e_new
        if signals and it == iterations:  # connections: the last pass only tests
            break
        e_old, e = e, e_new if every else _with_columns(e, cols, e_new)
        # step 3: corrector of the stage's subsystems; the finished ones' outputs follow e algebraically
        for i in stage.corrected:
            ends[i], ys[i] = problem.correct(i, state, history, e)
        if algebraic:
            for i in stage.finished:
                ys[i] = problem.reevaluate(i, ends[i], ys[i], e_old, e)
    if sc is not None:
        problem.implicit_work.iterations.append(it)
        if tol is not None and not converged:
            raise _not_converged(problem, sc, e_new, e_s, tol, iterations)
    return e


def _with_columns(e: Any, cols: slice | np.ndarray, values: Any) -> Any:
    """``e`` with the entries ``cols`` of its last axis replaced by ``values`` (leading axes broadcast)."""
    lead = np.broadcast_shapes(e.shape[:-1], values.shape[:-1])
    out = np.array(np.broadcast_to(e, lead + e.shape[-1:]), copy=True)
    out[..., cols] = values
    return out


def _not_converged(
    problem: CosimulationProblem, conditions: SignalConditions | JointSignalConditions, e_new: Any, e_s: Any,
    tol: float, n: int,
) -> NotConverged:  # fmt: skip
    bad = conditions.unconverged(e_new, e_s, tol)
    change = np.abs(np.asarray(e_new, dtype=float) - np.asarray(e_s, dtype=float))
    text = conditions.describe(problem, bad, change)
    return NotConverged(
        f"implicit coupling: Newton's iteration did not converge in {n} iterations (change of a coupling "
        f"variable at most tol (1 + |e|), tol = {tol:g}): {text}; raise coupling.iterations or tol, or reduce H"
    )


def _max_abs(values: Any) -> float:
    return float(np.max(np.abs(np.asarray(values, dtype=float)))) if np.size(values) else 0.0

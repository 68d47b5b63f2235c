"""The one macro-step algorithm (Sect. 2): predictor, corrected coupling
variables, corrector, projection.  It serves every method, decomposition,
approximation order and coupling scheme (Jacobi, Gauss-Seidel:
:mod:`icosim.engine.schemes`), the linear test model and the nonlinear pendulum alike.

A *problem* (:class:`icosim.engine.problem.CosimulationProblem`, whose docstring
states the contract) supplies the subsystems, the coupling conditions and their
sensitivities; the *method* (:class:`icosim.engine.methods.CouplingMethod`) only
decides how the corrected coupling variables are formed from ``e_p``, residuals
and Jacobians.  The step counts its coupling solves and projections in the
problem's :attr:`~icosim.engine.problem.CosimulationProblem.work`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from .schemes import JACOBI, N_SUBSYSTEMS, Scheme, get_scheme

if TYPE_CHECKING:
    from .backends import Backend
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
    ) -> np.ndarray: ...


def macro_step(
    problem: CosimulationProblem,
    method: CouplingRule,
    state: np.ndarray,
    history: np.ndarray,
    *,
    scheme: str | Scheme = JACOBI,
    iterations: int = 1,
    tol: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Advance one macro step ``T_N -> T_N+1``.

    Parameters
    ----------
    scheme : :class:`icosim.engine.schemes.Scheme` (or its name): the order of the
        subsystems.  Jacobi (default, the paper's): every subsystem is predicted
        and corrected.  Gauss-Seidel: the leading subsystem advances once with
        the extrapolation polynomials, its end state is final, and it enters
        the corrected coupling variables with its algebraic gradients and its
        finished outputs; only the other subsystem is corrected.  A scheme whose
        leading outputs stay as integrated (``reevaluates_leading`` False) skips
        the re-evaluation, and the leading subsystem does not respond at all.
    iterations : number of corrector steps.  The paper's scheme is one
        (semi-implicit; exact for the linear model because the sensitivities
        are constant).  More steps re-linearise about the latest coupling
        variables (fully implicit for nonlinear subsystems).
    tol : stop iterating once an iteration changes no coupling variable by
        more than ``tol`` (in the coupling variables' own units).  The change,
        not a residual, is the criterion: the weighted multiplier's corrected
        variables are a weighted mean of three solutions and satisfy none of the
        three conditions on its own; its iteration converges where the weighted
        correction vanishes.

    Returns
    -------
    state_new, history_new, y_new
    """
    scheme = get_scheme(scheme)
    subsystems = range(N_SUBSYSTEMS)
    e = problem.extrapolate(history)
    # step 1: every subsystem with the extrapolation polynomials; a leading one is then final
    ends, ys = map(list, zip(*(problem.predict(i, state, history, final=i in scheme.leading) for i in subsystems)))
    fixed = scheme.fixed(ends)
    y = problem.stack(ys)
    for it in range(max(1, iterations)):
        # step 2: corrected coupling variables (leading subsystems: finished outputs, algebraic gradients)
        r = problem.residuals(y)
        J = problem.jacobians(state, history, e, y, fixed, algebraic=scheme.reevaluates_leading)
        e_new = method.corrected_coupling(e, r, J, problem.backend)
        problem.work.coupling_solves += method.n_solves
        if it > 0 and tol is not None and _max_abs(e_new - e) <= tol:
            break  # converged: the corrector already ran with (nearly) e_new
        e_old, e = e, e_new
        # step 3: corrector of the corrected subsystems; the leading ones' outputs follow e algebraically
        for i in subsystems:
            if i in scheme.leading:
                if scheme.reevaluates_leading:
                    ys[i] = problem.reevaluate(i, ends[i], ys[i], e_old, e)
            else:
                ends[i], ys[i] = problem.correct(i, state, history, e)
        y = problem.stack(ys)
    state_new = problem.join(ends)
    if method.projection:  # step 4
        state_new = problem.project(state_new)
        problem.work.projections += 1
    return state_new, problem.shift(history, e), y


def _max_abs(values: Any) -> float:
    return float(np.max(np.abs(np.asarray(values, dtype=float)))) if np.size(values) else 0.0

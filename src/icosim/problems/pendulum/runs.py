"""A whole co-simulation run of the pendulum: to the end time, or to divergence or failure.

The run goes through :func:`icosim.engine.run.simulate`; it *diverges* at the
first macro step beyond a bound (or not finite) and *fails* at the first step
that cannot be computed (a :class:`~icosim.errors.StepFailure`: it says
nothing about stability).  The stored series end at the step before.

:func:`run_adaptive` runs the same problem with adaptive macro steps
(:func:`icosim.engine.control.driver.adaptive_macro_steps`): the same divergence
bounds, and beside the predictor-corrector estimate a **drift** criterion: the
joint drift ``|g_c|`` of the accepted state must stay within ``drift_tol`` (m),
so a step is accepted only if ``max(estimate, |g_c|/drift_tol) <= 1``.  With
projection the stored state is on the constraint and the drift criterion is met
by construction.  The starting history is the monolithic solution at
``T_0, T_0 - H0, ...``.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field

import numpy as np

from ...engine.control.controller import StepController
from ...engine.control.driver import adaptive_macro_steps
from ...engine.decompositions import get_decomposition
from ...engine.methods import CouplingMethod
from ...engine.run import simulate
from ...engine.schemes import JACOBI, get_scheme
from ...errors import ParameterError, StepFailure
from .integrator.compiled_step import warm_up
from .model import PendulumParameters, joint_constraint
from .problem import PendulumCosimulation
from .reference import consistent_history

__all__ = [
    "RunResult",
    "run_cosimulation",
    "AdaptiveResult",
    "run_adaptive",
    "CouplingSolveError",
    "divergence_reason",
    "joint_force",
]


# -- a whole run ------------------------------------------------------------------
@dataclass
class RunResult:
    """Time series of one co-simulation run up to the end time, divergence or failure.

    ``status`` is ``stable`` (reached the end time), ``diverged`` (a step
    exceeded a bound or was not finite, at ``t_diverged``) or ``failed`` (a
    step could not be computed, at ``t_failed``); ``reason`` says why.
    """

    t: np.ndarray
    series: dict  # name -> array over t (VARIABLES plus g_cax_corrector, g_cay_corrector)
    status: str
    t_diverged: float  # nan unless diverged
    t_failed: float  # nan unless failed
    reason: str
    stats: dict
    wall_time: float
    #: CPU seconds of the macro steps (time.process_time), like wall_time without the start-up
    cpu_seconds: float = math.nan
    #: Jacobian evaluations of the links (``jev``) and the right-hand side evaluations they took
    #: beyond ``stats["fev"]`` (``fev``): PendulumCosimulation.jacobian_stats
    jacobian_stats: dict = field(default_factory=dict)

    @property
    def diverged(self) -> bool:
        return self.status == "diverged"

    @property
    def failed(self) -> bool:
        return self.status == "failed"


class CouplingSolveError(StepFailure):
    """The linear system for the corrected coupling variables is singular."""


class _SingularSolveAsFailure:
    """A coupling method whose singular linear solve is a failed step (:class:`CouplingSolveError`)."""

    def __init__(self, method: CouplingMethod):
        self._method = method

    def __getattr__(self, name):
        return getattr(self._method, name)

    def corrected_coupling(self, *args, **kwargs):
        try:
            return self._method.corrected_coupling(*args, **kwargs)
        except np.linalg.LinAlgError as exc:
            raise CouplingSolveError(f"singular coupling system ({exc})") from exc


def joint_force(decomposition: str, e, y):
    """The joint force of link 1 on link 2 after a step: the coupling variable ``lambda_c`` where one drives a
    link (ff, fd), else link 2's multiplier ``mu_2`` (dd)."""
    j = _force_variable(decomposition)
    return e[2 * j : 2 * j + 2] if j is not None else y[1, 3]


@functools.lru_cache
def _force_variable(decomposition: str):
    """Index of the coupling variable ``lambda_c`` of a decomposition (None: no link is force driven)."""
    dec = get_decomposition(decomposition)
    return next((j for j in range(dec.n_coupling) if dec.variable_kind(j) == "force"), None)


def divergence_reason(
    problem, state, e, y, *, max_constraint: float, max_multiplier: float, max_rate: float
) -> str | None:
    """Why a step counts as diverged (its state ``state``, newest coupling variables ``e``, outputs
    ``y``), or None: not finite, ``|g_c|`` (after the step or after the corrector) beyond
    ``max_constraint``, ``|lambda_c|`` beyond ``max_multiplier``, ``|omega|`` beyond ``max_rate``."""
    s = state.tolist()
    g = problem.constraint(state).tolist()
    g_corr = (y[0, 0] - y[1, 0]).tolist()
    lam = joint_force(problem.decomposition.name, e, y).tolist()
    if not all(map(math.isfinite, s + e.tolist() + g + g_corr + lam)):
        return "not finite"
    if max(map(abs, g)) > max_constraint or max(map(abs, g_corr)) > max_constraint:
        return f"|g_c| > {max_constraint} m"
    if max(map(abs, lam)) > max_multiplier:
        return f"|lambda_c| > {max_multiplier} N"
    if max(abs(s[1]), abs(s[7])) > max_rate:
        return f"|omega| > {max_rate} rad/s"
    return None


def _series_row(p: PendulumParameters, state, g_corrector, lam) -> dict:
    """One time point of the stored series."""
    g = joint_constraint(p, state)
    return dict(
        phi1=state[0],
        phi2=state[4],
        g_cax=g[0],
        g_cay=g[1],
        lambda_cax=lam[0],
        lambda_cay=lam[1],
        g_cax_corrector=g_corrector[0],
        g_cay_corrector=g_corrector[1],
    )


def run_cosimulation(
    params: PendulumParameters,
    method: CouplingMethod,
    decomposition: str,
    k: int,
    *,
    H: float,
    t_end: float,
    rtol: float = 1e-6,
    atol: float = 1e-6,
    fd_step: float = 1e-3,
    newton_tol: float = 1e-8,
    iterations: int = 1,
    tol: float | None = None,
    scheme=JACOBI,
    max_constraint: float = 1e-2,
    max_multiplier: float = 1e3,
    max_rate: float = 1e2,
) -> RunResult:
    """Co-simulate from ``t = 0`` to ``t_end`` with macro step ``H`` (:func:`icosim.engine.run.simulate`).

    The run *diverges* at the first macro step whose state, coupling variables
    or outputs are not finite, whose joint constraint (after the step or after
    the corrector) exceeds ``max_constraint`` (m), whose joint force exceeds
    ``max_multiplier`` (N) or whose angular rates exceed ``max_rate`` (rad/s);
    it *fails* at the first step that raises a
    :class:`~icosim.errors.StepFailure`.  The series end at the step before.
    ``scheme``: the coupling scheme (:mod:`icosim.engine.schemes`; link 1 is subsystem 1).
    """
    scheme = get_scheme(scheme)
    dec = get_decomposition(decomposition)
    method.check_decomposition(dec)
    if not (isinstance(iterations, int) and iterations >= 1):
        raise ParameterError(f"iterations must be an integer >= 1, got {iterations!r}")
    for name, v in (
        ("t_end", t_end),
        ("max_constraint", max_constraint),
        ("max_multiplier", max_multiplier),
        ("max_rate", max_rate),
    ):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ParameterError(f"{name} must be a finite number > 0, got {v!r}")
    if tol is not None and not (math.isfinite(tol) and tol > 0):
        raise ParameterError(f"tol must be a finite number > 0 or null, got {tol!r}")
    n_steps = int(round(t_end / H))
    if abs(n_steps * H - t_end) > 1e-9 * t_end:
        raise ParameterError(f"t_end = {t_end!r} must be a whole number of macro steps H = {H!r}")
    problem = PendulumCosimulation(params, dec.name, k, H, rtol=rtol, atol=atol, fd_step=fd_step, newton_tol=newton_tol)
    state = params.initial_state()
    history = consistent_history(params, dec.name, k, H)

    bounds = dict(max_constraint=max_constraint, max_multiplier=max_multiplier, max_rate=max_rate)

    def check(n, state, history, y):
        """Reason for divergence of step ``n``, or None."""
        return divergence_reason(problem, state, history[0], y, **bounds)

    warm_up()  # the first run of a process would otherwise time numba's compilation or cache load
    t0 = time.perf_counter()
    c0 = time.process_time()
    with np.errstate(all="ignore"):
        traj = simulate(
            problem,
            _SingularSolveAsFailure(method),
            state,
            history,
            n_steps,
            observe=check,
            iterations=iterations,
            tol=tol,
            scheme=scheme,
        )
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0
    g0 = problem.constraint(state)
    rows = [_series_row(params, state, g0, consistent_history(params, "ff", 0, H)[0])]
    for s, e, y in zip(traj.states[1:], traj.coupling[1:], traj.outputs[1:]):
        rows.append(_series_row(params, s, y[0, 0] - y[1, 0], joint_force(dec.name, e, y)))
    n_done = len(rows) - 1
    series = {name: np.array([row[name] for row in rows], dtype=float) for name in rows[0]}
    status = "failed" if traj.failed_at else "diverged" if traj.diverged_at else "stable"
    t_div = traj.diverged_at * H if traj.diverged_at else math.nan
    t_fail = traj.failed_at * H if traj.failed_at else math.nan
    stats = dict(problem.stats, macro_steps=n_done)
    return RunResult(
        H * np.arange(n_done + 1),
        series,
        status,
        t_div,
        t_fail,
        traj.reason or "",
        stats,
        wall,
        cpu_seconds=cpu,
        jacobian_stats=dict(problem.jacobian_stats),
    )


# -- a whole run with adaptive macro steps ----------------------------------------
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

    ``controller`` are :class:`~icosim.engine.control.controller.StepController` settings
    (``order`` is ``k + 1``).  The bounds are those of :func:`run_cosimulation`; a
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
    bounds = dict(max_constraint=max_constraint, max_multiplier=max_multiplier, max_rate=max_rate)
    dec = problem.decomposition.name
    state = params.initial_state()
    lam0 = consistent_history(params, "ff", 0, H0)[0]
    g0 = joint_constraint(params, state)
    rows = [_series_row(params, state, g0, lam0)]

    def check(n, state, history, y):
        return divergence_reason(problem, state, history[0], y, **bounds)

    def drift(state):
        return float(np.max(np.abs(joint_constraint(params, state)))) / drift_tol

    def store(state, history, y):
        rows.append(_series_row(params, state, y[0, 0] - y[1, 0], joint_force(dec, history[0], y)))

    warm_up()  # not timed: numba's compilation or cache load
    steps = adaptive_macro_steps(
        problem,
        _SingularSolveAsFailure(method),
        state,
        consistent_history(params, dec, k, H0),
        t_end=t_end,
        H0=H0,
        controller=ctl,
        tol=tol,
        restart=lambda H: consistent_history(params, dec, k, H),
        observe=check,
        extra_error=drift,
        on_accept=store,
        scheme=scheme,
        iterations=iterations,
        corrector_tol=corrector_tol,
        max_steps=max_steps,
    )
    series = {name: np.array([r[name] for r in rows], dtype=float) for name in rows[0]}
    stats = dict(problem.stats, macro_steps=len(steps.H))
    return AdaptiveResult(
        steps.t,
        series,
        steps.H,
        steps.estimate,
        np.array([d * drift_tol for d in steps.extra]),
        steps.status,
        steps.reason,
        steps.n_rejected,
        stats,
        dict(problem.jacobian_stats),
        steps.cpu_seconds,
        steps.rejected_H,
    )

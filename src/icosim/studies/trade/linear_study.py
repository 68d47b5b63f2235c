"""What the linear test model predicts for the pendulum: orders over H and the stability limit.

Two comparisons, two linear models:

* **Orders** (:func:`linear_errors`): the test model of the paper's linear
  convergence study (Sect. 3.7: ``m1 = 1, m2 = 2, c1 = c2 = 1000, d1 = d2 = 10``
  in SI units, both masses at ``x0`` at rest), co-simulated with the *same
  scheme* (method with its SI parameters, decomposition, k) at the pendulum's
  step sizes, its error ``max |x_i - x| / x0`` over the macro nodes against
  the exact solution (:class:`icosim.problems.linear.exact.MonolithicSolution`), stepped with
  the engine's own amplification matrix
  (:func:`icosim.problems.linear.spectral.amplification_matrix`).  A step size whose spectral
  radius exceeds 1 is unstable, as in the linear study.  The pendulum's own
  point in the test model cannot serve here: its ratios ``am21 = alr21 =
  ali21 = 1`` make the two subsystems identical, so with force/force coupling
  the exact coupling force vanishes and the linear co-simulation is exact.
* **Stability** (:func:`linear_rho`): the larger spectral radius of the test
  model at the pendulum's two points (:func:`~.linearised.pendulum_test_model`:
  ``lr1 = -d H/(2 m1)``, ``li1 = H omega`` for the two modal frequencies,
  the mapping of today's ``rho ~ 1.13`` check), with the precision policy of
  :mod:`icosim.studies.stability` and its verdict (:func:`linear_stability`): a step
  size is stable when the verdict at both points is ``stable`` (float64
  trusted or proven); ``marginal`` (the proven enclosure contains 1) and
  ``undecided`` (nothing could be computed, ``rho`` NaN) are not.
"""

from __future__ import annotations

import math

import numpy as np

from ...engine.methods import CouplingMethod, engine_method
from ...problems.linear import exact
from ...problems.linear.model import PhysicalModel
from ...problems.linear.problem import LinearCosimulation
from ...problems.linear.spectral import amplification_matrix, spectral_radius
from ...problems.pendulum.linearised import linear_test_model_stability
from ...problems.pendulum.model import PendulumParameters

__all__ = ["PAPER_LINEAR_MODEL", "linear_errors", "linear_rho", "linear_stability"]

#: The test model of the paper's convergence study (Sect. 3.7), SI units.
PAPER_LINEAR_MODEL = {"m1": 1.0, "m2": 2.0, "c1": 1000.0, "c2": 1000.0, "d1": 10.0, "d2": 10.0}


def _error(c, method, decomposition: str, k: int, n_steps: int, x0: float, scheme="jacobi") -> float:
    """``max |x_i - x_exact| / x0`` over ``n_steps`` macro steps from ``x = x0`` at rest."""
    problem = LinearCosimulation(c, decomposition, k)
    sol = exact.MonolithicSolution(c, x0, 0.0)
    state, history = exact.consistent_start(problem, sol)
    M = amplification_matrix(c, method, decomposition, k, scheme=scheme)
    w = problem.pack(state, history)
    xs = np.empty((n_steps + 1, 2))
    xs[0] = w[[0, 2]]
    with np.errstate(all="ignore"):
        for n in range(1, n_steps + 1):
            w = M @ w
            xs[n] = w[[0, 2]]
    x_exact = sol.state(np.arange(n_steps + 1, dtype=float))[:, 0]
    return float(np.max(np.abs(xs - x_exact[:, None]))) / abs(x0)


def linear_errors(
    model: dict,
    method: CouplingMethod,
    decomposition: str,
    k: int,
    H_values,
    t_end: float,
    x0: float = 0.1,
    *,
    scheme="jacobi",
):
    """Errors of the linear test model ``model`` (m1, m2, c1, c2, d1, d2) co-simulated with ``method``.

    Returns ``(error, unstable, rho)`` over ``H_values`` (module docstring);
    ``error`` is NaN where the step is unstable: the verdict of the precision
    policy (:func:`icosim.problems.linear.spectral.spectral_radius`) is not ``stable`` --
    ``unstable``, or ``marginal`` / ``undecided``, where no bound on the growth
    is known -- or the run is not finite.  ``rho`` is NaN where undecided.
    """
    H_values = np.asarray(H_values, float)
    err = np.full(H_values.shape, np.nan)
    rho = np.full(H_values.shape, np.nan)
    unstable = np.zeros(H_values.shape, bool)
    for i, H in enumerate(H_values):
        n = max(1, math.ceil(t_end / H - 1e-9))
        c = PhysicalModel(H=H, **model).coefficients()
        m = engine_method(method, H)
        res = spectral_radius(c, m, decomposition, int(k), scheme=scheme)
        rho[i] = float(np.max(res.rho))  # NaN where undecided
        unstable[i] = not bool(np.all(res.verdict == "stable"))
        if not unstable[i]:
            err[i] = _error(c, m, decomposition, int(k), n, x0, scheme)
    unstable |= ~np.isfinite(err)
    return np.where(unstable, np.nan, err), unstable, rho


def linear_stability(
    params: PendulumParameters, method: CouplingMethod, decomposition: str, k: int, H: float, *, scheme="jacobi"
) -> tuple[float, str]:
    """``(rho, verdict)`` of the test model at the pendulum's two points with ``scheme`` (precision policy
    included; :func:`~.linearised.linear_test_model_stability`)."""
    rho, verdict, _ = linear_test_model_stability(params, H, method, decomposition, int(k), scheme=scheme)
    return rho, verdict


def linear_rho(
    params: PendulumParameters, method: CouplingMethod, decomposition: str, k: int, H: float, *, scheme="jacobi"
) -> float:
    """Larger spectral radius of the test model at the pendulum's two points (NaN where undecided)."""
    return linear_stability(params, method, decomposition, k, H, scheme=scheme)[0]

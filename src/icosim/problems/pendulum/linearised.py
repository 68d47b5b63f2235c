"""The pendulum's point in the parameter plane of the linear test model (Sect. 3), and its spectral radius.

The paper explains the instability of the weighted multiplier at ``k = 2`` by
the stability plot of the linear test model near the origin; these functions
put the pendulum on that plot.
"""

from __future__ import annotations

import math

import numpy as np

from ...engine.methods import CouplingMethod, engine_method
from ..linear.model import TestModel
from ..linear.spectral import spectral_radius
from .model import PendulumParameters
from .reference import Monolithic

__all__ = ["pendulum_test_model", "linear_test_model_rho", "linear_test_model_stability", "combined_verdict"]

#: The verdicts of :mod:`icosim.engine.spectral.policy`, the one that decides first when points are combined.
_VERDICT_ORDER = ("unstable", "undecided", "marginal", "stable")


def pendulum_test_model(params: PendulumParameters, H: float):
    """The pendulum's point in the parameter plane of Sect. 3: a :class:`~icosim.TestModel` with two points.

    As in the paper's explanation of Fig. 8, ``lr1 = -d H / (2 m1)`` (the
    damping per unit mass of one link, in macro steps).  ``li1 = omega H`` for
    the two modal frequencies ``omega`` of the pendulum linearised about its
    hanging rest (imaginary parts of the eigenvalues of the monolithic model's
    Jacobian, central differences): the two points bracket the frequencies the
    swinging pendulum passes through.  Ratios: ``am21 = m2/m1``,
    ``alr21 = m1/m2`` (the same damping ``d`` on each link), ``ali21 = 1``.
    """
    mono = Monolithic(params)
    y0 = np.array([-math.pi / 2, -math.pi / 2, 0.0, 0.0])
    h = 1e-6
    jac = np.array([(mono.rhs(0, y0 + h * ej) - mono.rhs(0, y0 - h * ej)) / (2 * h) for ej in np.eye(4)]).T
    omegas = np.sort(np.unique(np.round(np.abs(np.linalg.eigvals(jac).imag), 12)))
    omegas = omegas[omegas > 0]
    lr1 = -params.d * H / (2 * params.m1)
    return TestModel(np.full(omegas.shape, lr1), omegas * H, params.m2 / params.m1, params.m1 / params.m2, 1.0)


def combined_verdict(verdicts) -> str:
    """One verdict for several points: ``unstable`` if any is, else ``undecided``, else ``marginal``, else ``stable``.

    >>> combined_verdict(["stable", "marginal"]), combined_verdict(["undecided", "unstable"])
    ('marginal', 'unstable')
    """
    verdicts = {str(v) for v in np.ravel(verdicts)}
    return next(v for v in _VERDICT_ORDER if v in verdicts)


def linear_test_model_stability(
    params: PendulumParameters, H: float, method: CouplingMethod, decomposition: str, k: int, *, scheme="jacobi"
):
    """Spectral radius and verdict of the linear test model (Sect. 3) at the pendulum's points
    (:func:`pendulum_test_model`), for the dimensionless form of ``method``.

    The method's parameters are in SI units here and are scaled as the registry
    says (:func:`icosim.engine.methods.engine_method`: Baumgarte's ``beta_bar = beta/H``,
    ``gamma_bar = gamma/H^2``; the weighted multiplier's ``a``, ``b`` are
    dimensionless already).  ``scheme``: the coupling scheme (link 1 is
    subsystem 1).  The verdict is the precision policy's
    (:func:`icosim.problems.linear.spectral.spectral_radius`) over both points
    (:func:`combined_verdict`); ``rho`` is the larger one, NaN if a point is
    undecided (nothing is known there) unless the other is unstable.  Returns
    ``(rho, verdict, model)``.
    """
    dimensionless = engine_method(method, H)
    model = pendulum_test_model(params, H)
    result = spectral_radius(model, dimensionless, decomposition, int(k), scheme=scheme)
    verdict = combined_verdict(result.verdict)
    rho = np.asarray(result.rho, float)
    rho = float(np.nanmax(rho)) if verdict == "unstable" or np.all(np.isfinite(rho)) else math.nan
    return rho, verdict, model


def linear_test_model_rho(
    params: PendulumParameters, H: float, method: CouplingMethod, decomposition: str, k: int, *, scheme="jacobi"
):
    """Largest spectral radius of the linear test model at the pendulum's points
    (:func:`linear_test_model_stability` without the verdict).  Returns ``(rho, model)``."""
    rho, _, model = linear_test_model_stability(params, H, method, decomposition, k, scheme=scheme)
    return rho, model

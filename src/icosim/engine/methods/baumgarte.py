"""Baumgarte stabilisation (Eqs. 7c, 14-16, 41-43): one solve with the levels ``(1, beta, gamma)``.

Index 1: ``beta = 2 mu, gamma = mu^2``; index 2: ``gamma = 0``; index 3:
``beta = gamma = 0``.  The engine's parameters are dimensionless
(``beta_bar = beta/H``, ``gamma_bar = gamma/H^2``); in the dimensional setting
of the convergence study and the pendulum ``mu`` and ``beta`` are in seconds,
``gamma`` in s^2 (:data:`SPEC`).

>>> m = baumgarte(index=1, mu=0.5)
>>> m.params
{'beta': 1.0, 'gamma': 0.25, 'mu': 0.5, 'index': 1}
>>> [str(level) for level in m.solves[0][1]]  # exact: "0.1" would be 1/10, not the nearest double
['1', '1', '1/4']
"""

from __future__ import annotations

import sys
from fractions import Fraction

from ...errors import ParameterError
from ..decompositions import NEEDS_CONSTRAINT_CONDITION
from .base import CouplingMethod, MethodSpec, Parameter, exact

_FLOAT_MAX = Fraction(sys.float_info.max)

__all__ = ["baumgarte", "SPEC"]


def baumgarte(
    beta: float | Fraction | None = None,
    gamma: float | Fraction | None = None,
    *,
    mu: float | Fraction | None = None,
    index: int | None = None,
) -> CouplingMethod:
    """Baumgarte stabilisation (Eq. 7c) with dimensionless ``beta``, ``gamma``.

    Give either ``beta`` and ``gamma``, or ``index`` (1, 2, 3) with ``mu`` for
    indices 1 and 2: index 1 ``beta = 2 mu, gamma = mu^2``; index 2
    ``beta = 2 mu, gamma = 0``; index 3 ``beta = gamma = 0``.
    """
    if index is not None:
        if beta is not None or gamma is not None:
            raise ParameterError("give either index (with mu) or beta and gamma, not both")
        if index not in (1, 2, 3):
            raise ParameterError(f"index must be 1, 2 or 3, got {index!r}")
        if index == 3:
            if mu is not None:
                raise ParameterError("mu is not used at index 3 (beta = gamma = 0); drop mu")
            beta, gamma = Fraction(0), Fraction(0)
        else:
            if mu is None:
                raise ParameterError(f"Baumgarte index {index} needs mu")
            mu = exact("mu", mu)
            if mu <= 0:
                raise ParameterError(f"mu must be > 0, got {float(mu)!r}")
            beta, gamma = 2 * mu, (mu * mu if index == 1 else Fraction(0))
            for name, value in (("beta = 2 mu", beta), ("gamma = mu^2", gamma)):
                if value > _FLOAT_MAX:  # a derived quantity every arithmetic of the engine must hold
                    raise ParameterError(f"mu = {float(mu):g} makes {name} too large for float64 (not finite)")
    else:
        if mu is not None:
            raise ParameterError("mu needs index (1 or 2) for the Baumgarte method")
        if beta is None or gamma is None:
            raise ParameterError("Baumgarte needs beta and gamma, or index (and mu)")
        beta, gamma = exact("beta", beta), exact("gamma", gamma)
        if beta < 0 or gamma < 0:
            raise ParameterError(f"beta and gamma must be >= 0, got beta={float(beta)!r}, gamma={float(gamma)!r}")
    # the rule works with the exact values (decimal input stays exact at any precision); params show floats
    params = {"beta": float(beta), "gamma": float(gamma)}
    if mu is not None:
        params["mu"] = float(mu)
    # the index follows from the parameters: gamma = 0 drops the position level, beta = 0 too the velocity level
    params["index"] = index if index is not None else (3 if beta == gamma == 0 else 2 if gamma == 0 else 1)
    return CouplingMethod(
        "baumgarte",
        ((1, (1, beta, gamma)),),
        params=params,
        requires_constraint=True,
        refusal=NEEDS_CONSTRAINT_CONDITION,
    )


SPEC = MethodSpec(
    name="baumgarte",
    label="Baumgarte",
    short_label="Baumgarte",
    build=baumgarte,
    parameters=(
        Parameter(
            "mu",
            "Baumgarte: beta = 2 mu, gamma = mu^2 (index 1) or 0 (index 2)",
            unit="s",
            scaling=1,
            symbol="μ̄",
            tex=r"$\bar\mu$",
            tex_dimensional=r"$\mu$",
            exclusive_minimum=True,
            shorthand=True,
        ),
        Parameter(
            "beta",
            "Baumgarte parameter beta_bar",
            unit="s",
            scaling=1,
            symbol="β̄",
            tex=r"$\bar\beta$",
            tex_dimensional=r"$\beta$",
        ),
        Parameter(
            "gamma",
            "Baumgarte parameter gamma_bar",
            unit="s2",
            scaling=2,
            symbol="γ̄",
            tex=r"$\bar\gamma$",
            tex_dimensional=r"$\gamma$",
        ),
    ),
    indices=(1, 2, 3),
    unused_at_index={3: ("mu", "beta", "gamma")},
    requires_constraint=True,
    label_parameters=("mu",),
)

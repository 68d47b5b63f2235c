"""Lagrange extrapolation and interpolation of the coupling variables (Sect. 2.1.1).

Over the macro step ``[T_N, T_N+1]`` the local time is ``tau = t_bar - T_N_bar``
in ``[0, 1]``.  A coupling variable is approximated by the Lagrange polynomial of
degree ``k`` through ``k + 1`` samples:

* predictor (extrapolation, Eq. 9): nodes ``tau = 0, -1, ..., -k``
  (the values at ``T_N, T_N-1, ..., T_N-k``);
* corrector (interpolation, Eq. 11): nodes ``tau = 1, 0, ..., -k+1``
  (the new value at ``T_N+1`` and the values at ``T_N, ..., T_N-k+1``).

Weights are exact rationals (:class:`fractions.Fraction`), so they convert
without loss to float64 or to any multiprecision type.

Variable macro steps (non-equidistant nodes)
--------------------------------------------
With macro steps of different sizes the nodes are no longer integers.  In the
local time ``tau = (t - T_N)/H_N`` of the step ``[T_N, T_N+1]`` of size
``H_N``, with the past step sizes ``H_N-1, H_N-2, ...``:

* predictor: ``tau_0 = 0`` and ``tau_j = -(H_N-1 + ... + H_N-j)/H_N``,
  ``j = 1..k`` (:func:`variable_predictor_nodes`);
* corrector: ``1, tau_0, ..., tau_k-1`` (:func:`variable_corrector_nodes`).

:func:`lagrange_weights` and :func:`lagrange_coefficients` take any nodes:
exact for :class:`~fractions.Fraction` nodes and ``tau``, float64 for floats.
Equal step sizes give back the equidistant nodes and weights above:

>>> from fractions import Fraction as F
>>> variable_predictor_nodes(F(1), [F(1), F(1)]) == tuple(F(n) for n in predictor_nodes(2))
True
>>> lagrange_weights(variable_corrector_nodes(F(1, 2), [F(1)]), 1)
(Fraction(1, 1), Fraction(0, 1))
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from fractions import Fraction
from functools import cache
from typing import Any

__all__ = [
    "predictor_nodes",
    "corrector_nodes",
    "monomial_coefficients",
    "weights_at",
    "variable_predictor_nodes",
    "variable_step_polynomials",
    "variable_corrector_nodes",
    "lagrange_coefficients",
    "lagrange_weights",
]


def _check_k(k: int) -> int:
    if isinstance(k, bool) or int(k) != k or k < 0:
        raise ValueError(f"k must be an integer >= 0, got {k!r}")
    return int(k)


def predictor_nodes(k: int) -> tuple[int, ...]:
    """Nodes of the extrapolation polynomial: ``0, -1, ..., -k``."""
    return tuple(-j for j in range(_check_k(k) + 1))


def corrector_nodes(k: int) -> tuple[int, ...]:
    """Nodes of the interpolation polynomial: ``1, 0, ..., -k+1``."""
    return tuple(1 - j for j in range(_check_k(k) + 1))


@cache
def monomial_coefficients(nodes: tuple[int, ...]) -> tuple[tuple[Fraction, ...], ...]:
    """Matrix ``C`` with ``p(tau) = sum_m tau^m sum_j C[m][j] u_j``.

    Row ``m`` holds the coefficient of ``tau^m`` of every Lagrange basis
    polynomial ``l_j`` (``l_j(nodes[i]) = delta_ij``).
    """
    n = len(nodes)
    cols = []
    for j, tj in enumerate(nodes):
        poly = [Fraction(1)]  # coefficients, lowest degree first
        denom = Fraction(1)
        for i, ti in enumerate(nodes):
            if i == j:
                continue
            # multiply by (tau - ti)
            poly = [Fraction(0)] + poly
            for m in range(len(poly) - 1):
                poly[m] -= ti * poly[m + 1]
            denom *= tj - ti
        cols.append([c / denom for c in poly] + [Fraction(0)] * (n - len(poly)))
    return tuple(tuple(cols[j][m] for j in range(n)) for m in range(n))


def weights_at(nodes: tuple[int, ...], tau: float | Fraction) -> tuple[Fraction, ...]:
    """Lagrange weights ``l_j(tau)``; with exact ``tau`` the result is exact."""
    return _weights_at(tuple(nodes), Fraction(tau))


@cache
def _weights_at(nodes: tuple[int, ...], tau: Fraction) -> tuple[Fraction, ...]:
    C = monomial_coefficients(nodes)
    return tuple(sum((C[m][j] * tau**m for m in range(len(nodes))), Fraction(0)) for j in range(len(nodes)))


# -- variable step sizes: arbitrary nodes -------------------------------------------------
def variable_predictor_nodes(H: Any, past_steps: Sequence[Any]) -> tuple[Any, ...]:
    """Extrapolation nodes ``0, -H_N-1/H_N, -(H_N-1 + H_N-2)/H_N, ...`` in ``tau = (t - T_N)/H_N``.

    ``H`` is the size ``H_N`` of the step to be taken, ``past_steps`` the sizes
    ``H_N-1, ..., H_N-k`` of the previous ``k`` steps (most recent first); the
    result has ``k + 1`` nodes.  Exact for :class:`~fractions.Fraction` input.
    """
    if not H > 0 or any(not h > 0 for h in past_steps):
        raise ValueError(f"step sizes must be > 0, got H = {H!r}, past steps {tuple(past_steps)!r}")
    nodes, acc = [H - H], H - H  # a zero of the input's type
    for h in past_steps:
        acc = acc + h
        nodes.append(-acc / H)
    return tuple(nodes)


def variable_corrector_nodes(H: Any, past_steps: Sequence[Any]) -> tuple[Any, ...]:
    """Interpolation nodes ``1, 0, -H_N-1/H_N, ...``: ``tau = 1`` and the first ``k`` extrapolation nodes.

    ``past_steps`` are the same ``k`` previous step sizes as for
    :func:`variable_predictor_nodes` (the oldest one is not needed here).
    """
    k = len(past_steps)
    return (H / H,) + variable_predictor_nodes(H, past_steps)[:k]


def variable_step_polynomials(H: float, past_steps: Sequence[float] | None, k: int) -> tuple:
    """The polynomials of a macro step of size ``H`` after the past sizes ``H_N-1, ..., H_N-k`` (newest first;
    None: ``k`` steps of ``H``), through :func:`variable_predictor_nodes` and :func:`variable_corrector_nodes`:
    ``(H, past, w_pred, C_pred, C_corr)`` -- the extrapolation weights at ``tau = 1`` and both matrices of
    :func:`lagrange_coefficients`, computed exactly from the float sizes and rounded once to floats.  A size that
    is not a finite number > 0 raises :class:`~icosim.errors.ParameterError`.

    >>> H, past, w, C_pred, C_corr = variable_step_polynomials(0.5, [1.0], 1)  # nodes 0, -2: e_p = 1.5 e_N - 0.5 e_N-1
    >>> w.tolist(), C_corr.tolist()
    ([1.5, -0.5], [[0.0, 1.0], [1.0, -1.0]])
    """
    import numpy as np

    from ..errors import ParameterError

    if not (isinstance(H, (int, float)) and math.isfinite(H) and H > 0):
        raise ParameterError(f"H must be a finite number > 0, got {H!r}")
    past = [float(H)] * k if past_steps is None else [float(h) for h in past_steps][:k]
    if len(past) != k or not all(math.isfinite(h) and h > 0 for h in past):
        raise ParameterError(f"need {k} past step sizes > 0, got {past_steps!r}")
    exact = [Fraction(h) for h in [float(H)] + past]  # binary floats are exact rationals
    pred = variable_predictor_nodes(exact[0], exact[1:])
    corr = variable_corrector_nodes(exact[0], exact[1:])
    w_pred = np.array([float(w) for w in lagrange_weights(pred, 1)], dtype=float)
    C_pred = np.array(lagrange_coefficients(pred), dtype=float)
    return float(H), past, w_pred, C_pred, np.array(lagrange_coefficients(corr), dtype=float)


def lagrange_coefficients(nodes: Iterable[Any]) -> tuple[tuple[Any, ...], ...]:
    """:func:`monomial_coefficients` for arbitrary nodes (not cached): ``C[m][j]`` is the
    coefficient of ``tau^m`` of the Lagrange basis polynomial ``l_j``.

    Exact for :class:`~fractions.Fraction` nodes, float64 for float nodes.
    """
    nodes = tuple(nodes)
    n = len(nodes)
    if len(set(nodes)) != n:
        raise ValueError(f"Lagrange nodes must be distinct, got {nodes!r}")
    one = nodes[0] - nodes[0] + 1
    cols = []
    for j, tj in enumerate(nodes):
        poly = [one]  # lowest degree first
        denom = one
        for i, ti in enumerate(nodes):
            if i == j:
                continue
            poly = [one - one] + poly  # multiply by (tau - ti)
            for m in range(len(poly) - 1):
                poly[m] = poly[m] - ti * poly[m + 1]
            denom = denom * (tj - ti)
        cols.append([c / denom for c in poly])
    return tuple(tuple(cols[j][m] for j in range(n)) for m in range(n))


def lagrange_weights(nodes: Iterable[Any], tau: Any) -> tuple[Any, ...]:
    """Lagrange weights ``l_j(tau)`` for arbitrary distinct nodes (barycentric-free product form).

    ``l_j(tau) = prod_{i != j} (tau - t_i)/(t_j - t_i)``; exact for
    :class:`~fractions.Fraction` nodes and ``tau`` (an ``int`` ``tau`` is taken
    as exact), float64 for floats.
    """
    nodes = tuple(nodes)
    if len(set(nodes)) != len(nodes):
        raise ValueError(f"Lagrange nodes must be distinct, got {nodes!r}")
    if isinstance(tau, int) and nodes and isinstance(nodes[0], Fraction):
        tau = Fraction(tau)
    out = []
    for j, tj in enumerate(nodes):
        w = tau - tau + 1
        for i, ti in enumerate(nodes):
            if i != j:
                w = w * (tau - ti) / (tj - ti)
        out.append(w)
    return tuple(out)

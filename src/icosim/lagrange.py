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
"""

from __future__ import annotations

from fractions import Fraction
from functools import cache

__all__ = ["predictor_nodes", "corrector_nodes", "monomial_coefficients", "weights_at"]


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


def weights_at(nodes: tuple[int, ...], tau) -> tuple[Fraction, ...]:
    """Lagrange weights ``l_j(tau)``; with exact ``tau`` the result is exact."""
    return _weights_at(tuple(nodes), Fraction(tau))


@cache
def _weights_at(nodes: tuple[int, ...], tau: Fraction) -> tuple[Fraction, ...]:
    C = monomial_coefficients(nodes)
    return tuple(sum(C[m][j] * tau**m for m in range(len(nodes))) for j in range(len(nodes)))

"""The links' right-hand sides compiled with numba (:mod:`icosim.problems.pendulum.integrator.compiled` integrates them).

The links' equations (docs/pendulum.md; force-driven or kinematically driven), in the same order as
their numpy reference in ``tests/reference_links.py``, for one batch member at a time; the input
polynomial in ``tau = t / H`` is evaluated by Horner's scheme.  A link is an integer id
(1 or 2), its kind :data:`FORCE` or :data:`KINEMATIC`, and its constants a
float array (:func:`link_parameters`): no Python closures in compiled code.

Id :data:`MONOLITHIC` (0) is the whole pendulum in minimal coordinates, the expressions of
:meth:`icosim.problems.pendulum.reference.Monolithic.rhs` (constants :func:`monolithic_parameters`, no
input): the monolithic baseline of the speed-accuracy study integrates it with the links' Radau IIA.
"""

from __future__ import annotations

import numba
import numpy as np

from ..links import Link1

__all__ = [
    "FORCE",
    "KINEMATIC",
    "MONOLITHIC",
    "link_parameters",
    "monolithic_parameters",
    "batch_rhs",
    "member_rhs",
    "member_outputs",
]

FORCE, KINEMATIC = 0, 1  # the link's kind (links.py: "force" or the kinematically driven one)
MONOLITHIC = 0  # the id of the whole pendulum (links are 1 and 2)


@numba.njit(cache=True)
def _input(coef_b, tau):
    """Input ``(u_x, u_y)`` at ``tau`` of one member's polynomial ``coef_b`` (K, 2), as ``links._poly``."""
    K = coef_b.shape[0]
    ux, uy = coef_b[K - 1, 0], coef_b[K - 1, 1]
    for m in range(K - 2, -1, -1):
        ux = ux * tau + coef_b[m, 0]
        uy = uy * tau + coef_b[m, 1]
    return ux, uy


@numba.njit(cache=True)
def member_rhs(link, kind, par, H, t, y, coef_b, out):
    """``out = y'`` of link 1 or 2 for one member (state ``y``, input polynomial ``coef_b``).

    ``par``: link 1 ``(-m1 g l1/2, d l1^2/4, l1, J_O1)``, link 2 ``(l2/2, d, m2, g, J2, J2 + m2 l2^2/4)``
    (:func:`link_parameters`); the expressions in the order of links.py.  The whole pendulum
    (``link`` :data:`MONOLITHIC`) ignores ``kind``, ``H``, ``t`` and ``coef_b``.
    """
    if link == MONOLITHIC:
        _monolithic_rhs(par, y, out)
        return
    ux, uy = _input(coef_b, t / H)
    if link == 1:
        phi, w = y[0], y[1]
        c, s = np.cos(phi), np.sin(phi)
        tangential = c * uy - s * ux  # n1 . u
        if kind == FORCE:
            torque_ext = par[0] * c - par[1] * w
            alpha = (torque_ext - par[2] * tangential) / par[3]
        else:
            alpha = tangential / par[2]
        out[0] = w
        out[1] = alpha
        return
    l2h, d, m2, g, J2, inertia = par[0], par[1], par[2], par[3], par[4], par[5]
    c, s = np.cos(y[2]), np.sin(y[2])
    out[0], out[1], out[2] = y[3], y[4], y[5]
    if kind == FORCE:
        out[3] = (ux - d * y[3]) / m2
        out[4] = (uy - d * y[4]) / m2 - g
        out[5] = -l2h * (c * uy - s * ux) / J2
        return
    Fx = -d * y[3]
    Fy = -m2 * g - d * y[4]
    # (J + m l^2/4) phi2'' = (l/2) e2 x F - (m l/2) e2 x a_tilde
    alpha = l2h * ((c * Fy - s * Fx) - m2 * (c * uy - s * ux)) / inertia
    ww = y[5] * y[5]
    # a_S = a_tilde + (l/2)(phi2'' n2 - omega2^2 e2)
    out[3] = ux + l2h * (-alpha * s - ww * c)
    out[4] = uy + l2h * (alpha * c - ww * s)
    out[5] = alpha


@numba.njit(cache=True)
def _monolithic_rhs(par, y, out):
    """``out = y'`` of the whole pendulum, state ``(phi1, phi2, w1, w2)``: ``Monolithic.rhs``'s Lagrange
    equations in its order (``par`` from :func:`monolithic_parameters`)."""
    l1, l2, m1, m2, g, d, J1, J2 = par[0], par[1], par[2], par[3], par[4], par[5], par[6], par[7]
    w1, w2 = y[2], y[3]
    e1x, e1y = np.cos(y[0]), np.sin(y[0])
    e2x, e2y = np.cos(y[1]), np.sin(y[1])
    n1x, n1y, n2x, n2y = -e1y, e1x, -e2y, e2x
    v1x, v1y = l1 / 2 * w1 * n1x, l1 / 2 * w1 * n1y
    v2x = l1 * w1 * n1x + l2 / 2 * w2 * n2x
    v2y = l1 * w1 * n1y + l2 / 2 * w2 * n2y
    c1x, c1y = -l1 / 2 * w1**2 * e1x, -l1 / 2 * w1**2 * e1y  # convective accelerations of S1, S2
    c2x = -l1 * w1**2 * e1x - l2 / 2 * w2**2 * e2x
    c2y = -l1 * w1**2 * e1y - l2 / 2 * w2**2 * e2y
    # columns of the Jacobians of S1, S2 w.r.t. (phi1, phi2) (S1's second is 0)
    a1x, a1y = l1 / 2 * n1x, l1 / 2 * n1y
    a2x, a2y = l1 * n1x, l1 * n1y
    b2x, b2y = l2 / 2 * n2x, l2 / 2 * n2y
    F1x, F1y = -d * v1x, -m1 * g - d * v1y
    F2x, F2y = -d * v2x, -m2 * g - d * v2y
    M11 = m1 * (a1x * a1x + a1y * a1y) + m2 * (a2x * a2x + a2y * a2y) + J1
    M12 = m2 * (a2x * b2x + a2y * b2y)
    M22 = m2 * (b2x * b2x + b2y * b2y) + J2
    G2x, G2y = F2x - m2 * c2x, F2y - m2 * c2y
    Q1 = (a1x * (F1x - m1 * c1x) + a1y * (F1y - m1 * c1y)) + (a2x * G2x + a2y * G2y)
    Q2 = b2x * G2x + b2y * G2y
    det = M11 * M22 - M12 * M12
    out[0], out[1] = w1, w2
    out[2] = (M22 * Q1 - M12 * Q2) / det
    out[3] = (M11 * Q2 - M12 * Q1) / det


@numba.njit(cache=True)
def batch_rhs(link, kind, par, H, t, Y, coef, out):
    """The batch: ``out[b] = y'(t, Y[b])`` with member ``b``'s input; False if a value is not finite."""
    finite = True
    for b in range(Y.shape[0]):
        member_rhs(link, kind, par, H, t, Y[b], coef[b], out[b])
        for v in out[b]:
            finite = finite and np.isfinite(v)
    return finite


@numba.njit(cache=True)
def member_outputs(link, kind, par, y, f, ux, uy, out):
    """``out`` (4, 2) = ``(P, P', P'', f)`` of the joint point for one member: ``Link1.outputs`` or
    ``Link2.outputs`` at state ``y`` with ``f = y'`` and the input ``(ux, uy)``, the expressions in
    the order of links.py (``par`` as for :func:`member_rhs`)."""
    if link == 1:
        l1 = par[2]
        phi, w, alpha = y[0], y[1], f[1]
        c, s = np.cos(phi), np.sin(phi)  # e = (c, s), its normal (-s, c)
        out[0, 0], out[0, 1] = l1 * c, l1 * s
        out[1, 0], out[1, 1] = (l1 * w) * -s, (l1 * w) * c
        out[2, 0] = (l1 * alpha) * -s - (l1 * (w * w)) * c
        out[2, 1] = (l1 * alpha) * c - (l1 * (w * w)) * s
        if kind == FORCE:
            out[3, 0], out[3, 1] = ux, uy
        else:  # tangential joint force that realises l1 phi1'' = n1 . a_tilde
            mu1 = ((par[0] * c - par[1] * w) - par[3] * alpha) / l1
            out[3, 0], out[3, 1] = mu1 * -s, mu1 * c
        return
    l2h, d, m2, g = par[0], par[1], par[2], par[3]
    phi, w, alpha = y[2], y[5], f[5]
    c, s = np.cos(phi), np.sin(phi)
    out[0, 0], out[0, 1] = y[0] - l2h * c, y[1] - l2h * s
    out[1, 0], out[1, 1] = y[3] - (l2h * w) * -s, y[4] - (l2h * w) * c
    out[2, 0] = f[3] - l2h * (alpha * -s - (w * w) * c)
    out[2, 1] = f[4] - l2h * (alpha * c - (w * w) * s)
    if kind == FORCE:
        out[3, 0], out[3, 1] = ux, uy
    else:  # m2 a_S - F_ext
        out[3, 0] = m2 * f[3] - -d * y[3]
        out[3, 1] = m2 * f[4] - (-m2 * g - d * y[4])


def link_parameters(link) -> np.ndarray:
    """The constants of a link's right-hand side, formed by the same expressions as in links.py."""
    p = link.p
    if isinstance(link, Link1):
        return np.array([-p.m1 * p.g * p.l1 / 2, p.d * p.l1**2 / 4, p.l1, p.JO1])
    l2h = p.l2 / 2
    return np.array([l2h, p.d, p.m2, p.g, p.J2, p.J2 + p.m2 * l2h**2])


def monolithic_parameters(p) -> np.ndarray:
    """The constants of the whole pendulum's right-hand side (:data:`MONOLITHIC`) for
    :class:`~icosim.problems.pendulum.model.PendulumParameters` ``p``."""
    return np.array([p.l1, p.l2, p.m1, p.m2, p.g, p.d, p.J1, p.J2], dtype=float)

"""The monolithic double pendulum in minimal coordinates, its solution, and consistent starting values.

The reference solution integrates the whole pendulum (Lagrange's equations in
``(phi1, phi2)``) at tight tolerance; the coupling history at ``T_0, T_-1,
..., T_-k`` is taken from it, backwards in time (docs/pendulum.md).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .model import PendulumParameters
from .names import coupling_variables

__all__ = ["Monolithic", "reference_solution", "consistent_history"]


# -- monolithic model -----------------------------------------------------------
class Monolithic:
    """The whole pendulum in minimal coordinates ``(phi1, phi2)``; state ``(phi1, phi2, w1, w2)``.

    ``S_1 = l_1/2 e_1``, ``S_2 = l_1 e_1 + l_2/2 e_2``; Lagrange's equations of the
    second kind with the applied forces (gravity, damping at the centres of mass).
    """

    def __init__(self, params: PendulumParameters):
        self.p = params

    def _kinematics(self, Y):
        p = self.p
        phi1, phi2, w1, w2 = (Y[..., i] for i in range(4))
        e1 = np.stack([np.cos(phi1), np.sin(phi1)], axis=-1)
        e2 = np.stack([np.cos(phi2), np.sin(phi2)], axis=-1)
        n1 = np.stack([-e1[..., 1], e1[..., 0]], axis=-1)
        n2 = np.stack([-e2[..., 1], e2[..., 0]], axis=-1)
        w1c, w2c = w1[..., None], w2[..., None]
        v1 = p.l1 / 2 * w1c * n1
        v2 = p.l1 * w1c * n1 + p.l2 / 2 * w2c * n2
        c1 = -p.l1 / 2 * w1c**2 * e1  # convective accelerations of S1, S2
        c2 = -p.l1 * w1c**2 * e1 - p.l2 / 2 * w2c**2 * e2
        # Jacobians of S1, S2 w.r.t. (phi1, phi2): columns
        J1 = (p.l1 / 2 * n1, 0 * n1)
        J2 = (p.l1 * n1, p.l2 / 2 * n2)
        return e1, n1, e2, n2, v1, v2, c1, c2, J1, J2

    def _solve(self, Y):
        p = self.p
        e1, n1, e2, n2, v1, v2, c1, c2, J1, J2 = self._kinematics(Y)
        F1 = np.stack([-p.d * v1[..., 0], -p.m1 * p.g - p.d * v1[..., 1]], axis=-1)
        F2 = np.stack([-p.d * v2[..., 0], -p.m2 * p.g - p.d * v2[..., 1]], axis=-1)
        dot = lambda a, b: np.sum(a * b, axis=-1)  # noqa: E731
        M11 = p.m1 * dot(J1[0], J1[0]) + p.m2 * dot(J2[0], J2[0]) + p.J1
        M12 = p.m2 * dot(J2[0], J2[1])
        M22 = p.m2 * dot(J2[1], J2[1]) + p.J2
        Q1 = dot(J1[0], F1 - p.m1 * c1) + dot(J2[0], F2 - p.m2 * c2)
        Q2 = dot(J2[1], F2 - p.m2 * c2)
        det = M11 * M22 - M12 * M12
        a1 = (M22 * Q1 - M12 * Q2) / det
        a2 = (M11 * Q2 - M12 * Q1) / det
        return a1, a2, (e1, n1, J2, c2, F2)

    def rhs(self, t, Y):
        a1, a2, _ = self._solve(Y)
        return np.stack(np.broadcast_arrays(Y[..., 2], Y[..., 3], a1, a2), axis=-1)

    def joint_quantities(self, Y):
        """``lambda_c`` (force of link 1 on link 2) and the joint acceleration ``P''``, each ``(..., 2)``."""
        p = self.p
        a1, a2, (e1, n1, J2, c2, F2) = self._solve(Y)
        aS2 = J2[0] * a1[..., None] + J2[1] * a2[..., None] + c2
        lam = p.m2 * aS2 - F2
        w1 = Y[..., 2]
        acc = p.l1 * a1[..., None] * n1 - p.l1 * (w1 * w1)[..., None] * e1
        return lam, acc

    def initial_state(self):
        return np.array([self.p.phi1_0, self.p.phi2_0, 0.0, 0.0])

    def cosim_state(self, Y):
        """The co-simulation state ``(phi1, w1, x2, y2, phi2, vx2, vy2, w2)`` of a monolithic state."""
        p = self.p
        phi1, phi2, w1, w2 = Y
        e1 = np.array([math.cos(phi1), math.sin(phi1)])
        n1 = np.array([-e1[1], e1[0]])
        e2 = np.array([math.cos(phi2), math.sin(phi2)])
        n2 = np.array([-e2[1], e2[0]])
        s2 = p.l1 * e1 + p.l2 / 2 * e2
        v2 = p.l1 * w1 * n1 + p.l2 / 2 * w2 * n2
        return np.array([phi1, w1, s2[0], s2[1], phi2, v2[0], v2[1], w2])


def reference_solution(
    params: PendulumParameters, t, *, method: str = "DOP853", rtol: float = 1e-12, atol: float = 1e-12
):
    """Monolithic solution at the times ``t`` (any sign order: integrates from 0 both ways).

    Returns a dict of arrays ``phi1, phi2, omega1, omega2, lambda_cax, lambda_cay,
    a_x, a_y`` (the last two: joint acceleration) over ``t``.  A process keeps the latest solutions:
    the studies ask for the same one for every configuration run on the same macro grid, and every
    run's starting history (:func:`consistent_history`) for the same few times.
    """
    t = np.array(t, dtype=float)
    solution = _solution(params, t.tobytes(), t.shape, method, float(rtol), float(atol))
    return {name: values.copy() for name, values in solution.items()}


@functools.lru_cache(maxsize=64)
def _solution(params: PendulumParameters, t_bytes: bytes, shape: tuple, method: str, rtol: float, atol: float):
    """:func:`reference_solution` at the times ``np.frombuffer(t_bytes).reshape(shape)``."""
    from scipy.integrate import solve_ivp

    mono = Monolithic(params)
    t = np.frombuffer(t_bytes, dtype=float).reshape(shape)
    Y = np.empty(t.shape + (4,))
    y0 = mono.initial_state()
    for sign in (1.0, -1.0):
        sel = np.flatnonzero(t * sign > 0)
        if not sel.size:
            continue
        sel = sel[np.argsort(t[sel] * sign)]  # in the direction of integration
        sol = solve_ivp(mono.rhs, (0.0, t[sel[-1]]), y0, method=method, rtol=rtol, atol=atol, t_eval=t[sel])
        if not sol.success:
            raise RuntimeError(f"reference integration failed: {sol.message}")
        Y[sel] = sol.y.T
    Y[t == 0] = y0
    lam, acc = mono.joint_quantities(Y)
    return {
        "phi1": Y[:, 0],
        "phi2": Y[:, 1],
        "omega1": Y[:, 2],
        "omega2": Y[:, 3],
        "lambda_cax": lam[:, 0],
        "lambda_cay": lam[:, 1],
        "a_x": acc[:, 0],
        "a_y": acc[:, 1],
    }


def consistent_history(params: PendulumParameters, decomposition: str, k: int, H: float, **ref_kw):
    """Exact coupling variables at ``T_0, T_-1, ..., T_-k`` from the monolithic solution.

    Backwards in time from the initial state, as for the linear model
    (:func:`icosim.problems.linear.exact.consistent_start`): ``lambda_c`` and/or the joint
    acceleration ``a_tilde``.
    """
    ref = reference_solution(params, -H * np.arange(k + 1), **ref_kw)
    cols = {
        "lambda_cax": ref["lambda_cax"],
        "lambda_cay": ref["lambda_cay"],
        "a_tilde_x": ref["a_x"],
        "a_tilde_y": ref["a_y"],
    }
    return np.stack([cols[name] for name in coupling_variables(decomposition)], axis=-1)
